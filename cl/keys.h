/* raysort — ray sort keys: what every key layout shares (encoder ids, the scene frame, quantization,
 * bit assembly, Morton spreading); the families follow in keys_spatial.h, keys_cut.h and
 * keys_ppc.h. Shared by cl/encode.cl and the host twin (host/encode/). Bit diagrams:
 * docs/encoders.md.
 *
 * Every encoder builds a 64-bit code, most significant bit first; a key of b bits is the code's
 * top b bits, code >> (64 − b) (this is how Meister et al. 2020's reference
 * kernels truncate). Keys of up to 32 bits are stored in 32-bit words, 64-bit keys in 64-bit words.
 *
 * Spatial encoders (Meister et al. 2020, "On Ray Reordering Techniques for Faster GPU Ray
 * Tracing"; Xiang et al., "Faster Ray Tracing through Hierarchy Cut Code", section 3.2):
 *   Origin    3-D Morton code of the origin (22 levels, truncated to 64 bits)
 *   Reis      22 origin bits (7 Morton levels + 1), then 21 levels of (φ, θ) interleaved
 *   Costa     4 levels of (φ, θ), then 15 Morton levels of the origin, then 11 zero bits
 *   Aila      3 Morton levels of the origin, then 9 groups [origin level i xyz | direction level xyz]
 *   TwoPoint  6-D Morton code of origin a and estimated termination point b (11 levels, truncated)
 * Box-set encoders (Xiang et al. sections 4.2–4.3, 5): bit i (from the top) = the ray segment
 * [tmin, tmax] overlaps box i. HCC (cut nodes by descending HAD), RegularGrid (grid cells),
 * HCC_DIR (appendix: b − d cut bits, then d direction bits), MLHCC (two-level cut),
 * PPC (section 4.1: the first b box tests of a traversal in fixed left-first order).
 * Beyond the paper (issue 21): HCC_REGION (r bits of the origin's region, then the HCC of that
 * region's own cut) and HCC_TRAFFIC (an HCC whose cut priority blends HAD with measured node traffic;
 * its key is HCC's box-set key over another cut), and MLHCC_COST (MLHCC's two-level cut with a
 * shorter low level, then a traversal-cost estimate from a previous frame; keys_cut.h).
 *
 * Quantization is in the scene's box: q = clamp(floor(t·2^n), 0, 2^n − 1) with
 * t = (p − box.min)·inv_extent; a flat axis has inv_extent = 0 (t = 0). The clamp keeps points on
 * the max face, and points outside the box, inside their field.
 * Directions are normalised here (rays need not carry unit directions); φ = atan2(dy, dx)/2π + ½,
 * θ = acos(dz)/π with dz clamped to [−1, 1]; atan2/acos come from encode_math.h (no library
 * transcendentals). The ray segment tests use the ray's own parameterisation (t units).
 */
#ifndef RAYSORT_KEYS_H
#define RAYSORT_KEYS_H

#include "encode_math.h"
#include "encoders.h"
#include "intersect.h"
#include "shared.h"

/* Key code is inlined into the kernels, so PoCL sees one straight-line work-item body (except under
 * Oclgrind; plain inline on the host: RS_FORCE_INLINE, shared.h). */
#define RS_KEY_INLINE RS_FORCE_INLINE

#ifdef __OPENCL_VERSION__
#define RS_LOCAL __local
#define RS_U64(x) ((ulong)(x))
#define RS_CONSTANT __constant
RS_KEY_INLINE rs_u32 rs_clz64(rs_u64 x) { return (rs_u32)clz(x); }
/* Key stores of the encode kernels (encode.cl, encode_file.h). A 64-bit key goes out as two 32-bit
 * words on a little-endian device: PoCL's work-group vectoriser sizes its vectors by the widest type
 * stored, so a ulong store runs the whole kernel 4 rays at a time (AVX2), two uint stores 8 at a time. */
#define RS_STORE_KEY_k32(keys, i, key) ((keys)[i] = (uint)(key))
#ifdef __ENDIAN_LITTLE__
#define RS_STORE_KEY_k64(keys, i, key)                            \
  do {                                                            \
    const ulong k_ = (key);                                       \
    ((__global uint*)(keys))[2u * (i)] = (uint)k_;                \
    ((__global uint*)(keys))[2u * (i) + 1u] = (uint)(k_ >> 32);   \
  } while (0)
#else
#define RS_STORE_KEY_k64(keys, i, key) ((keys)[i] = (ulong)(key))
#endif
#else
#define RS_LOCAL
#define RS_CONSTANT
#define RS_U64(x) ((rs_u64)(x))
RS_KEY_INLINE rs_u32 rs_clz64(rs_u64 x) { return (rs_u32)std::countl_zero(x); }
#endif

/* Encoder ids, RS_ENC_NOSORT = 0, RS_ENC_ORIGIN, ...: the positions in the encoder list
 * (encoders.h), and the values of the host's enum class Encoder (host/encode/encoder.h). */
#define RS_ENCODER_ID(ID, HOST, NAME, FAMILY_OR_CODE, WEIGHT, ALIASES) RS_ENC_##ID,
enum { RS_ENCODERS(RS_ENCODER_ID, RS_ENCODER_ID) RS_ENC_COUNT };
#undef RS_ENCODER_ID

/* The most boxes a box-set key reads per ray: one per key bit. */
#define RS_MAX_KEY_BITS 64

/* An axis-aligned box, 24 bytes: [bmin.x bmin.y bmin.z bmax.x bmax.y bmax.z]. Cut nodes and grid
 * cells go to the device as arrays of these (bit order = array order). */
typedef struct {
  float bmin[3];
  float bmax[3];
} RsBox;

/* Per-scene encode constants, 48 bytes, computed once on the host and uploaded as is:
 * [box_min xyz | twopoint_length | box_max xyz | pad | inv_extent xyz | pad].
 * inv_extent[a] = 1 / (box_max[a] − box_min[a]), or 0 on a flat axis.
 * twopoint_length = TwoPoint's fixed ray length (fraction · largest extent of the box). */
typedef struct {
  float box_min[3];
  float twopoint_length;
  float box_max[3];
  float pad0;
  float inv_extent[3];
  float pad1;
} RsEncodeFrame;

/* ---------------------------------------------------------------------------------------------
 * Quantization and bit assembly.
 * ------------------------------------------------------------------------------------------- */

/* clamp(floor(t·2^n), 0, 2^n − 1) for n ≤ 24 (2^n exact in float). NaN maps to 0. */
RS_KEY_INLINE rs_u32 rs_quantize(float t, rs_u32 n) {
  float cells = (float)(1u << n);
  float q = rs_floor(t * cells);
  q = rs_max(0.0f, rs_min(q, cells - 1.0f));
  return (rs_u32)q;
}

/* The n-bit cell of coordinate p on axis a of the scene box. */
RS_KEY_INLINE rs_u32 rs_quantize_axis(const RsEncodeFrame* f, int a, float p, rs_u32 n) {
  return rs_quantize((p - f->box_min[a]) * f->inv_extent[a], n);
}

/* A 64-bit code filled from its most significant bit down. */
typedef struct {
  rs_u64 code;
  rs_u32 used;
} RsBitWriter;

RS_KEY_INLINE RsBitWriter rs_bit_writer(void) {
  RsBitWriter w;
  w.code = 0;
  w.used = 0;
  return w;
}

/* Appends the low n bits of v (n ≤ 32), most significant first; bits past 64 are dropped. */
RS_KEY_INLINE void rs_put_bits(RsBitWriter* w, rs_u32 v, rs_u32 n) {
  if (w->used >= 64u || n == 0u) return;
  rs_u64 bits = RS_U64(v) & ((RS_U64(1) << n) - 1u);
  rs_u32 room = 64u - w->used;
  if (n <= room) {
    w->code |= bits << (room - n);
    w->used += n;
  } else {
    w->code |= bits >> (n - room);
    w->used = 64u;
  }
}

/* Bit `level` (0 = most significant) of an n-bit quantized coordinate. */
RS_KEY_INLINE rs_u32 rs_level_bit(rs_u32 q, rs_u32 n, rs_u32 level) { return (q >> (n - 1u - level)) & 1u; }

/* The key of b bits (1 ≤ b ≤ 64): the code's top b bits. */
RS_KEY_INLINE rs_u64 rs_key_from_code(rs_u64 code, rs_u32 bits) { return bits >= 64u ? code : code >> (64u - bits); }

/* ---------------------------------------------------------------------------------------------
 * Ray fields.
 * ------------------------------------------------------------------------------------------- */

#define RS_ORIGIN_LEVELS 22u    /* 3·22 = 66 ≥ 64: enough levels for every origin field */
#define RS_DIRECTION_LEVELS 21u /* 2·21 = 42: Reis's direction field */
#define RS_AILA_DIR_LEVELS 9u
#define RS_TWOPOINT_LEVELS 11u  /* 6·11 = 66 ≥ 64 */

/* Origin cells (n bits per axis). */
RS_KEY_INLINE void rs_quantize_point(const RsEncodeFrame* f, RsVec3 p, rs_u32 n, rs_u32 q[3]) {
  q[0] = rs_quantize_axis(f, 0, p.x, n);
  q[1] = rs_quantize_axis(f, 1, p.y, n);
  q[2] = rs_quantize_axis(f, 2, p.z, n);
}

/* The unit direction: d / |d| (a zero direction stays zero). */
RS_KEY_INLINE RsVec3 rs_unit_direction(RsRay r) {
  /* rs_normalize (cl/shared.h), the same arithmetic in the same order, with one select per
   * component instead of a select of the whole vector (which PoCL's vectoriser cannot widen). */
  const float x = r.d[0], y = r.d[1], z = r.d[2];
  const float len = rs_sqrt(x * x + y * y + z * z);
  const int ok = len > 0.0f;
  const float s = 1.0f / (ok ? len : 1.0f);
  return rs_vec3(ok ? x * s : x, ok ? y * s : y, ok ? z * s : z);
}

/* Spherical direction cells: q[0] = φ = atan2(dy, dx)/2π + ½, q[1] = θ = acos(dz)/π, n bits each. */
RS_KEY_INLINE void rs_quantize_spherical(RsVec3 d, rs_u32 n, rs_u32 q[2]) {
  float phi = rs_atan2(d.y, d.x) * RS_INV_2PI_F + 0.5f;
  float theta = rs_acos(d.z) * RS_INV_PI_F;
  q[0] = rs_quantize(phi, n);
  q[1] = rs_quantize(theta, n);
}

/* Bit interleaving without loops ("part1by2"/"part1by1" magic-number spreading on 64 bits): the
 * codes below are exactly those of appending Morton levels one bit at a time, most significant
 * first, and dropping bits past 64 (docs/encoders.md; tests/encode_test.cpp keeps that bitwise
 * formulation as a reference and compares). */

/* Bit k of v (v < 2^21) moves to bit 3k. */
RS_KEY_INLINE rs_u64 rs_spread3(rs_u32 v) {
  rs_u64 x = RS_U64(v) & RS_U64(0x1fffff);
  x = (x | (x << 32)) & RS_U64(0x1f00000000ffff);
  x = (x | (x << 16)) & RS_U64(0x1f0000ff0000ff);
  x = (x | (x << 8)) & RS_U64(0x100f00f00f00f00f);
  x = (x | (x << 4)) & RS_U64(0x10c30c30c30c30c3);
  x = (x | (x << 2)) & RS_U64(0x1249249249249249);
  return x;
}

/* Bit k of v moves to bit 2k. */
RS_KEY_INLINE rs_u64 rs_spread2(rs_u32 v) {
  rs_u64 x = RS_U64(v);
  x = (x | (x << 16)) & RS_U64(0x0000ffff0000ffff);
  x = (x | (x << 8)) & RS_U64(0x00ff00ff00ff00ff);
  x = (x | (x << 4)) & RS_U64(0x0f0f0f0f0f0f0f0f);
  x = (x | (x << 2)) & RS_U64(0x3333333333333333);
  x = (x | (x << 1)) & RS_U64(0x5555555555555555);
  return x;
}

/* Bit k of v (v < 2^10) moves to bit 6k. */
RS_KEY_INLINE rs_u64 rs_spread6(rs_u32 v) { return rs_spread2((rs_u32)rs_spread3(v)); }

/* The 3-D Morton code of (x, y, z), each below 2^21: bit k of x at 3k + 2, of y at 3k + 1, of z
 * at 3k, i.e. levels most significant first, x y z per level. */
RS_KEY_INLINE rs_u64 rs_morton3(rs_u32 x, rs_u32 y, rs_u32 z) {
  return (rs_spread3(x) << 2) | (rs_spread3(y) << 1) | rs_spread3(z);
}

/* The 2-D Morton code of (a, b): a's bits above b's, per level. */
RS_KEY_INLINE rs_u64 rs_morton2(rs_u32 a, rs_u32 b) { return (rs_spread2(a) << 1) | rs_spread2(b); }

/* The 6-D Morton code of six coordinates below 2^10, a0 most significant per level. */
RS_KEY_INLINE rs_u64 rs_morton6(rs_u32 a0, rs_u32 a1, rs_u32 a2, rs_u32 a3, rs_u32 a4, rs_u32 a5) {
  return (rs_spread6(a0) << 5) | (rs_spread6(a1) << 4) | (rs_spread6(a2) << 3) | (rs_spread6(a3) << 2) |
         (rs_spread6(a4) << 1) | rs_spread6(a5);
}

/* The ray rs_prepare_ray (intersect.h) gives, bit for bit, for TwoPoint's scene exit: the same
 * reciprocal 1/d with |d| < tiny replaced by ±tiny of d's sign, that sign picked by a select
 * rather than moved with integer operations as rs_safe_rcp does. Why (issue 42): rs_safe_rcp's
 * integer form (commit 609a4b9, for Oclgrind) gives three identical and/or chains, one per axis,
 * which PoCL's SLP pass packs two at a time into 2-lane vectors from the adjacent loads of dx and
 * dy; a vector-typed instruction stops its work-group vectoriser, so TwoPoint ran one ray at a
 * time, 2-5x HCC's encode (results/history/encoder-kernels.md). The select form is not packed.
 * Oclgrind cannot run the llvm.copysign.f32 that LLVM's optimiser makes of the select, but the
 * host builds kernels for simulators with -cl-opt-disable (host/runtime/runtime.cpp), where no
 * such fold runs. EncodeMath.ExitRayIsThePreparedRay compares with rs_prepare_ray bit for bit;
 * the ctest spatial_kernels_vectorised checks that PoCL vectorises every spatial kernel. */
RS_KEY_INLINE float rs_exit_rcp(float d) {
  const float tiny = 1e-30f;
  const float sd = rs_abs(d) < tiny ? (d < 0.0f || (d == 0.0f && rs_float_as_int(d) < 0) ? -tiny : tiny) : d;
  return 1.0f / sd;
}

/* Written out, not rs_prepare_ray with inv_d replaced: PoCL does not drop the integer-form
 * reciprocals in time and the kernel stays scalar (spatial_kernels_vectorised fails that way). */
RS_KEY_INLINE RsTraversalRay rs_exit_ray(RsRay ray) {
  RsTraversalRay t;
  t.o = rs_vec3(ray.o[0], ray.o[1], ray.o[2]);
  t.d = rs_vec3(ray.d[0], ray.d[1], ray.d[2]);
  t.inv_d = rs_vec3(rs_exit_rcp(ray.d[0]), rs_exit_rcp(ray.d[1]), rs_exit_rcp(ray.d[2]));
  t.o_inv_d = rs_vec3(-(t.o.x * t.inv_d.x), -(t.o.y * t.inv_d.y), -(t.o.z * t.inv_d.z));
  t.tmin = ray.tmin;
  t.tmax = ray.tmax;
  return t;
}

/* Far end of a ray's segment inside the scene box: the slab-test exit distance (same reciprocal
 * as traversal), capped by tmax. The far plane of each axis is picked by the sign of inv_d, which
 * equals max((lo − o)·inv, (hi − o)·inv) since lo <= hi and the rounded product is monotone. The y
 * axis is written −((o − hi)·inv), the same value (up to the sign of a zero, which quantization
 * cannot see), and the minimum is taken as a chain: with three identical per-axis expressions
 * PoCL's SLP pass packs two of them into a 2-lane vector, which stops its work-group vectoriser
 * (TwoPoint then ran one ray at a time, 3x slower). tests/encode_test.cpp compares with the
 * min/max form. */
RS_KEY_INLINE float rs_scene_exit(const RsEncodeFrame* f, RsTraversalRay r) {
  float fx = ((r.inv_d.x < 0.0f ? f->box_min[0] : f->box_max[0]) - r.o.x) * r.inv_d.x;
  float fy = -((r.o.y - (r.inv_d.y < 0.0f ? f->box_min[1] : f->box_max[1])) * r.inv_d.y);
  float fz = ((r.inv_d.z < 0.0f ? f->box_min[2] : f->box_max[2]) - r.o.z) * r.inv_d.z;
  return rs_min(rs_min(rs_min(fx, fy), fz), r.tmax);
}

#endif /* RAYSORT_KEYS_H */
