/* raysort — random numbers and the rays made from them, the same bits on the host and the device:
 * the counter-based RNG, sin/cos of a turn, camera rays, and the origin offset, hit point and
 * facing normal of secondary rays (render/rays.cpp and shade.h build every batch from these).
 */
#ifndef RAYSORT_SAMPLING_H
#define RAYSORT_SAMPLING_H

#include "shared.h"

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

#endif /* RAYSORT_SAMPLING_H */
