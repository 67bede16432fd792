/* raysort — the spatial keys (Meister et al. 2020, section 3; Xiang et al. section 3.2 and
 * section 5): Origin, Reis, Costa, Aila and TwoPoint, codes of a ray's origin, direction or
 * estimated termination point in the scene's box; and the direction bits HCC_DIR appends
 * (keys_cut.h). Layouts: keys.h's banner and docs/encoders.md.
 */
#ifndef RAYSORT_KEYS_SPATIAL_H
#define RAYSORT_KEYS_SPATIAL_H

#include "keys.h"

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
  RsTraversalRay r = rs_exit_ray(ray); /* rs_prepare_ray's bits, in a form PoCL vectorises (keys.h) */
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

/* The host twin's spatial key: one case per SPATIAL row of the encoder list (encoders.h), each
 * calling that row's rs_<code>_code. The kernels call rs_<code>_code directly (encode.cl). */
#define RS_SPATIAL_CASE(ID, HOST, NAME, CODE, WEIGHT, ALIASES) \
  case RS_ENC_##ID:                                \
    return rs_##CODE##_code(f, r);
RS_KEY_INLINE rs_u64 rs_spatial_code(int encoder, const RsEncodeFrame* f, RsRay r) {
  switch (encoder) {
    RS_ENCODERS(RS_NO_ROW, RS_SPATIAL_CASE)
    default: return 0;
  }
}
#undef RS_SPATIAL_CASE

#endif /* RAYSORT_KEYS_SPATIAL_H */
