/* raysort — the one header shared by the OpenCL kernels and the C++ host.
 *
 * Every struct that crosses between host and device is defined here, once, with its byte layout
 * next to it, and so is every piece of arithmetic whose result must be bit-identical on both sides
 * (vector maths, the counter-based RNG, sin/cos for ray generation). The host compiles this file as
 * C++ with -ffp-contract=off; kernels compile it as OpenCL C 1.2 with FP_CONTRACT OFF and
 * correctly rounded divide/sqrt, so the same source gives the same bits (DESIGN.md section 4).
 *
 * No library transcendentals appear here: OpenCL's and libm's sin/acos/atan2 may differ by ulps.
 */
#ifndef RAYSORT_SHARED_H
#define RAYSORT_SHARED_H

#ifdef __OPENCL_VERSION__
#pragma OPENCL FP_CONTRACT OFF
#define RS_GLOBAL __global
#define RS_INLINE inline
/* Fully unrolls the short fixed loop that follows (per-axis loops in the traversal). */
#define RS_UNROLL _Pragma("unroll")
typedef uint rs_u32;
typedef int rs_i32;
typedef ulong rs_u64;
RS_INLINE float rs_min(float a, float b) { return fmin(a, b); }
RS_INLINE float rs_max(float a, float b) { return fmax(a, b); }
RS_INLINE float rs_abs(float a) { return fabs(a); }
RS_INLINE float rs_sqrt(float a) { return sqrt(a); }
RS_INLINE float rs_floor(float a) { return floor(a); }
RS_INLINE rs_i32 rs_float_as_int(float f) { return as_int(f); }
RS_INLINE float rs_int_as_float(rs_i32 i) { return as_float(i); }
#else
#include <bit>
#include <cmath>
#include <cstdint>
#define RS_GLOBAL
#define RS_INLINE inline
#define RS_UNROLL _Pragma("GCC unroll 4")
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
RS_INLINE rs_i32 rs_float_as_int(float f) { return std::bit_cast<rs_i32>(f); }
RS_INLINE float rs_int_as_float(rs_i32 i) { return std::bit_cast<float>(i); }
#endif

/* "Infinite" ray length. A finite value on purpose: kernels must not rely on inf arithmetic,
 * which -cl-fast-relaxed-math (finite-math-only) leaves undefined (DESIGN.md section 6). */
#define RS_T_FAR 3.0e38f
#define RS_NO_HIT 0xFFFFFFFFu
/* Traversal stack entries per work-item (private memory). The BVH builder guarantees that the
 * tree depth stays below this bound (host/bvh/build_sah.cpp, kMaxDepth); nearest-child-first
 * traversal pushes at most one node per level, so the stack cannot overflow. */
#define RS_STACK_SIZE 64

/* ---------------------------------------------------------------------------------------------
 * Device structs. All fields are 4 bytes; no float3 (whose size differs between host and CL).
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

/* A node of the flat binary BVH, 32 bytes: [bmin.x bmin.y bmin.z first | bmax.x bmax.y bmax.z count].
 * count == 0: inner node; its children are nodes[first] (left) and nodes[first + 1] (right).
 * count  > 0: leaf holding triangles [first, first + count) of the leaf-ordered triangle array.
 * Node 0 is the root. Children are stored next to each other so one index names both. */
typedef struct {
  float bmin[3];
  rs_u32 first;
  float bmax[3];
  rs_u32 count;
} RsBvhNode;

/* A triangle in leaf order, 48 bytes: [v0 id | v1 pad | v2 pad], id = the triangle's index in the
 * scene's flattened triangle list (what hits report). */
typedef struct {
  float v0[3];
  rs_u32 id;
  float v1[3];
  rs_u32 pad0;
  float v2[3];
  rs_u32 pad1;
} RsTriangle;

/* ---------------------------------------------------------------------------------------------
 * Four-lane vectors for the 4-wide BVH (cl/traverse.h). OpenCL's float4/int4 on the device; on the
 * host a 16-byte struct with the same layout and per-lane IEEE operations, so the same source gives
 * the same bits. Comparisons give -1 (true) / 0 (false) per lane, as OpenCL's do. min/max are
 * selects (a < b ? a : b), not fmin/fmax: no NaN special case, one instruction on SSE.
 * ------------------------------------------------------------------------------------------- */
#ifdef __OPENCL_VERSION__
typedef float4 rs_f4;
typedef int4 rs_i4;
RS_INLINE rs_f4 rs4_splat(float x) { return (float4)(x); }
RS_INLINE rs_f4 rs4_min(rs_f4 a, rs_f4 b) { return select(b, a, a < b); }
RS_INLINE rs_f4 rs4_max(rs_f4 a, rs_f4 b) { return select(b, a, a > b); }
RS_INLINE rs_f4 rs4_select(rs_f4 if_false, rs_f4 if_true, rs_i4 m) { return select(if_false, if_true, m); }
/* The lanes of a -1/0 mask as bits, lane i -> bit i. The traversal branches on these bits at every
 * node, so on x86 devices (PoCL) it is one movmskps; the portable form (AND with 1, 2, 4, 8, then OR
 * the lanes) put a shuffle-and-OR chain on that path, and the trace took 4-13 % longer (sibenik,
 * docs/trace.md). GPUs and other CPUs use the portable form; ClRuntime.MaskBitsFormsAgree compares
 * the two on the device for every mask. */
RS_INLINE int rs4_bits_portable(rs_i4 m) { return (m.s0 & 1) | (m.s1 & 2) | (m.s2 & 4) | (m.s3 & 8); }
#if defined(__x86_64__) && defined(__SSE__) && !defined(RS_PORTABLE_MASK_BITS)
#define RS_MASK_BITS_MOVMSK 1
RS_INLINE int rs4_bits(rs_i4 m) { return __builtin_ia32_movmskps(as_float4(m)); }
#else
#define RS_MASK_BITS_MOVMSK 0
RS_INLINE int rs4_bits(rs_i4 m) { return rs4_bits_portable(m); }
#endif
RS_INLINE void rs4_store(rs_f4 a, float* p) { vstore4(a, 0, p); }
/* Index of the lowest set bit of x != 0 (OpenCL 1.2 has clz but no ctz). */
RS_INLINE int rs_lowest_bit(int x) { return 31 - clz(x & -x); }
RS_INLINE rs_f4 rs4_load(const float* p) { return vload4(0, p); }
#else
typedef struct alignas(16) rs_f4 {
  float s[4];
} rs_f4;
typedef struct alignas(16) rs_i4 {
  rs_i32 s[4];
} rs_i4;
/* Per-lane operators of the host lane structs (N lanes; comparisons give -1 / 0 like OpenCL's).
 * Defined once here and used for the 8-lane structs below too. */
#define RS_LANES_BINARY(T, R, N, op)                         \
  RS_INLINE R operator op(T a, T b) {                        \
    R r;                                                     \
    for (int i = 0; i < N; ++i) r.s[i] = a.s[i] op b.s[i];   \
    return r;                                                \
  }
#define RS_LANES_COMPARE(F, I, N, op)                                          \
  RS_INLINE I operator op(F a, F b) {                                          \
    I r;                                                                       \
    for (int i = 0; i < N; ++i) r.s[i] = a.s[i] op b.s[i] ? -1 : 0;            \
    return r;                                                                  \
  }
#define RS4_COMPARE(op)                  \
  RS_LANES_COMPARE(rs_f4, rs_i4, 4, op) \
  RS_INLINE rs_i4 operator op(rs_f4 a, float b) { return a op rs_f4{{b, b, b, b}}; }
RS_LANES_BINARY(rs_f4, rs_f4, 4, +)
RS_LANES_BINARY(rs_f4, rs_f4, 4, -)
RS_LANES_BINARY(rs_f4, rs_f4, 4, *)
RS_LANES_BINARY(rs_f4, rs_f4, 4, /)
RS_LANES_BINARY(rs_i4, rs_i4, 4, &)
RS_LANES_BINARY(rs_i4, rs_i4, 4, |)
RS4_COMPARE(<)
RS4_COMPARE(>)
RS4_COMPARE(<=)
RS4_COMPARE(>=)
RS4_COMPARE(==)
RS4_COMPARE(!=)
#undef RS4_COMPARE
RS_INLINE rs_f4 rs4_splat(float x) { return rs_f4{{x, x, x, x}}; }
RS_INLINE rs_f4 operator*(rs_f4 a, float b) { return a * rs4_splat(b); }
RS_INLINE rs_f4 operator*(float a, rs_f4 b) { return rs4_splat(a) * b; }
RS_INLINE rs_f4 operator-(rs_f4 a, float b) { return a - rs4_splat(b); }
RS_INLINE rs_f4 operator-(float a, rs_f4 b) { return rs4_splat(a) - b; }
RS_INLINE rs_f4 rs4_select(rs_f4 if_false, rs_f4 if_true, rs_i4 m) {
  rs_f4 r;
  for (int i = 0; i < 4; ++i) r.s[i] = m.s[i] < 0 ? if_true.s[i] : if_false.s[i];
  return r;
}
RS_INLINE rs_f4 rs4_min(rs_f4 a, rs_f4 b) { return rs4_select(b, a, a < b); }
RS_INLINE rs_f4 rs4_max(rs_f4 a, rs_f4 b) { return rs4_select(b, a, a > b); }
RS_INLINE int rs4_bits(rs_i4 m) { return (m.s[0] & 1) | (m.s[1] & 2) | (m.s[2] & 4) | (m.s[3] & 8); }
RS_INLINE int rs_lowest_bit(int x) { return std::countr_zero(static_cast<unsigned>(x)); }
RS_INLINE void rs4_store(rs_f4 a, float* p) {
  for (int i = 0; i < 4; ++i) p[i] = a.s[i];
}
RS_INLINE rs_f4 rs4_load(const float* p) { return rs_f4{{p[0], p[1], p[2], p[3]}}; }
#endif

/* |x| per lane, as max(x, 0 − x): the same bits on both sides (±0 gives +0). */
RS_INLINE rs_f4 rs4_abs(rs_f4 x) { return rs4_max(x, 0.0f - x); }

/* Sixteen-lane vectors in the same style (the encoders' cut-box tests, cl/keys.h): OpenCL's
 * float16/int16 on the device, a 64-byte struct with per-lane IEEE operations on the host. min/max
 * are selects, as rs4_min/rs4_max. Sixteen lanes because a CPU with AVX-512 runs them as one
 * instruction (PoCL turns float16 into zmm operations), which halves the instructions of a key
 * against eight-lane groups; elsewhere they are two eight-lane or sixteen scalar operations. */
#ifdef __OPENCL_VERSION__
typedef float16 rs_f16;
typedef int16 rs_i16;
RS_INLINE rs_f16 rs16_splat(float x) { return (float16)(x); }
RS_INLINE rs_f16 rs16_min(rs_f16 a, rs_f16 b) { return select(b, a, a < b); }
RS_INLINE rs_f16 rs16_max(rs_f16 a, rs_f16 b) { return select(b, a, a > b); }
/* Eight-lane forms for a half-full group (device only, cl/keys.h rs_cut_bits). */
RS_INLINE float8 rs8_min(float8 a, float8 b) { return select(b, a, a < b); }
RS_INLINE float8 rs8_max(float8 a, float8 b) { return select(b, a, a > b); }
/* The OR of the eight lanes. */
RS_INLINE int rs8_or_lanes(int8 m) {
  int4 h = m.lo | m.hi;
  int2 q = h.lo | h.hi;
  return q.s0 | q.s1;
}
/* The lanes of a sixteen- or eight-lane -1/0 mask as bits, lane i -> bit i (the cut-box tests,
 * cl/keys.h rs_cut_bits). On AVX-512 devices (PoCL on such CPUs) the compare's mask register is
 * the answer (kmovd, RS_MASK16_BITS = 1); elsewhere the lanes are ANDed with their bits and ORed,
 * a fold of the lanes per group (on PoCL 1.2-1.6x slower box-set keys).
 * ClRuntime.MaskBitsFormsAgree checks them on the device. */
#if defined(__AVX512F__) && defined(__AVX512DQ__) && !defined(RS_PORTABLE_MASK_BITS)
#define RS_MASK16_BITS 1
RS_INLINE uint rs16_mask_bits(int16 m) { return (uint)__builtin_ia32_cvtd2mask512(m); }
RS_INLINE uint rs8_mask_bits(int8 m) { return (uint)__builtin_ia32_movmskps256(as_float8(m)); }
#else
#define RS_MASK16_BITS 0
RS_INLINE uint rs8_mask_bits(int8 m) { return (uint)rs8_or_lanes(m & (int8)(1, 2, 4, 8, 16, 32, 64, 128)); }
RS_INLINE uint rs16_mask_bits(int16 m) { return rs8_mask_bits(m.lo) | (rs8_mask_bits(m.hi) << 8); }
#endif
#else
typedef struct alignas(64) rs_f16 {
  float s[16];
} rs_f16;
typedef struct alignas(64) rs_i16 {
  rs_i32 s[16];
} rs_i16;
RS_LANES_BINARY(rs_f16, rs_f16, 16, +)
RS_LANES_BINARY(rs_f16, rs_f16, 16, -)
RS_LANES_BINARY(rs_f16, rs_f16, 16, *)
RS_LANES_BINARY(rs_i16, rs_i16, 16, &)
RS_LANES_BINARY(rs_i16, rs_i16, 16, |)
RS_LANES_COMPARE(rs_f16, rs_i16, 16, <)
RS_LANES_COMPARE(rs_f16, rs_i16, 16, >)
RS_LANES_COMPARE(rs_f16, rs_i16, 16, <=)
#undef RS_LANES_BINARY
#undef RS_LANES_COMPARE
RS_INLINE rs_f16 rs16_splat(float x) {
  rs_f16 r;
  for (int i = 0; i < 16; ++i) r.s[i] = x;
  return r;
}
RS_INLINE rs_f16 rs16_min(rs_f16 a, rs_f16 b) {
  rs_f16 r;
  for (int i = 0; i < 16; ++i) r.s[i] = a.s[i] < b.s[i] ? a.s[i] : b.s[i];
  return r;
}
RS_INLINE rs_f16 rs16_max(rs_f16 a, rs_f16 b) {
  rs_f16 r;
  for (int i = 0; i < 16; ++i) r.s[i] = a.s[i] > b.s[i] ? a.s[i] : b.s[i];
  return r;
}
/* Lane i -> bit i (the device's rs16_mask_bits). */
RS_INLINE rs_u32 rs16_mask_bits(rs_i16 m) {
  rs_u32 b = 0;
  for (int i = 0; i < 16; ++i) b |= static_cast<rs_u32>(m.s[i] != 0) << i;
  return b;
}
#endif

/* A node of the 4-wide BVH the trace kernels traverse, 128 bytes (two cache lines): the boxes of
 * up to four children, one axis bound per vector ("SoA", so one vector operation tests four
 * boxes), then per child: valid (-1 / 0) and a reference:
 *   RS_WIDE_LEAF clear: index of an inner node;
 *   RS_WIDE_LEAF set:   a leaf, packets [first, first + count) with first = (ref & ~RS_WIDE_LEAF) >> 2
 *                       and count = (ref & 3) + 1.
 * Node 0 is the root. host/bvh/wide.cpp collapses the binary BVH into this layout. */
#define RS_WIDE_LEAF 0x80000000u
typedef struct {
  rs_f4 lo_x, hi_x, lo_y, hi_y, lo_z, hi_z;
  rs_i4 valid;
  rs_u32 child[4];
} RsWideNode;

/* Four triangles of a leaf, 192 bytes, one vertex coordinate per vector so one pass of the
 * intersection test serves four triangles. id[i] = the triangle's index in the scene's flat list
 * (RS_NO_HIT in an empty lane); valid = -1 for a real triangle; nondegenerate = -1 unless the
 * triangle has exactly zero area (its cross product is 0 in exact arithmetic), which the robust
 * test must reject and which is cheaper to decide once on the host. */
typedef struct {
  rs_f4 v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z;
  rs_i4 valid;
  rs_i4 nondegenerate;
  rs_u32 id[4];
} RsTriPacket;

/* Traversal stack entries for the 4-wide BVH. Every wide node spans two levels of the binary
 * tree (host/bvh/wide.cpp), so its depth is at most ceil(RS_STACK_SIZE / 2) = 32, and a node
 * pushes at most three children: 3 * 32 = 96 entries suffice. */
#define RS_WIDE_STACK_SIZE 96

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

/* ---------------------------------------------------------------------------------------------
 * Counter-based RNG: a value is a pure function of (pixel, sample, bounce, dimension), so the
 * same command gives the same rays on every device and in any order of evaluation.
 * The mixer is the 32-bit finaliser of MurmurHash3, chained over the four counters.
 * ------------------------------------------------------------------------------------------- */
RS_INLINE rs_u32 rs_mix32(rs_u32 h) {
  h ^= h >> 16;
  h *= 0x85ebca6bu;
  h ^= h >> 13;
  h *= 0xc2b2ae35u;
  h ^= h >> 16;
  return h;
}
RS_INLINE rs_u32 rs_hash4(rs_u32 seed, rs_u32 pixel, rs_u32 sample, rs_u32 bounce_dim) {
  rs_u32 h = rs_mix32(seed ^ 0x9e3779b9u);
  h = rs_mix32(h ^ pixel);
  h = rs_mix32(h ^ (sample * 0x27d4eb2fu));
  h = rs_mix32(h ^ (bounce_dim * 0x165667b1u));
  return h;
}
/* Uniform float in [0, 1) with 24 random bits: exact, no rounding. */
RS_INLINE float rs_uniform(rs_u32 bits) { return (float)(bits >> 8) * (1.0f / 16777216.0f); }
/* Dimension ids for rs_hash4's last counter: (bounce << 8) | dimension. */
#define RS_DIM(bounce, dim) ((((rs_u32)(bounce)) << 8) | (rs_u32)(dim))

/* sin and cos of 2π·u for u in [0, 1), from + − × only (odd/even Taylor polynomials on
 * [−π/4, π/4] after an exact octant reduction); absolute error below 4e-7. */
RS_INLINE void rs_sincos_2pi(float u, float* s, float* c) {
  float q = u * 4.0f;                 /* quadrant coordinate in [0, 4) */
  float qi = rs_floor(q + 0.5f);      /* nearest quadrant boundary 0..4 */
  float x = (q - qi) * 1.57079632679f; /* in [−π/4, π/4] */
  float x2 = x * x;
  float sx = x * (1.0f + x2 * (-1.0f / 6.0f + x2 * (1.0f / 120.0f + x2 * (-1.0f / 5040.0f))));
  float cx = 1.0f + x2 * (-0.5f + x2 * (1.0f / 24.0f + x2 * (-1.0f / 720.0f + x2 * (1.0f / 40320.0f))));
  rs_i32 k = ((rs_i32)qi) & 3;
  if (k == 0) { *s = sx; *c = cx; }
  else if (k == 1) { *s = cx; *c = -sx; }
  else if (k == 2) { *s = -sx; *c = -cx; }
  else { *s = -cx; *c = sx; }
}

/* ---------------------------------------------------------------------------------------------
 * Ray generation pieces shared by the host and the (later) generate kernels.
 * ------------------------------------------------------------------------------------------- */

/* The ray o + t·d for t in [0, tmax]. */
RS_INLINE RsRay rs_make_ray(RsVec3 o, RsVec3 d, float tmax) {
  RsRay r;
  r.o[0] = o.x;
  r.o[1] = o.y;
  r.o[2] = o.z;
  r.tmin = 0.0f;
  r.d[0] = d.x;
  r.d[1] = d.y;
  r.d[2] = d.z;
  r.tmax = tmax;
  return r;
}

/* Primary ray through pixel (x, y), jittered by (jx, jy) in [0,1)². */
RS_INLINE RsRay rs_camera_ray(RsCamera cam, rs_u32 x, rs_u32 y, float jx, float jy) {
  float sx = (2.0f * (((float)x + jx) / (float)cam.width) - 1.0f) * cam.tan_half_fov_y * cam.aspect;
  float sy = (1.0f - 2.0f * (((float)y + jy) / (float)cam.height)) * cam.tan_half_fov_y;
  RsVec3 d = rs_add(rs_load3(cam.forward), rs_add(rs_scale(rs_load3(cam.right), sx), rs_scale(rs_load3(cam.up), sy)));
  return rs_make_ray(rs_load3(cam.pos), rs_normalize(d), RS_T_FAR);
}

/* Orthonormal basis around unit n (Duff et al. 2017, "Building an Orthonormal Basis, Revisited"). */
RS_INLINE void rs_onb(RsVec3 n, RsVec3* t, RsVec3* b) {
  float sign = n.z >= 0.0f ? 1.0f : -1.0f;
  float a = -1.0f / (sign + n.z);
  float bb = n.x * n.y * a;
  *t = rs_vec3(1.0f + sign * n.x * n.x * a, sign * bb, -sign * n.x);
  *b = rs_vec3(bb, sign + n.y * n.y * a, -n.y);
}

/* Cosine-weighted direction around unit normal n from (u1, u2) in [0,1)² (Malley's method). */
RS_INLINE RsVec3 rs_cosine_direction(RsVec3 n, float u1, float u2) {
  float r = rs_sqrt(u1);
  float s, c;
  rs_sincos_2pi(u2, &s, &c);
  float lx = r * c, ly = r * s;
  float lz = rs_sqrt(rs_max(0.0f, 1.0f - u1));
  RsVec3 t, b;
  rs_onb(n, &t, &b);
  return rs_normalize(rs_add(rs_add(rs_scale(t, lx), rs_scale(b, ly)), rs_scale(n, lz)));
}

/* Uniform point on the unit sphere from (u1, u2) in [0,1)². */
RS_INLINE RsVec3 rs_sphere_point(float u1, float u2) {
  float z = 1.0f - 2.0f * u1;
  float r = rs_sqrt(rs_max(0.0f, 1.0f - z * z));
  float s, c;
  rs_sincos_2pi(u2, &s, &c);
  return rs_vec3(r * c, r * s, z);
}

/* Offset a surface point p along the geometric normal n (pointing to the side the new ray leaves
 * from) so that the new ray does not hit its own surface: an offset in ulps, which scales with
 * the magnitude of p, and a small absolute offset near the origin (Wächter & Binder,
 * "A Fast and Robust Method for Avoiding Self-Intersection", Ray Tracing Gems, ch. 6). */
RS_INLINE float rs_offset_component(float p, float n) {
  const float origin = 1.0f / 32.0f;
  const float float_scale = 1.0f / 65536.0f;
  const float int_scale = 256.0f;
  rs_i32 of_i = (rs_i32)(int_scale * n);
  float p_i = rs_int_as_float(rs_float_as_int(p) + (p < 0.0f ? -of_i : of_i));
  return rs_abs(p) < origin ? p + float_scale * n : p_i;
}
RS_INLINE RsVec3 rs_offset_ray_origin(RsVec3 p, RsVec3 n) {
  return rs_vec3(rs_offset_component(p.x, n.x), rs_offset_component(p.y, n.y), rs_offset_component(p.z, n.z));
}

/* Hit point from barycentrics: (1-u-v)·v0 + u·v1 + v·v2 (more accurate than o + t·d). */
RS_INLINE RsVec3 rs_hit_point(RsVec3 v0, RsVec3 v1, RsVec3 v2, float u, float v) {
  float w = 1.0f - u - v;
  return rs_add(rs_add(rs_scale(v0, w), rs_scale(v1, u)), rs_scale(v2, v));
}

/* Unit geometric normal of a triangle, turned to face against direction d (the side a ray
 * arrived from). */
RS_INLINE RsVec3 rs_facing_normal(RsVec3 v0, RsVec3 v1, RsVec3 v2, RsVec3 d) {
  RsVec3 n = rs_normalize(rs_cross(rs_sub(v1, v0), rs_sub(v2, v0)));
  return rs_dot(n, d) > 0.0f ? rs_scale(n, -1.0f) : n;
}

#endif /* RAYSORT_SHARED_H */
