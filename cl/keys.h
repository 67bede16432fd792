/* raysort — ray sort keys: the one definition of every key layout, shared by cl/encode.cl and
 * the host twin (host/encode/). Bit diagrams: docs/encoders.md.
 *
 * Every encoder builds a 64-bit code, most significant bit first; a key of b bits is the code's
 * top b bits, code >> (64 − b) (DESIGN.md section 3; this is how Meister et al. 2020's reference
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
#include "shared.h"
#include "traverse.h"

#ifdef __OPENCL_VERSION__
#define RS_LOCAL __local
#define RS_U64(x) ((ulong)(x))
#define RS_CONSTANT __constant
/* Key code is inlined into the kernels, so PoCL sees one straight-line work-item body. */
#define RS_KEY_INLINE inline __attribute__((always_inline))
RS_KEY_INLINE rs_u32 rs_clz64(rs_u64 x) { return (rs_u32)clz(x); }
#else
#define RS_LOCAL
#define RS_CONSTANT
#define RS_U64(x) ((rs_u64)(x))
#define RS_KEY_INLINE inline
RS_KEY_INLINE rs_u32 rs_clz64(rs_u64 x) { return (rs_u32)std::countl_zero(x); }
#endif

/* Encoder ids: the values of the host's enum class Encoder (host/encode/encode.h). */
#define RS_ENC_NOSORT 0
#define RS_ENC_ORIGIN 1
#define RS_ENC_REIS 2
#define RS_ENC_COSTA 3
#define RS_ENC_AILA 4
#define RS_ENC_TWOPOINT 5
#define RS_ENC_REGULAR_GRID 6
#define RS_ENC_HCC 7
#define RS_ENC_MLHCC 8
#define RS_ENC_PPC 9
#define RS_ENC_HCC_DIR 10

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

/* ---------------------------------------------------------------------------------------------
 * Spatial codes (Meister et al. 2020, section 3; Xiang et al. section 3.2 and section 5).
 * ------------------------------------------------------------------------------------------- */

/* Origin: the 3-D Morton code of the origin, x y z per level: levels 0..20 (63 bits), then x of
 * level 21 (y and z of level 21 fall past bit 0). */
RS_KEY_INLINE rs_u64 rs_origin_code(const RsEncodeFrame* f, RsRay r) {
  rs_u32 q[3];
  rs_quantize_point(f, rs_load3(r.o), RS_ORIGIN_LEVELS, q);
  return (rs_morton3(q[0] >> 1, q[1] >> 1, q[2] >> 1) << 1) | (q[0] & 1u);
}

/* Reis et al. 2017 (origin → direction): 22 origin Morton bits (7 levels and x of level 7), then
 * 21 levels of (φ, θ). */
RS_KEY_INLINE rs_u64 rs_reis_code(const RsEncodeFrame* f, RsRay r) {
  rs_u32 q[3], s[2];
  rs_quantize_point(f, rs_load3(r.o), RS_ORIGIN_LEVELS, q);
  rs_quantize_spherical(rs_unit_direction(r), RS_DIRECTION_LEVELS, s);
  const rs_u32 k = RS_ORIGIN_LEVELS - 7u; /* the low bits below the 7 top levels */
  return (rs_morton3(q[0] >> k, q[1] >> k, q[2] >> k) << 43) | (RS_U64((q[0] >> (k - 1u)) & 1u) << 42) |
         rs_morton2(s[0], s[1]);
}

/* Costa et al. 2015 (direction → origin): 4 levels of (φ, θ), 15 origin Morton levels, 11 zeros. */
RS_KEY_INLINE rs_u64 rs_costa_code(const RsEncodeFrame* f, RsRay r) {
  rs_u32 q[3], s[2];
  rs_quantize_point(f, rs_load3(r.o), 15u, q);
  rs_quantize_spherical(rs_unit_direction(r), 4u, s);
  return (rs_morton2(s[0], s[1]) << 56) | (rs_morton3(q[0], q[1], q[2]) << 11);
}

/* Aila & Karras 2010 ("Aila_Compact" of Meister et al.): 3 origin Morton levels, then 9 groups of
 * [origin level 3+i: x y z | direction level i: x y z of (d + 1)/2]; the last bit is 0. */
RS_KEY_INLINE rs_u64 rs_aila_code(const RsEncodeFrame* f, RsRay r) {
  const rs_u32 on = 12u, dn = RS_AILA_DIR_LEVELS;
  rs_u32 q[3], dq[3];
  rs_quantize_point(f, rs_load3(r.o), on, q);
  RsVec3 d = rs_unit_direction(r);
  dq[0] = rs_quantize((d.x + 1.0f) * 0.5f, dn);
  dq[1] = rs_quantize((d.y + 1.0f) * 0.5f, dn);
  dq[2] = rs_quantize((d.z + 1.0f) * 0.5f, dn);
  const rs_u32 low = (1u << (on - 3u)) - 1u; /* origin levels 3..11 (9 = dn bits) */
  return (rs_morton3(q[0] >> (on - 3u), q[1] >> (on - 3u), q[2] >> (on - 3u)) << 55) |
         (rs_morton6(q[0] & low, q[1] & low, q[2] & low, dq[0], dq[1], dq[2]) << 1);
}

/* TwoPoint (Moon et al. 2010; Meister et al. 2020, fixed-length estimate): 6-D Morton code of the
 * origin a and b = a + L·d, L = max(0, min(twopoint_length, tmax, scene-box exit)); b is clamped
 * to the box by the quantization. Per level: a.x a.y a.z b.x b.y b.z; levels 0..9 (60 bits), then
 * a.x a.y a.z b.x of level 10. */
RS_KEY_INLINE rs_u64 rs_twopoint_code(const RsEncodeFrame* f, RsRay ray) {
  const rs_u32 n = RS_TWOPOINT_LEVELS;
  RsTraversalRay r = rs_prepare_ray(ray);
  float len = rs_max(0.0f, rs_min(f->twopoint_length, rs_scene_exit(f, r)));
  RsVec3 b = rs_add(r.o, rs_scale(r.d, len));
  rs_u32 qa[3], qb[3];
  rs_quantize_point(f, r.o, n, qa);
  rs_quantize_point(f, b, n, qb);
  return (rs_morton6(qa[0] >> 1, qa[1] >> 1, qa[2] >> 1, qb[0] >> 1, qb[1] >> 1, qb[2] >> 1) << 4) |
         RS_U64(((qa[0] & 1u) << 3) | ((qa[1] & 1u) << 2) | ((qa[2] & 1u) << 1) | (qb[0] & 1u));
}

/* d direction bits (HCC_DIR): the top d bits of the Reis direction field, (φ, θ) interleaved. */
RS_KEY_INLINE rs_u64 rs_direction_bits(RsRay r, rs_u32 d) {
  rs_u32 s[2];
  rs_quantize_spherical(rs_unit_direction(r), RS_DIRECTION_LEVELS, s);
  return rs_key_from_code(rs_morton2(s[0], s[1]) << (64u - 2u * RS_DIRECTION_LEVELS), d);
}

/* rs_direction_bits(r, 1), HCC_DIR's default single direction bit, read from the signs of dx and dy
 * where they decide it, so that HCC_DIR needs no atan2 per ray and runs in one pass with its box
 * test (encode.cl). The bit is φ's top bit: φ = atan2(y, x)/2π + ½ ≥ ½ on the unit direction (x, y).
 * - dy ≥ 0 (±0 included): the unit y is ≥ 0, ±0 or NaN, for which rs_atan2 returns an angle ≥ 0 or
 *   NaN, so φ ≥ ½ or NaN, which quantises to the top cell: 1, at any scale.
 * - dy < 0, the largest |component| in [2^-40, 2^40] and |dy| ≥ 2^-80: normalising neither overflows
 *   nor underflows, so the unit y is < 0 and the unit x has dx's sign (or is ±0).
 *   dx ≤ 0: the angle is ≤ −π/2, φ ≤ ¼: 0.
 *   dx ≥ 2^-80 and |dy| ≥ 2^-19·dx: the unit ratio |y|/x is ≥ 2^-19·(1 − 2^-21), rs_atan_unit
 *   gives more than 0.9 times it, so φ < ½ − 2.7e-7, which stays below ½ after rounding (the float
 *   below ½ is ½ − 3e-8): 0.
 * - otherwise (dy < 0 within 2^-19 of the +x axis, where φ can round up to ½; extreme scales; NaN):
 *   the definition itself.
 * Encode.DirectionTopBitIsTheDefinitions checks rays on and around every boundary. */
RS_KEY_INLINE rs_u64 rs_direction_top_bit(RsRay r) {
  const float x = r.d[0], y = r.d[1], z = r.d[2];
  if (y >= 0.0f) return 1u;
  const float ax = rs_abs(x), ay = -y, az = rs_abs(z);
  const float m = ax > ay ? (ax > az ? ax : az) : (ay > az ? ay : az);
  if (m >= 0x1p-40f && m <= 0x1p40f && ay >= 0x1p-80f) {
    if (x <= 0.0f) return 0u;
    if (x >= 0x1p-80f && ay >= x * 0x1p-19f) return 0u;
  }
  return rs_direction_bits(r, 1u);
}

/* HCC_DIR's d direction bits: rs_direction_bits, by the signs of dx and dy for d = 1. */
RS_KEY_INLINE rs_u64 rs_direction_field(RsRay r, rs_u32 d) {
  return d == 1u ? rs_direction_top_bit(r) : rs_direction_bits(r, d);
}

RS_KEY_INLINE rs_u64 rs_spatial_code(int encoder, const RsEncodeFrame* f, RsRay r) {
  switch (encoder) {
    case RS_ENC_ORIGIN: return rs_origin_code(f, r);
    case RS_ENC_REIS: return rs_reis_code(f, r);
    case RS_ENC_COSTA: return rs_costa_code(f, r);
    case RS_ENC_AILA: return rs_aila_code(f, r);
    case RS_ENC_TWOPOINT: return rs_twopoint_code(f, r);
    default: return 0;
  }
}

/* ---------------------------------------------------------------------------------------------
 * Box-set codes (Xiang et al. Alg. 1).
 * ------------------------------------------------------------------------------------------- */

/* Does the segment [tmin, tmax] of r overlap box b? The same slab arithmetic, in the same order,
 * as rs_intersect_box in traverse.h (which takes a __global node; this takes a box by value):
 * a cut-node bit is 1 exactly when traversal would enter it.
 * (The key kernels test sixteen boxes at once, rs_cut_mask; this one-box form is kept for
 * reference and tests.) */
RS_KEY_INLINE int rs_segment_overlaps_box(RsTraversalRay r, RsBox b) {
  float tx0 = (b.bmin[0] - r.o.x) * r.inv_d.x, tx1 = (b.bmax[0] - r.o.x) * r.inv_d.x;
  float ty0 = (b.bmin[1] - r.o.y) * r.inv_d.y, ty1 = (b.bmax[1] - r.o.y) * r.inv_d.y;
  float tz0 = (b.bmin[2] - r.o.z) * r.inv_d.z, tz1 = (b.bmax[2] - r.o.z) * r.inv_d.z;
  float tnear = rs_max(rs_max(rs_min(tx0, tx1), rs_min(ty0, ty1)), rs_max(rs_min(tz0, tz1), r.tmin));
  float tfar = rs_min(rs_min(rs_max(tx0, tx1), rs_max(ty0, ty1)), rs_min(rs_max(tz0, tz1), r.tmax));
  return tnear <= tfar;
}

/* Sixteen cut boxes, one axis bound per vector (SoA), so one pass of the slab test serves sixteen
 * boxes. Box j of a group sits in lane 15 − j, so that the group's hit mask, as bits (lane l ->
 * bit l, rs16_mask_bits), is the group's field of the code: shifted into place, lane l of group k is
 * code bit 48 + l − first_bit − 16k. An empty lane is a zero box, masked off by the box count.
 * 384 bytes. Built on the host (host/encode/encode.cpp, rs_cut_groups). The bounds must come in
 * this order: rs_cut_mask indexes them as (&lo_x)[2·axis + side]. */
#define RS_CUT_LANES 16u
typedef struct {
  rs_f16 lo_x, hi_x, lo_y, hi_y, lo_z, hi_z;
} RsCutGroup;

/* The number of groups holding n boxes. */
RS_KEY_INLINE rs_u32 rs_cut_group_count(rs_u32 n) { return (n + RS_CUT_LANES - 1u) / RS_CUT_LANES; }

/* A ray broadcast to sixteen lanes, and per axis the side of the box its slab enters first
 * (near_x = 1: the hi plane, where 1/d < 0). */
typedef struct {
  rs_f16 ox, oy, oz, ix, iy, iz, tmin, tmax;
  rs_u32 near_x, near_y, near_z;
} RsCutRay;

RS_KEY_INLINE RsCutRay rs_cut_ray(RsTraversalRay r) {
  RsCutRay c;
  c.ox = rs16_splat(r.o.x), c.oy = rs16_splat(r.o.y), c.oz = rs16_splat(r.o.z);
  c.ix = rs16_splat(r.inv_d.x), c.iy = rs16_splat(r.inv_d.y), c.iz = rs16_splat(r.inv_d.z);
  c.tmin = rs16_splat(r.tmin), c.tmax = rs16_splat(r.tmax);
  c.near_x = r.inv_d.x < 0.0f, c.near_y = r.inv_d.y < 0.0f, c.near_z = r.inv_d.z < 0.0f;
  return c;
}

/* rs_segment_overlaps_box on the sixteen boxes of g: -1 in each lane whose box the segment overlaps.
 * The same values as there, with the near and far plane of each axis picked by the sign of 1/d
 * instead of a min and a max per box (the trace kernels' rs_wide_boxes does the same): for
 * lo <= hi, (lo − o)·inv and (hi − o)·inv keep their order after rounding, so the min is the near
 * plane's t. inv is never 0 or NaN (rs_safe_rcp) and rays are finite; a box must have lo <= hi
 * (rs_cut_groups checks). min/max are selects, see rs16_min. */
#define RS_DEFINE_CUT_MASK(NAME, SPACE, MASK_T, VEC_T, HALF, MIN, MAX)                                     \
  RS_KEY_INLINE MASK_T NAME(const RsCutRay* r, SPACE const RsCutGroup* g) {                                   \
    SPACE const rs_f16* b = &g->lo_x;                                                                         \
    const VEC_T tnx = (b[r->near_x] HALF - r->ox HALF) * r->ix HALF;                                          \
    const VEC_T tfx = (b[1u - r->near_x] HALF - r->ox HALF) * r->ix HALF;                                     \
    const VEC_T tny = (b[2u + r->near_y] HALF - r->oy HALF) * r->iy HALF;                                     \
    const VEC_T tfy = (b[3u - r->near_y] HALF - r->oy HALF) * r->iy HALF;                                     \
    const VEC_T tnz = (b[4u + r->near_z] HALF - r->oz HALF) * r->iz HALF;                                     \
    const VEC_T tfz = (b[5u - r->near_z] HALF - r->oz HALF) * r->iz HALF;                                     \
    const VEC_T tnear = MAX(MAX(tnx, tny), MAX(tnz, r->tmin HALF));                                           \
    const VEC_T tfar = MIN(MIN(tfx, tfy), MIN(tfz, r->tmax HALF));                                            \
    return tnear <= tfar;                                                                                     \
  }

/* The code bits of the n boxes of g that the segment overlaps (n <= 64; box i in group i / 16,
 * code bit 63 − first_bit − i): each group's hit mask as bits (rs16_mask_bits: one kmovd on
 * AVX-512 devices, cl/shared.h), restricted to its boxes' lanes and shifted into place.
 * On the device, a last group with at most eight boxes (in lanes 8..15) is tested on its upper
 * eight lanes only (rs_cut_mask_half_*): with AVX-512, PoCL runs a sixteen-lane operation as one
 * zmm instruction, which Zen 4 executes in two halves, so a half-empty group would cost a full one
 * (MLHCC at 16 bits has two such groups per key). The host tests every group whole; the code is
 * the same.
 * One definition per address space (OpenCL C 1.2 has no generic pointers): _p private/host,
 * _c constant, _g global. */
#ifdef __OPENCL_VERSION__
#define RS_CUT_WHOLE_ABOVE (RS_CUT_LANES / 2u) /* a last group with more boxes is tested whole */
#define RS_DEFINE_CUT_MASK_HALF(SUFFIX, SPACE)                                                       \
  RS_DEFINE_CUT_MASK(rs_cut_mask_half_##SUFFIX, SPACE, int8, float8, .hi, rs8_min, rs8_max)
#define RS_CUT_BITS_HALF(SUFFIX)                                                                     \
  if (rest > 0u && rest <= RS_CUT_WHOLE_ABOVE) {                                                     \
    const rs_u32 m = rs8_mask_bits(rs_cut_mask_half_##SUFFIX(r, &g[full])) & (0xFF00u >> rest);      \
    code |= (RS_U64(m) << 56) >> (first_bit + RS_CUT_LANES * full);                                  \
  }
#else
#define RS_CUT_WHOLE_ABOVE 0u
#define RS_DEFINE_CUT_MASK_HALF(SUFFIX, SPACE)
#define RS_CUT_BITS_HALF(SUFFIX)
#endif
#define RS_DEFINE_CUT_BITS(SUFFIX, SPACE)                                                            \
  RS_DEFINE_CUT_MASK(rs_cut_mask_##SUFFIX, SPACE, rs_i16, rs_f16, , rs16_min, rs16_max)              \
  RS_DEFINE_CUT_MASK_HALF(SUFFIX, SPACE)                                                             \
  RS_KEY_INLINE rs_u64 rs_cut_bits_##SUFFIX(const RsCutRay* r, SPACE const RsCutGroup* g, rs_u32 n,  \
                                            rs_u32 first_bit) {                                      \
    rs_u64 code = 0;                                                                                 \
    const rs_u32 full = n / RS_CUT_LANES, rest = n % RS_CUT_LANES;                                   \
    for (rs_u32 k = 0; k < full + (rest > RS_CUT_WHOLE_ABOVE); ++k) {                                \
      const rs_u32 left = n - RS_CUT_LANES * k; /* boxes from this group on, in lanes 15, 14, ... */   \
      const rs_u32 boxes = left < RS_CUT_LANES ? left : RS_CUT_LANES;                                \
      const rs_u32 m = rs16_mask_bits(rs_cut_mask_##SUFFIX(r, &g[k])) & (0xFFFF0000u >> boxes);      \
      code |= (RS_U64(m) << 48) >> (first_bit + RS_CUT_LANES * k);                                   \
    }                                                                                                \
    RS_CUT_BITS_HALF(SUFFIX)                                                                         \
    return code;                                                                                     \
  }
#ifdef __OPENCL_VERSION__
RS_DEFINE_CUT_BITS(c, __constant)
RS_DEFINE_CUT_BITS(g, __global)
#define RS_CUT_BITS_TOP rs_cut_bits_c
#else
RS_DEFINE_CUT_BITS(p, )
#define RS_CUT_BITS_TOP rs_cut_bits_p
#define rs_cut_bits_g rs_cut_bits_p
#endif

/* The space the box-set kernels read the cut groups from (HCC, grid, HCC_DIR, MLHCC top level). */
#define RS_CUT_SPACE RS_CONSTANT

/* HCC / RegularGrid / HCC_DIR: bit 63 − i = overlap with box i of the set (n boxes in
 * ceil(n / 16) groups, built on the host by rs_cut_groups; n ≤ 64 − dir_bits); then dir_bits
 * direction bits right below the box field of `field` bits (HCC_DIR). Every group is tested:
 * testing a group's union box first and skipping the groups it misses (a summary group, tried with
 * eight-box groups, in bit order and in Morton order) gave the same bits but was 1.2–1.9x slower
 * on PoCL for HCC and no faster for grid cells: sibenik's shadow rays are long and meet most of the
 * union boxes, and the data-dependent loop costs more than the groups it skips. */
RS_KEY_INLINE rs_u64 rs_box_set_code(RsRay ray, RS_CUT_SPACE const RsCutGroup* set, rs_u32 n, rs_u32 field,
                                     rs_u32 dir_bits) {
  RsTraversalRay r = rs_prepare_ray(ray);
  RsCutRay c = rs_cut_ray(r);
  rs_u64 code = RS_CUT_BITS_TOP(&c, set, n, 0u);
  if (dir_bits > 0u) code |= rs_direction_field(ray, dir_bits) << (64u - field - dir_bits);
  return code;
}

/* MLHCC (Xiang et al. section 4.3): the top `half_bits` bits are the HCC of the top-level cut; the
 * representative top node is the first one hit (top nodes are in descending HAD order); the next
 * `half_bits` bits are the HCC of its low-level cut: row rep of `low` (ceil(half_bits / 16)
 * groups, box j in group j / 16, j < low_count[rep], its code bit already 63 − half_bits − j). No
 * top node hit: the low bits are 0. */
RS_KEY_INLINE rs_u64 rs_two_level_cut_code(RsRay ray, RS_CUT_SPACE const RsCutGroup* top, rs_u32 n_top,
                                           RS_GLOBAL const RsCutGroup* low, RS_GLOBAL const rs_u32* low_count,
                                           rs_u32 half_bits) {
  RsTraversalRay r = rs_prepare_ray(ray);
  RsCutRay c = rs_cut_ray(r);
  rs_u64 code = RS_CUT_BITS_TOP(&c, top, n_top, 0u);
  if (code != 0u) {
    const rs_u32 rep = rs_clz64(code);
    code |= rs_cut_bits_g(&c, low + rep * rs_cut_group_count(half_bits), low_count[rep], half_bits);
  }
  return code;
}

/* Rays per work-item of the MLHCC kernel (rs_two_level_cut_code2 below; the host sizes the launch). */
#define RS_TWO_LEVEL_RAYS 2u
#ifdef __OPENCL_VERSION__
/* rs_two_level_cut_code for two rays, a and b (the device kernel's form; the host twin is the
 * one-ray function above, and the tests compare the two). A key's low-level test needs its own
 * top-level result first (which row), so one ray's work is a chain of dependent steps longer than
 * the processor can look ahead over; placed one after the other, two rays' chains overlap. The row
 * test runs with no branch on whether a top node was hit; its bits are dropped if not. (Four rays,
 * through private arrays, measured slower than one.) */
RS_KEY_INLINE void rs_two_level_cut_code2(RsRay ray_a, RsRay ray_b, RS_CUT_SPACE const RsCutGroup* top, rs_u32 n_top,
                                          RS_GLOBAL const RsCutGroup* low, RS_GLOBAL const rs_u32* low_count,
                                          rs_u32 half_bits, rs_u64* code_a, rs_u64* code_b) {
  const RsCutRay a = rs_cut_ray(rs_prepare_ray(ray_a));
  const RsCutRay b = rs_cut_ray(rs_prepare_ray(ray_b));
  const rs_u64 top_a = RS_CUT_BITS_TOP(&a, top, n_top, 0u);
  const rs_u64 top_b = RS_CUT_BITS_TOP(&b, top, n_top, 0u);
  const rs_u32 rep_a = top_a != 0u ? rs_clz64(top_a) : 0u, rep_b = top_b != 0u ? rs_clz64(top_b) : 0u;
  const rs_u32 row = rs_cut_group_count(half_bits);
  const rs_u64 low_a = rs_cut_bits_g(&a, low + rep_a * row, low_count[rep_a], half_bits);
  const rs_u64 low_b = rs_cut_bits_g(&b, low + rep_b * row, low_count[rep_b], half_bits);
  *code_a = top_a | (top_a != 0u ? low_a : 0u);
  *code_b = top_b | (top_b != 0u ? low_b : 0u);
}
#endif

/* PPC (Xiang et al. section 4.1): the first `bits` box-test results of a closest-hit traversal
 * that visits children in fixed order, left first: the root's test, then at each inner node the
 * left and the right child's tests (rs_intersect_box, the trace kernels' test, against the
 * current closest hit); leaves test their triangles, which shortens the segment as in a trace.
 * 1 = hit, most significant first; a traversal that ends early leaves 0s. */
RS_KEY_INLINE rs_u64 rs_prefix_path_code(RS_GLOBAL const RsBvhNode* nodes, RS_GLOBAL const RsTriangle* tris, RsRay ray,
                                     rs_u32 bits) {
  RsTraversalRay r = rs_prepare_ray(ray);
  float tmax = ray.tmax;
  RsBitWriter w = rs_bit_writer();
  int hit;
  rs_intersect_box(r, &nodes[0], tmax, &hit);
  rs_put_bits(&w, (rs_u32)hit, 1u);
  if (!hit) return w.code;
  rs_u32 stack[RS_STACK_SIZE];
  int sp = 0;
  rs_u32 node = 0;
  while (w.used < bits) {
    RS_GLOBAL const RsBvhNode* n = &nodes[node];
    if (n->count > 0) {
      for (rs_u32 i = n->first; i < n->first + n->count; ++i) {
        float t, u, v;
        if (rs_intersect_triangle(r, &tris[i], tmax, &t, &u, &v)) tmax = t;
      }
    } else {
      rs_u32 left = n->first;
      int hit_l, hit_r;
      rs_intersect_box(r, &nodes[left], tmax, &hit_l);
      rs_intersect_box(r, &nodes[left + 1], tmax, &hit_r);
      rs_put_bits(&w, (rs_u32)hit_l, 1u);
      rs_put_bits(&w, (rs_u32)hit_r, 1u);
      if (hit_l) {
        if (hit_r) stack[sp++] = left + 1;
        node = left;
        continue;
      }
      if (hit_r) {
        node = left + 1;
        continue;
      }
    }
    if (sp == 0) break;
    node = stack[--sp];
  }
  /* Drop results past the key (the last pair may overrun it by one). */
  return bits >= 64u ? w.code : w.code & ~((~RS_U64(0)) >> bits);
}

#endif /* RAYSORT_KEYS_H */
