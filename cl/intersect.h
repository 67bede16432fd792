/* raysort — ray/box and ray/triangle tests on the binary BVH layout, in two variants (docs/trace.md):
 *  - fast:   slab test for boxes (Kay & Kajiya 1986, as in Williams et al. 2005) and Möller–Trumbore
 *            for triangles (1997) — the usual GPU choice;
 *  - robust: watertight ray/triangle test (Woop, Benthin & Wald 2013, JCGT 2(1)) and a conservative
 *            slab test (Ize 2013, "Robust BVH Ray Traversal", JCGT 2(2)); no inf arithmetic, and
 *            zero direction components handled without a division.
 * Shared by the traversals (traverse_binary.h; traverse_wide.h and traverse_wide8.h, whose four- and
 * eight-lane tests do the same arithmetic per lane), the PPC key (keys_ppc.h), the cut keys' segment test (keys_cut.h) and the
 * host twin (host/trace/tracer.cpp), so host and kernel run the same operations in the same order.
 */
#ifndef RAYSORT_INTERSECT_H
#define RAYSORT_INTERSECT_H

#include "bvh_layout.h"
#include "shared.h"

/* A ray prepared for traversal: origin, direction, per-axis reciprocal direction, and per axis
 * −(o · 1/d) rounded once, the offset of the fast slab test's fused distances (rs_intersect_box). */
typedef struct {
  RsVec3 o;
  RsVec3 d;
  RsVec3 inv_d;
  RsVec3 o_inv_d; /* −(o · 1/d) per axis */
  float tmin;
  float tmax;
} RsTraversalRay;

/* The hit record of a ray that has hit nothing (yet): t = tmax, no triangle. */
RS_INLINE RsHit rs_miss(float tmax) {
  RsHit h;
  h.t = tmax;
  h.tri = RS_NO_HIT;
  h.u = 0.0f;
  h.v = 0.0f;
  return h;
}

/* 1/d with zero components mapped to a huge finite reciprocal of the same sign, so no inf or
 * NaN ever enters the slab test (the kernels must not depend on inf arithmetic).
 * Below tiny (zeros and denormals) the divisor is ±tiny with d's sign bit, so −0 gives −tiny.
 * The sign bit is moved with integer operations, not with a select between −tiny and tiny: LLVM
 * folds such a select into llvm.copysign.f32, which Oclgrind's interpreter cannot run
 * ("Undefined external function"). Same bits as the select for every d, NaN included. */
RS_INLINE float rs_safe_rcp(float d) {
  const float tiny = 1e-30f;
  float ad = rs_abs(d);
  const rs_i32 sign = rs_float_as_int(d) & (rs_i32)0x80000000u;
  float sd = ad < tiny ? rs_int_as_float(rs_float_as_int(tiny) | sign) : d;
  return 1.0f / sd;
}

/* The octant of a ray's 1/d (bit a set: 1/d < 0 on axis a, so a box's upper bound on that axis is
 * its near plane): what the W-wide box tests choose a node's planes by (traverse_wide_w.h). */
RS_INLINE int rs_octant_of_signs(int nx, int ny, int nz) { return nx | (ny << 1) | (nz << 2); }
RS_INLINE int rs_octant(float ix, float iy, float iz) { return rs_octant_of_signs(ix < 0.0f, iy < 0.0f, iz < 0.0f); }

RS_INLINE RsTraversalRay rs_prepare_ray(RsRay r) {
  RsTraversalRay t;
  t.o = rs_vec3(r.o[0], r.o[1], r.o[2]);
  t.d = rs_vec3(r.d[0], r.d[1], r.d[2]);
  t.inv_d = rs_vec3(rs_safe_rcp(r.d[0]), rs_safe_rcp(r.d[1]), rs_safe_rcp(r.d[2]));
  t.o_inv_d = rs_vec3(-(t.o.x * t.inv_d.x), -(t.o.y * t.inv_d.y), -(t.o.z * t.inv_d.z));
  t.tmin = r.tmin;
  t.tmax = r.tmax;
  return t;
}

/* Slab test: returns the entry distance and sets *hit when [entry, exit] overlaps [tmin, tmax].
 * A plane's distance is fma(plane, 1/d, −o·1/d), one fused operation after the ray's product (as
 * Embree's and Aila and Laine's kernels write it), not (plane − o) · 1/d: a subtraction fewer per
 * plane in every class's box test, measured 1-10 % faster on PoCL (results/history/trace-kernels.md,
 * "The fused slab test"). Every fast class but the coherent packets (traverse_coherent.h, whose
 * frustum bounds the unfused form) computes exactly this per box and lane, so they still agree bit
 * for bit; the robust variant keeps Ize's form, whose error bound is written for it. */
RS_INLINE float rs_intersect_box(RsTraversalRay r, RS_GLOBAL const RsBvhNode* n, float tmax, int* hit) {
  const float ax = r.o_inv_d.x, ay = r.o_inv_d.y, az = r.o_inv_d.z;
  float tx0 = rs_fma(n->bmin[0], r.inv_d.x, ax), tx1 = rs_fma(n->bmax[0], r.inv_d.x, ax);
  float ty0 = rs_fma(n->bmin[1], r.inv_d.y, ay), ty1 = rs_fma(n->bmax[1], r.inv_d.y, ay);
  float tz0 = rs_fma(n->bmin[2], r.inv_d.z, az), tz1 = rs_fma(n->bmax[2], r.inv_d.z, az);
  float tnear = rs_max(rs_max(rs_min(tx0, tx1), rs_min(ty0, ty1)), rs_max(rs_min(tz0, tz1), r.tmin));
  float tfar = rs_min(rs_min(rs_max(tx0, tx1), rs_max(ty0, ty1)), rs_min(rs_max(tz0, tz1), tmax));
  *hit = tnear <= tfar;
  return tnear;
}

/* The same test with distances (plane − o) · 1/d, two roundings: rs_intersect_box as it was before
 * it fused them. The encoders keep this form, so their keys and learned statistics keep their bits:
 * PPC's box tests (keys_ppc.h), the cut keys' segment test (keys_cut.h, the same arithmetic) and the
 * node traffic that hcc-traffic, hcc-region and mlhcc-cost learn from (RS_VARIANT_FAST_UNFUSED). It
 * differs from rs_intersect_box only for a ray that grazes a box within an ulp of a plane. */
RS_INLINE float rs_intersect_box_unfused(RsTraversalRay r, RS_GLOBAL const RsBvhNode* n, float tmax, int* hit) {
  float tx0 = (n->bmin[0] - r.o.x) * r.inv_d.x, tx1 = (n->bmax[0] - r.o.x) * r.inv_d.x;
  float ty0 = (n->bmin[1] - r.o.y) * r.inv_d.y, ty1 = (n->bmax[1] - r.o.y) * r.inv_d.y;
  float tz0 = (n->bmin[2] - r.o.z) * r.inv_d.z, tz1 = (n->bmax[2] - r.o.z) * r.inv_d.z;
  float tnear = rs_max(rs_max(rs_min(tx0, tx1), rs_min(ty0, ty1)), rs_max(rs_min(tz0, tz1), r.tmin));
  float tfar = rs_min(rs_min(rs_max(tx0, tx1), rs_max(ty0, ty1)), rs_min(rs_max(tz0, tz1), tmax));
  *hit = tnear <= tfar;
  return tnear;
}

/* Möller–Trumbore, two-sided. Returns 1 and fills (t, u, v) for a hit with tmin < t < tmax.
 * A degenerate triangle (zero area) has det == 0 and never hits. */
RS_INLINE int rs_intersect_triangle(RsTraversalRay r, RS_GLOBAL const RsTriangle* tri, float tmax, float* t_out,
                                    float* u_out, float* v_out) {
  RsVec3 v0 = rs_load3g(tri->v0);
  RsVec3 e1 = rs_sub(rs_load3g(tri->v1), v0);
  RsVec3 e2 = rs_sub(rs_load3g(tri->v2), v0);
  RsVec3 p = rs_cross(r.d, e2);
  float det = rs_dot(e1, p);
  if (det == 0.0f) return 0;
  float inv_det = 1.0f / det;
  RsVec3 s = rs_sub(r.o, v0);
  float u = rs_dot(s, p) * inv_det;
  if (!(u >= 0.0f && u <= 1.0f)) return 0;
  RsVec3 q = rs_cross(s, e1);
  float v = rs_dot(r.d, q) * inv_det;
  if (!(v >= 0.0f && u + v <= 1.0f)) return 0;
  float t = rs_dot(e2, q) * inv_det;
  if (!(t > r.tmin && t < tmax)) return 0;
  *t_out = t;
  *u_out = u;
  *v_out = v;
  return 1;
}


/* ---------------------------------------------------------------------------------------------
 * Robust variant.
 * ------------------------------------------------------------------------------------------- */

/* Double precision for the watertight test's tie-break (Woop et al. 2013, section 3.3): products
 * of two floats are exact in double, so an edge function recomputed in double has the exact sign.
 * Devices without cl_khr_fp64 keep the float value: an edge function that rounds to exactly 0 then
 * counts as "on the edge", which is still watertight (the ray is accepted by both triangles that
 * share the edge, never by neither) but may pick a different one of two equally near triangles
 * than the host reference, which always has double. */
#ifdef __OPENCL_VERSION__
#ifdef cl_khr_fp64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#define RS_HAS_FP64 1
#else
#define RS_HAS_FP64 0
#endif
#else
#define RS_HAS_FP64 1
#endif

/* 1 + 2·γ(3), γ(n) = n·u / (1 − n·u), u = 2^-24: Ize's bound on the relative error of a slab
 * distance (one subtraction and one product with a rounded reciprocal), applied to the far
 * distance so that a ray that touches a box is never rejected (pbrt-v3, section 3.9.2). */
#define RS_SLAB_FAR_SCALE 1.0000003576278687f
/* A direction component below this fraction of the largest one is treated as exactly 0 (ray
 * parallel to that slab), so 1/d stays below 1e20/max|d| and no slab distance can overflow for
 * scene coordinates below 1e18. Over a distance t the ray moves at most t·1e-20·max|d| along that
 * axis, far below the float spacing of anything at distance t. */
#define RS_PARALLEL_FRACTION 1e-20f

/* A ray prepared for the robust variant: the Woop et al. ray-space transform (kz = axis of the
 * largest |d|, kx and ky the others, swapped when d[kz] < 0 to keep the winding; shear sx, sy, sz),
 * the origin permuted to (o[kx], o[ky], o[kz]), and, for the slab test, 1/d per axis with
 * parallel[a] = 1 (and inv_d = 0) where the component is treated as 0. valid = 0 for a zero or
 * non-finite direction, which hits nothing. */
typedef struct {
  float o[3];      /* world-space origin, for the slab test */
  float inv_d[3];  /* 1/d, 0 where parallel */
  rs_i32 parallel[3];
  rs_i32 oblique; /* no axis parallel: the slab test needs no per-axis branch */
  rs_i32 kx, ky, kz;
  float okx, oky, okz; /* origin in the permuted axis order */
  float sx, sy, sz;
  float tmin, tmax;
  rs_i32 valid;
} RsRobustRay;

RS_INLINE RsRobustRay rs_prepare_robust_ray(RsRay ray) {
  RsRobustRay r;
  float ad[3];
  for (int a = 0; a < 3; ++a) {
    r.o[a] = ray.o[a];
    ad[a] = rs_abs(ray.d[a]);
  }
  int kz = ad[0] > ad[1] ? (ad[0] > ad[2] ? 0 : 2) : (ad[1] > ad[2] ? 1 : 2);
  float dmax = ad[kz];
  /* dmax > 0 and finite (NaN fails every comparison; 3.4e38 is the largest finite float). */
  r.valid = dmax > 0.0f && dmax <= 3.4028234e38f;
  float threshold = dmax * RS_PARALLEL_FRACTION;
  for (int a = 0; a < 3; ++a) {
    r.parallel[a] = !(ad[a] > threshold);
    r.inv_d[a] = r.parallel[a] ? 0.0f : 1.0f / ray.d[a];
  }
  r.oblique = !(r.parallel[0] | r.parallel[1] | r.parallel[2]);
  int kx = kz == 2 ? 0 : kz + 1;
  int ky = kx == 2 ? 0 : kx + 1;
  if (ray.d[kz] < 0.0f) {
    int k = kx;
    kx = ky;
    ky = k;
  }
  r.kx = kx;
  r.ky = ky;
  r.kz = kz;
  r.okx = ray.o[kx];
  r.oky = ray.o[ky];
  r.okz = ray.o[kz];
  float dz = r.valid ? ray.d[kz] : 1.0f;
  r.sx = r.valid ? ray.d[kx] / dz : 0.0f;
  r.sy = r.valid ? ray.d[ky] / dz : 0.0f;
  r.sz = 1.0f / dz;
  r.tmin = ray.tmin;
  r.tmax = ray.tmax;
  return r;
}

/* Conservative slab test (Ize 2013): each axis's far distance is scaled by 1 + 2γ(3). An axis
 * the ray is parallel to contributes no distance, only the test bmin <= o <= bmax (inclusive, so
 * a ray grazing a box face or starting on a slab plane stays in). Returns the entry distance and
 * sets *hit when [entry, exit] overlaps [tmin, tmax]. */
RS_FORCE_INLINE float rs_intersect_box_robust(const RsRobustRay* r, RS_GLOBAL const RsBvhNode* n, float tmax,
                                              int* hit) {
  float tnear = r->tmin;
  float tfar = tmax;
  int inside = 1;
  RS_UNROLL
  for (int a = 0; a < 3; ++a) {
    float t0 = (n->bmin[a] - r->o[a]) * r->inv_d[a];
    float t1 = (n->bmax[a] - r->o[a]) * r->inv_d[a];
    if (r->parallel[a]) {
      inside = inside && n->bmin[a] <= r->o[a] && r->o[a] <= n->bmax[a];
    } else {
      tnear = rs_max(tnear, rs_min(t0, t1));
      tfar = rs_min(tfar, rs_max(t0, t1) * RS_SLAB_FAR_SCALE);
    }
  }
  *hit = inside && tnear <= tfar;
  return tnear;
}

/* The rounding error bound of the watertight test's t (Pharr, Jakob & Humphreys, "Physically Based
 * Rendering", 4th ed., section 6.8.4, "Conservative ray–triangle t values"): from the largest
 * ray-space coordinates of the three vertices (x, y after the shear, z scaled by sz), the largest
 * edge function and |det|. A hit at t <= this bound may in truth lie behind the origin: a ray
 * leaving a surface could otherwise hit the triangle it leaves, which the slab test of a tight
 * leaf box happens to hide but a leaf holding a small subtree does not. γ(n) = n·u / (1 − n·u),
 * u = 2^-24. */
#define RS_GAMMA2 1.1920930e-7f
#define RS_GAMMA3 1.7881395e-7f
#define RS_GAMMA5 2.9802326e-7f
#define RS_DEFINE_T_BOUND(NAME, T)                                                                  \
  RS_INLINE T NAME(T max_xt, T max_yt, T max_zt, T max_e, T abs_det) {                              \
    const T delta_z = RS_GAMMA3 * max_zt;                                                           \
    const T delta_x = RS_GAMMA5 * (max_xt + max_zt), delta_y = RS_GAMMA5 * (max_yt + max_zt);       \
    const T delta_e = 2.0f * (RS_GAMMA2 * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);   \
    return 3.0f * (RS_GAMMA3 * max_e * max_zt + delta_e * max_zt + delta_z * max_e) / abs_det;      \
  }
RS_DEFINE_T_BOUND(rs_robust_t_bound, float)  /* one triangle */
RS_DEFINE_T_BOUND(rs4_robust_t_bound, rs_f4) /* four, lane by lane (the packet test) */
RS_DEFINE_T_BOUND(rs8_robust_t_bound, rs_f8) /* eight (the 8-wide BVH's packets, traverse_wide8.h) */
/* RS_DEFINE_T_BOUND stays defined: the ray-packet traversal (traverse_packet.h) makes its own,
 * for the width of its build. */

/* The bound above is a worst case; it grows with the vertices' ray-space extent over |det|, so on a
 * long sliver seen edge-on (a 5 m strip 7 mm tall) it reaches 0.026 for a true t of 0.001 and 13.6
 * for a true t of 10.45, while the float t is off by 1e-4. Rejecting every hit with t <= bound
 * (the rule before issue 23) made the robust variant skip real surfaces right in front of the ray;
 * the exact oracle of `raysort trace --adjudicate` found them. Such a hit is decided again in
 * double (rs_robust_t_in_double); hits beyond their bound keep the float t, as before. */
/* A hit closer to the origin than this many float ulps of the coordinates' magnitude counts as the
 * surface the ray leaves (the origin is rounded onto it): below the exact oracle's tie tolerance
 * of 64 ulps (host/trace/exact_oracle.h), far above the rounding of a ray leaving a surface. */
#define RS_SELF_HIT_ULPS 32.0

#if RS_HAS_FP64
/* The hit's t in double (Möller–Trumbore in world space: differences of floats and their products
 * are exact or nearly so in double, so t is accurate to about 2^-50 relative) for a triangle whose
 * watertight test accepted the ray but whose float t lies within its error bound of the origin;
 * d is the ray's world-space direction (kept out of RsRobustRay: the traversal loops carry that
 * struct in registers, and this path is rare). Returns 1 and *t_out when
 * tmin + (self-hit band) < t and the rounded t lies in (tmin, tmax); the inside/outside decision
 * stays the watertight one. */
RS_INLINE int rs_robust_t_in_double(const RsRobustRay* r, const float* d, float v0x, float v0y, float v0z, float v1x, float v1y,
                                    float v1z, float v2x, float v2y, float v2z, float tmax, float* t_out) {
  const double e1x = (double)v1x - v0x, e1y = (double)v1y - v0y, e1z = (double)v1z - v0z;
  const double e2x = (double)v2x - v0x, e2y = (double)v2y - v0y, e2z = (double)v2z - v0z;
  const double dx = d[0], dy = d[1], dz = d[2];
  const double sx = (double)r->o[0] - v0x, sy = (double)r->o[1] - v0y, sz = (double)r->o[2] - v0z;
  const double px = dy * e2z - dz * e2y, py = dz * e2x - dx * e2z, pz = dx * e2y - dy * e2x;
  const double det = e1x * px + e1y * py + e1z * pz;
  if (det == 0.0) return 0;
  const double qx = sy * e1z - sz * e1y, qy = sz * e1x - sx * e1z, qz = sx * e1y - sy * e1x;
  const double t = (e2x * qx + e2y * qy + e2z * qz) / det;
  /* The self-hit band, in t: RS_SELF_HIT_ULPS ulps of max(|o|, |hit point|), over max |d|. */
  const double ax = fabs(r->o[0] + t * dx), ay = fabs(r->o[1] + t * dy), az = fabs(r->o[2] + t * dz);
  const double mag = fmax(fmax(fmax(ax, ay), az), fmax(fmax(fabs((double)r->o[0]), fabs((double)r->o[1])),
                                                        fabs((double)r->o[2])));
  const double dmax = fmax(fmax(fabs(dx), fabs(dy)), fabs(dz));
  const double band = RS_SELF_HIT_ULPS * 5.9604644775390625e-8 * mag / dmax;
  /* The float t must keep the order the callers rely on (tmin < t < tmax, tmax = the closest hit
   * so far): rounding must not put it on an end. */
  const float ft = (float)t;
  if (!(t > (double)r->tmin + band && ft > r->tmin && ft < tmax)) return 0;
  *t_out = ft;
  return 1;
}
#endif

/* Watertight ray/triangle test (Woop, Benthin & Wald 2013), two-sided. The vertices are moved to
 * ray space (translate by the origin, permute, shear so the ray runs along +z); the 2-D edge
 * functions U, V, W of the sheared vertices then decide inside/outside. A vertex shared by two
 * triangles is transformed to the same floats in both, so an edge's functions agree in sign across
 * the edge; an edge function that rounds to exactly 0 is recomputed in double, where it is exact.
 * Accepts when U, V, W do not have mixed signs; det = U + V + W == 0 (ray in the triangle's plane,
 * or a degenerate triangle) never hits. t = T / det is bounded by the triangle's ray-space depth
 * because U, V, W share a sign, so no division can overflow. */
RS_INLINE int rs_intersect_triangle_robust(const RsRobustRay* r, const float* d, RS_GLOBAL const RsTriangle* tri,
                                           float tmax, float* t_out, float* u_out, float* v_out) {
  const int kx = r->kx, ky = r->ky, kz = r->kz;
  const float az0 = tri->v0[kz] - r->okz, bz0 = tri->v1[kz] - r->okz, cz0 = tri->v2[kz] - r->okz;
  const float ax = (tri->v0[kx] - r->okx) - r->sx * az0, ay = (tri->v0[ky] - r->oky) - r->sy * az0;
  const float bx = (tri->v1[kx] - r->okx) - r->sx * bz0, by = (tri->v1[ky] - r->oky) - r->sy * bz0;
  const float cx = (tri->v2[kx] - r->okx) - r->sx * cz0, cy = (tri->v2[ky] - r->oky) - r->sy * cz0;
  float u = cx * by - cy * bx;
  float v = ax * cy - ay * cx;
  float w = bx * ay - by * ax;
#if RS_HAS_FP64
  if (u == 0.0f || v == 0.0f || w == 0.0f) {
    u = (float)((double)cx * (double)by - (double)cy * (double)bx);
    v = (float)((double)ax * (double)cy - (double)ay * (double)cx);
    w = (float)((double)bx * (double)ay - (double)by * (double)ax);
  }
#endif
  if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return 0;
  const float det = u + v + w;
  if (det == 0.0f) return 0;
  const float azt = r->sz * az0, bzt = r->sz * bz0, czt = r->sz * cz0;
  const float t_scaled = u * azt + v * bzt + w * czt;
  float t = t_scaled / det;
  if (!(t > r->tmin && t < tmax)) return 0;
  {
    const float max_xt = rs_max(rs_max(rs_abs(ax), rs_abs(bx)), rs_abs(cx));
    const float max_yt = rs_max(rs_max(rs_abs(ay), rs_abs(by)), rs_abs(cy));
    const float max_zt = rs_max(rs_max(rs_abs(azt), rs_abs(bzt)), rs_abs(czt));
    const float max_e = rs_max(rs_max(rs_abs(u), rs_abs(v)), rs_abs(w));
    if (!(t > rs_robust_t_bound(max_xt, max_yt, max_zt, max_e, rs_abs(det)))) {
#if RS_HAS_FP64
      if (!rs_robust_t_in_double(r, d, tri->v0[0], tri->v0[1], tri->v0[2], tri->v1[0], tri->v1[1], tri->v1[2], tri->v2[0],
                                 tri->v2[1], tri->v2[2], tmax, &t))
        return 0;
#else
      return 0;
#endif
    }
  }
  /* A zero-area triangle can still pass the test above: the shear rounds its collinear vertices
   * apart. Reject it by its world-space cross product, exact in double (differences and products
   * of floats are exact there); only hits that would be accepted pay for this. */
#if RS_HAS_FP64
  {
    const double a1x = (double)tri->v1[0] - (double)tri->v0[0], a1y = (double)tri->v1[1] - (double)tri->v0[1],
                 a1z = (double)tri->v1[2] - (double)tri->v0[2];
    const double a2x = (double)tri->v2[0] - (double)tri->v0[0], a2y = (double)tri->v2[1] - (double)tri->v0[1],
                 a2z = (double)tri->v2[2] - (double)tri->v0[2];
    if (a1y * a2z - a1z * a2y == 0.0 && a1z * a2x - a1x * a2z == 0.0 && a1x * a2y - a1y * a2x == 0.0) return 0;
  }
#else
  const float e1x = tri->v1[0] - tri->v0[0], e1y = tri->v1[1] - tri->v0[1], e1z = tri->v1[2] - tri->v0[2];
  const float e2x = tri->v2[0] - tri->v0[0], e2y = tri->v2[1] - tri->v0[1], e2z = tri->v2[2] - tri->v0[2];
  if (e1y * e2z - e1z * e2y == 0.0f && e1z * e2x - e1x * e2z == 0.0f && e1x * e2y - e1y * e2x == 0.0f) return 0;
#endif
  /* Barycentrics of the hit record: u weights v1, v weights v2 (p = (1-u-v)·v0 + u·v1 + v·v2). */
  *t_out = t;
  *u_out = v / det;
  *v_out = w / det;
  return 1;
}

/* Triangle `tri` against the ray in the variant (fast: r; robust: rr and the ray's direction d),
 * within (tmin, hit->t): on a hit, *hit becomes it (t, the triangle's id, u, v) and 1 is returned.
 * What every single-ray leaf of the binary tree's triangles does (traverse_binary.h,
 * traverse_binary_ww.h, traverse_cwbvh.h). */
RS_INLINE int rs_take_triangle(RsTraversalRay r, const RsRobustRay* rr, const float* d, RS_GLOBAL const RsTriangle* tri,
                               int robust, RsHit* hit) {
  float t, u, v;
  const int found = robust ? rs_intersect_triangle_robust(rr, d, tri, hit->t, &t, &u, &v)
                           : rs_intersect_triangle(r, tri, hit->t, &t, &u, &v);
  if (found) {
    hit->t = t;
    hit->tri = tri->id;
    hit->u = u;
    hit->v = v;
  }
  return found;
}

#endif /* RAYSORT_INTERSECT_H */
