/* raysort — what every stage shares, host and kernels alike: the scalar types and helpers, the ray
 * and hit records, the camera, and small vector maths.
 *
 * The other structs that cross between host and device live with their concept, each with its
 * byte layout beside it: the BVH layouts in bvh_layout.h, the lane types in lanes.h, the key
 * inputs in keys.h and keys_cut.h, the path state in shade.h. Every piece of arithmetic whose
 * result must be bit-identical on both sides is written once in these headers. The host compiles
 * them as C++ with -ffp-contract=off; kernels compile them as OpenCL C 1.2 with FP_CONTRACT OFF and
 * correctly rounded divide/sqrt, so the same source gives the same bits (docs/trace.md).
 *
 * No library transcendentals appear here: OpenCL's and libm's sin/acos/atan2 may differ by ulps.
 */
#ifndef RAYSORT_SHARED_H
#define RAYSORT_SHARED_H

#ifdef __OPENCL_VERSION__
#pragma OPENCL FP_CONTRACT OFF
#define RS_GLOBAL __global
/* static: OpenCL C has C99 inline semantics, where a plain `inline` function is only an inline
 * definition. A call the compiler does not inline (clang for NVPTX keeps the robust traversal out
 * of line) then refers to an external definition that no kernel file provides, which the PTX link
 * leaves undefined. `static inline` (OpenCL C 1.2) emits a local copy whenever one is needed. */
#define RS_INLINE static inline
/* The small lane and vector helpers (lanes.h, packet_lanes.h): plain RS_INLINE on the device. */
#define RS_LANE_INLINE RS_INLINE
/* Forced inline, for code PoCL's inliner otherwise leaves as a function of its own in a hot loop
 * (objdump of its kernel cache shows it): the key code (keys.h) and the robust slab test of the
 * binary classes. The host passes RS_NO_FORCED_INLINE for Oclgrind (host/runtime/runtime.cpp):
 * LLVM's always-inliner emits llvm.experimental.noalias.scope.decl even at -O0, which Oclgrind 21.10
 * cannot interpret. */
#ifdef RS_NO_FORCED_INLINE
#define RS_FORCE_INLINE static inline
#else
#define RS_FORCE_INLINE static inline __attribute__((always_inline))
#endif
/* Fully unrolls the short fixed loop that follows (per-axis loops in the traversal). */
#define RS_UNROLL _Pragma("unroll")
/* A prefetch hint, on a CPU device only: the host builds a CPU device's kernels with RS_PREFETCH_AHEAD
 * (host/runtime/runtime.cpp; cl/trace.cl, "Gather on a CPU"), and PoCL's clang makes the builtin a
 * prefetcht0. Oclgrind gets the define without the x86 or Arm builtin. A prefetch changes no result. */
#if defined(RS_PREFETCH_AHEAD) && (defined(__x86_64__) || defined(__aarch64__))
#define RS_PREFETCH(p) __builtin_prefetch(p)
#else
#define RS_PREFETCH(p) ((void)(p))
#endif
typedef uchar rs_u8;
typedef uint rs_u32;
typedef int rs_i32;
typedef ulong rs_u64;
RS_INLINE float rs_min(float a, float b) { return fmin(a, b); }
RS_INLINE float rs_max(float a, float b) { return fmax(a, b); }
RS_INLINE float rs_abs(float a) { return fabs(a); }
RS_INLINE float rs_sqrt(float a) { return sqrt(a); }
RS_INLINE float rs_floor(float a) { return floor(a); }
/* a·b + c rounded once (IEEE fused multiply-add; OpenCL's fma is correctly rounded on every device). */
RS_INLINE float rs_fma(float a, float b, float c) { return fma(a, b, c); }
RS_INLINE rs_i32 rs_float_as_int(float f) { return as_int(f); }
RS_INLINE float rs_int_as_float(rs_i32 i) { return as_float(i); }
#else
#include <bit>
#include <cmath>
#include <cstdint>
#define RS_GLOBAL
#define RS_INLINE inline
/* The host lane structs' operators and helpers (lanes.h, packet_lanes.h) are forced inline: GCC kept
 * rs4_max, operator*, operator- and rs4_abs out of line in the host twins and the SIMT model's
 * recording traversal, 6.6 % of a quick preset's samples in calls (issue 42, item 5). Same
 * arithmetic, so the same bits. */
#define RS_LANE_INLINE inline __attribute__((always_inline))
#define RS_FORCE_INLINE inline
#define RS_UNROLL _Pragma("GCC unroll 4")
#define RS_PREFETCH(p) ((void)(p)) /* the host twins need no prefetch */
typedef std::uint8_t rs_u8;
typedef std::uint32_t rs_u32;
typedef std::int32_t rs_i32;
typedef std::uint64_t rs_u64;
/* fmin/fmax exactly as x86-64 glibc's (minss/maxss when ordered, the non-NaN operand otherwise),
 * written inline: the library call made every host twin traversal step a function call (a third
 * of the host reference's time in perf). The same values as before for every input, NaN and
 * signed zeros included, so device/host equality is unchanged. */
RS_INLINE float rs_min(float a, float b) { return (a < b || b != b) ? a : b; }
RS_INLINE float rs_max(float a, float b) { return (a > b || b != b) ? a : b; }
RS_INLINE float rs_abs(float a) { return std::fabs(a); }
RS_INLINE float rs_sqrt(float a) { return std::sqrt(a); }
RS_INLINE float rs_floor(float a) { return std::floor(a); }
/* a·b + c rounded once: std::fma's float overload is fmaf (the FMA instruction where the CPU has
 * one), never the double form, whose second rounding to float could differ. */
RS_INLINE float rs_fma(float a, float b, float c) { return std::fma(a, b, c); }
RS_INLINE rs_i32 rs_float_as_int(float f) { return std::bit_cast<rs_i32>(f); }
RS_INLINE float rs_int_as_float(rs_i32 i) { return std::bit_cast<float>(i); }
#endif

/* "Infinite" ray length. A finite value on purpose: kernels must not rely on inf arithmetic,
 * which -cl-fast-relaxed-math (finite-math-only) leaves undefined (docs/design.md, "Device facts"). */
#define RS_T_FAR 3.0e38f
#define RS_NO_HIT 0xFFFFFFFFu
/* How many rays ahead a CPU trace fetches the ray it will read through a sorted order: the host's
 * -DRS_PREFETCH_AHEAD for the kernels on a CPU device (cl/trace.cl, "Gather on a CPU") and Embree's
 * arms on a sorted order. A work-item takes about 0.1-1 µs on a CPU core, a miss to DRAM about 0.1. */
#define RS_RAY_PREFETCH_DISTANCE 4
/* The stream class (cl/traverse_stream.h): rays per stream (one bit each in a 64-bit mask, as Embree's
 * AVX-512 streams hold) and rays per work-item, which deals them into streams of one direction octant
 * each (2,048: more of its streams are full than from 1,024, 1-3.5 % faster on every 1080p batch of
 * sibenik and breakfast_room; a 1080p batch is still about 1,000 work-items). */
#define RS_STREAM_RAYS 64
#ifndef RS_STREAM_CHUNK
#define RS_STREAM_CHUNK 2048
#endif
/* ---------------------------------------------------------------------------------------------
 * Ray and hit records. All fields are 4 bytes; no float3 (whose size differs between host and CL).
 * ------------------------------------------------------------------------------------------- */

/* A ray, 32 bytes: [o.x o.y o.z tmin | d.x d.y d.z tmax]. The hit interval is (tmin, tmax). */
typedef struct {
  float o[3];
  float tmin;
  float d[3];
  float tmax;
} RsRay;

/* A hit record, 16 bytes: distance t, original triangle id (RS_NO_HIT on a miss) and the
 * barycentrics (u, v) of the hit point: p = (1-u-v)·v0 + u·v1 + v·v2. */
typedef struct {
  float t;
  rs_u32 tri;
  float u;
  float v;
} RsHit;

/* A pinhole camera, 64 bytes. tan_half_fov_y is computed on the host once (no transcendentals
 * on the device). right/up are unit vectors; right is scaled by the aspect ratio at use. */
typedef struct {
  float pos[3];
  float tan_half_fov_y;
  float forward[3];
  float aspect;
  float right[3];
  rs_u32 width;
  float up[3];
  rs_u32 height;
} RsCamera;

/* ---------------------------------------------------------------------------------------------
 * Small vector maths (explicit, so host and device evaluate in the same order).
 * ------------------------------------------------------------------------------------------- */
typedef struct {
  float x, y, z;
} RsVec3;

RS_INLINE RsVec3 rs_vec3(float x, float y, float z) {
  RsVec3 r;
  r.x = x;
  r.y = y;
  r.z = z;
  return r;
}
RS_INLINE RsVec3 rs_load3(const float* p) { return rs_vec3(p[0], p[1], p[2]); }
RS_INLINE RsVec3 rs_load3g(RS_GLOBAL const float* p) { return rs_vec3(p[0], p[1], p[2]); }
RS_INLINE RsVec3 rs_add(RsVec3 a, RsVec3 b) { return rs_vec3(a.x + b.x, a.y + b.y, a.z + b.z); }
RS_INLINE RsVec3 rs_sub(RsVec3 a, RsVec3 b) { return rs_vec3(a.x - b.x, a.y - b.y, a.z - b.z); }
RS_INLINE RsVec3 rs_scale(RsVec3 a, float s) { return rs_vec3(a.x * s, a.y * s, a.z * s); }
RS_INLINE float rs_dot(RsVec3 a, RsVec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
RS_INLINE RsVec3 rs_cross(RsVec3 a, RsVec3 b) {
  return rs_vec3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
RS_INLINE RsVec3 rs_normalize(RsVec3 a) {
  float len = rs_sqrt(rs_dot(a, a));
  return len > 0.0f ? rs_scale(a, 1.0f / len) : a;
}

#endif /* RAYSORT_SHARED_H */
