/* raysort — BVH traversal and intersection, shared by cl/trace.cl and the host reference
 * (host/trace/reference.cpp). One source, so the host twin runs the same arithmetic in the same
 * order as the kernel; tests check that PoCL and the host compiler agree bit for bit.
 *
 * Algorithm: stack-based traversal of a binary BVH, one ray per work-item, nearest child first
 * (Aila & Laine 2009, "Understanding the Efficiency of Ray Traversal on GPUs", the "while-while"
 * loop without persistent threads). Two variants share the loop (DESIGN.md section 3, docs/trace.md):
 *  - fast:   slab test for boxes (Kay & Kajiya 1986, as in Williams et al. 2005) and Möller–Trumbore
 *            for triangles (1997) — the usual GPU choice;
 *  - robust: watertight ray/triangle test (Woop, Benthin & Wald 2013, JCGT 2(1)) and a conservative
 *            slab test (Ize 2013, "Robust BVH Ray Traversal", JCGT 2(2)); no inf arithmetic, and
 *            zero direction components handled without a division.
 * The variant is an int argument (OpenCL C has no templates); the kernels pass a constant, so each
 * kernel compiles to one variant only.
 */
#ifndef RAYSORT_TRAVERSE_H
#define RAYSORT_TRAVERSE_H

#include "shared.h"

/* A ray prepared for traversal: origin, direction and per-axis reciprocal direction. */
typedef struct {
  RsVec3 o;
  RsVec3 d;
  RsVec3 inv_d;
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
 * NaN ever enters the slab test (the kernels must not depend on inf arithmetic). */
RS_INLINE float rs_safe_rcp(float d) {
  const float tiny = 1e-30f;
  float ad = rs_abs(d);
  float sd = ad < tiny ? (d < 0.0f || (d == 0.0f && rs_float_as_int(d) < 0) ? -tiny : tiny) : d;
  return 1.0f / sd;
}

RS_INLINE RsTraversalRay rs_prepare_ray(RsRay r) {
  RsTraversalRay t;
  t.o = rs_vec3(r.o[0], r.o[1], r.o[2]);
  t.d = rs_vec3(r.d[0], r.d[1], r.d[2]);
  t.inv_d = rs_vec3(rs_safe_rcp(r.d[0]), rs_safe_rcp(r.d[1]), rs_safe_rcp(r.d[2]));
  t.tmin = r.tmin;
  t.tmax = r.tmax;
  return t;
}

/* Slab test: returns the entry distance and sets *hit when [entry, exit] overlaps [tmin, tmax]. */
RS_INLINE float rs_intersect_box(RsTraversalRay r, RS_GLOBAL const RsBvhNode* n, float tmax, int* hit) {
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
RS_INLINE float rs_intersect_box_robust(const RsRobustRay* r, RS_GLOBAL const RsBvhNode* n, float tmax, int* hit) {
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
#undef RS_DEFINE_T_BOUND

/* Watertight ray/triangle test (Woop, Benthin & Wald 2013), two-sided. The vertices are moved to
 * ray space (translate by the origin, permute, shear so the ray runs along +z); the 2-D edge
 * functions U, V, W of the sheared vertices then decide inside/outside. A vertex shared by two
 * triangles is transformed to the same floats in both, so an edge's functions agree in sign across
 * the edge; an edge function that rounds to exactly 0 is recomputed in double, where it is exact.
 * Accepts when U, V, W do not have mixed signs; det = U + V + W == 0 (ray in the triangle's plane,
 * or a degenerate triangle) never hits. t = T / det is bounded by the triangle's ray-space depth
 * because U, V, W share a sign, so no division can overflow. */
RS_INLINE int rs_intersect_triangle_robust(const RsRobustRay* r, RS_GLOBAL const RsTriangle* tri, float tmax,
                                           float* t_out, float* u_out, float* v_out) {
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
  const float t = t_scaled / det;
  if (!(t > r->tmin && t < tmax)) return 0;
  {
    const float max_xt = rs_max(rs_max(rs_abs(ax), rs_abs(bx)), rs_abs(cx));
    const float max_yt = rs_max(rs_max(rs_abs(ay), rs_abs(by)), rs_abs(cy));
    const float max_zt = rs_max(rs_max(rs_abs(azt), rs_abs(bzt)), rs_abs(czt));
    const float max_e = rs_max(rs_max(rs_abs(u), rs_abs(v)), rs_abs(w));
    if (!(t > rs_robust_t_bound(max_xt, max_yt, max_zt, max_e, rs_abs(det)))) return 0;
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

/* Closest hit (any_hit = 0) or first hit found (any_hit = 1, shadow rays), fast (robust = 0) or
 * robust (robust = 1) variant.
 * *node_visits, when not null, counts the nodes whose box was fetched (for cost heatmaps).
 * trail, when not null, receives the id of every node the loop steps through, in order, up to
 * trail_cap entries; *trail_len gets the full step count (the SIMT model, host only: kernels pass
 * null and the compiler drops the recording). */
RS_INLINE RsHit rs_traverse_variant_recorded(RS_GLOBAL const RsBvhNode* nodes, RS_GLOBAL const RsTriangle* tris,
                                             RsRay ray, int robust, int any_hit, rs_u32* node_visits, rs_u32* trail,
                                             rs_u32 trail_cap, rs_u32* trail_len) {
  rs_u32 steps = 0;
  RsTraversalRay r = rs_prepare_ray(ray);
  RsRobustRay rr = rs_prepare_robust_ray(ray);
  RsHit hit = rs_miss(ray.tmax);
  rs_u32 visits = 1;

  int root_hit;
  if (robust)
    rs_intersect_box_robust(&rr, &nodes[0], hit.t, &root_hit);
  else
    rs_intersect_box(r, &nodes[0], hit.t, &root_hit);
  if (robust && !rr.valid) root_hit = 0;
  if (!root_hit) {
    if (node_visits) *node_visits = visits;
    if (trail_len) *trail_len = 0;
    return hit;
  }

  rs_u32 stack[RS_STACK_SIZE];
  int sp = 0;
  rs_u32 node = 0;
  for (;;) {
    RS_GLOBAL const RsBvhNode* n = &nodes[node];
    if (trail && steps < trail_cap) trail[steps] = node;
    ++steps;
    if (n->count > 0) {
      for (rs_u32 i = n->first; i < n->first + n->count; ++i) {
        float t, u, v;
        int found = robust ? rs_intersect_triangle_robust(&rr, &tris[i], hit.t, &t, &u, &v)
                           : rs_intersect_triangle(r, &tris[i], hit.t, &t, &u, &v);
        if (found) {
          hit.t = t;
          hit.tri = tris[i].id;
          hit.u = u;
          hit.v = v;
          if (any_hit) {
            if (node_visits) *node_visits = visits;
            if (trail_len) *trail_len = steps;
            return hit;
          }
        }
      }
    } else {
      rs_u32 left = n->first;
      int hit_l, hit_r;
      float t_l = robust ? rs_intersect_box_robust(&rr, &nodes[left], hit.t, &hit_l)
                         : rs_intersect_box(r, &nodes[left], hit.t, &hit_l);
      float t_r = robust ? rs_intersect_box_robust(&rr, &nodes[left + 1], hit.t, &hit_r)
                         : rs_intersect_box(r, &nodes[left + 1], hit.t, &hit_r);
      visits += 2;
      if (hit_l && hit_r) {
        /* Nearest child first; ties go left so the order is fixed. */
        rs_u32 near_child = t_r < t_l ? left + 1 : left;
        stack[sp++] = near_child == left ? left + 1 : left;
        node = near_child;
        continue;
      }
      if (hit_l) {
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
  if (node_visits) *node_visits = visits;
  if (trail_len) *trail_len = steps;
  return hit;
}

/* The fast variant with a trail (the SIMT model, host/bench/metrics.cpp). */
RS_INLINE RsHit rs_traverse_recorded(RS_GLOBAL const RsBvhNode* nodes, RS_GLOBAL const RsTriangle* tris, RsRay ray,
                                     int any_hit, rs_u32* node_visits, rs_u32* trail, rs_u32 trail_cap,
                                     rs_u32* trail_len) {
  return rs_traverse_variant_recorded(nodes, tris, ray, 0, any_hit, node_visits, trail, trail_cap, trail_len);
}

RS_INLINE RsHit rs_traverse(RS_GLOBAL const RsBvhNode* nodes, RS_GLOBAL const RsTriangle* tris, RsRay ray, int any_hit,
                            rs_u32* node_visits) {
  return rs_traverse_variant_recorded(nodes, tris, ray, 0, any_hit, node_visits, 0, 0, 0);
}

RS_INLINE RsHit rs_traverse_robust(RS_GLOBAL const RsBvhNode* nodes, RS_GLOBAL const RsTriangle* tris, RsRay ray,
                                   int any_hit, rs_u32* node_visits) {
  return rs_traverse_variant_recorded(nodes, tris, ray, 1, any_hit, node_visits, 0, 0, 0);
}

/* ---------------------------------------------------------------------------------------------
 * 4-wide BVH traversal: what the trace kernels run (docs/trace.md, "Trace kernel").
 *
 * The binary BVH above stays the reference structure (HCC cuts, the SIMT model's trail); for
 * speed the kernels walk the same tree collapsed to four children per node (host/bvh/wide.cpp),
 * testing the four child boxes, and four triangles of a leaf, with one vector operation each —
 * the single-ray wide-BVH scheme of Embree (Wald et al. 2014) written with OpenCL vector types,
 * which PoCL maps to SSE/AVX and GPUs to plain scalar code. Per lane the arithmetic is that of
 * the binary traversal's tests (Möller–Trumbore / Woop et al. and the slab tests above), so a
 * triangle is hit or missed exactly as there; only which of two equally near triangles wins may
 * differ, because the visiting order differs.
 * ------------------------------------------------------------------------------------------- */

/* Slab test of a node's four child boxes (fast variant). The near plane of each axis is chosen by
 * the sign of 1/d once, instead of min/max per box (lo <= hi, so the result is the same).
 * Returns the hit lanes (with the node's valid lanes) and each box's entry distance. */
RS_INLINE rs_i4 rs_wide_boxes(RsTraversalRay r, RS_GLOBAL const RsWideNode* n, float tmax, rs_f4* tnear_out) {
  RS_GLOBAL const rs_f4* b = &n->lo_x; /* lo_x hi_x lo_y hi_y lo_z hi_z */
  const int nx = r.inv_d.x < 0.0f, ny = r.inv_d.y < 0.0f, nz = r.inv_d.z < 0.0f;
  rs_f4 tnx = (b[nx] - r.o.x) * r.inv_d.x, tfx = (b[1 - nx] - r.o.x) * r.inv_d.x;
  rs_f4 tny = (b[2 + ny] - r.o.y) * r.inv_d.y, tfy = (b[3 - ny] - r.o.y) * r.inv_d.y;
  rs_f4 tnz = (b[4 + nz] - r.o.z) * r.inv_d.z, tfz = (b[5 - nz] - r.o.z) * r.inv_d.z;
  rs_f4 tnear = rs4_max(rs4_max(tnx, tny), rs4_max(tnz, rs4_splat(r.tmin)));
  rs_f4 tfar = rs4_min(rs4_min(tfx, tfy), rs4_min(tfz, rs4_splat(tmax)));
  *tnear_out = tnear;
  return (tnear <= tfar) & n->valid;
}

/* The conservative slab test (Ize 2013, as rs_intersect_box_robust) on four boxes. Most rays have
 * no parallel axis (r->oblique) and skip the per-axis branch; the axis loop is unrolled, so a
 * ray's per-axis values stay in registers across the traversal instead of being re-read and
 * re-broadcast from the ray struct on every visit (docs/trace.md: 0.79–0.91x the time). */
RS_INLINE rs_i4 rs_wide_boxes_robust(const RsRobustRay* r, RS_GLOBAL const RsWideNode* n, float tmax,
                                     rs_f4* tnear_out) {
  RS_GLOBAL const rs_f4* b = &n->lo_x;
  rs_f4 tnear = rs4_splat(r->tmin);
  rs_f4 tfar = rs4_splat(tmax);
  rs_i4 inside = n->valid;
  RS_UNROLL
  for (int a = 0; a < 3; ++a) {
    if (!r->oblique && r->parallel[a]) {
      inside = inside & (b[2 * a] <= r->o[a]) & (b[2 * a + 1] >= r->o[a]);
      continue;
    }
    const int neg = r->inv_d[a] < 0.0f;
    rs_f4 t0 = (b[2 * a + neg] - r->o[a]) * r->inv_d[a];
    rs_f4 t1 = (b[2 * a + 1 - neg] - r->o[a]) * r->inv_d[a];
    tnear = rs4_max(tnear, t0);
    tfar = rs4_min(tfar, t1 * RS_SLAB_FAR_SCALE);
  }
  *tnear_out = tnear;
  return inside & (tnear <= tfar);
}

/* Möller–Trumbore on a packet of four triangles: per lane the operations of rs_intersect_triangle
 * in the same order. Returns the bits of the lanes hit within (tmin, tmax), with t, u, v per lane. */
RS_INLINE int rs_packet_intersect(RsTraversalRay r, RS_GLOBAL const RsTriPacket* p, float tmax, rs_f4* t_out,
                                  rs_f4* u_out, rs_f4* v_out) {
  const rs_f4 v0x = p->v0x, v0y = p->v0y, v0z = p->v0z;
  const rs_f4 e1x = p->v1x - v0x, e1y = p->v1y - v0y, e1z = p->v1z - v0z;
  const rs_f4 e2x = p->v2x - v0x, e2y = p->v2y - v0y, e2z = p->v2z - v0z;
  const rs_f4 px = r.d.y * e2z - r.d.z * e2y, py = r.d.z * e2x - r.d.x * e2z, pz = r.d.x * e2y - r.d.y * e2x;
  const rs_f4 det = e1x * px + e1y * py + e1z * pz;
  int bits = rs4_bits(p->valid & (det != 0.0f));
  if (!bits) return 0;
  /* Lanes with det == 0 divide by 1 instead (and stay rejected): no inf in any lane. */
  const rs_f4 inv_det = rs4_splat(1.0f) / rs4_select(det, rs4_splat(1.0f), det == 0.0f);
  const rs_f4 sx = r.o.x - v0x, sy = r.o.y - v0y, sz = r.o.z - v0z;
  const rs_f4 u = (sx * px + sy * py + sz * pz) * inv_det;
  bits &= rs4_bits((u >= 0.0f) & (u <= 1.0f));
  if (!bits) return 0;
  const rs_f4 qx = sy * e1z - sz * e1y, qy = sz * e1x - sx * e1z, qz = sx * e1y - sy * e1x;
  const rs_f4 v = (r.d.x * qx + r.d.y * qy + r.d.z * qz) * inv_det;
  bits &= rs4_bits((v >= 0.0f) & (u + v <= 1.0f));
  if (!bits) return 0;
  const rs_f4 t = (e2x * qx + e2y * qy + e2z * qz) * inv_det;
  bits &= rs4_bits((t > r.tmin) & (t < tmax));
  *t_out = t;
  *u_out = u;
  *v_out = v;
  return bits;
}

/* The watertight test (Woop et al. 2013, as rs_intersect_triangle_robust) on a packet of four
 * triangles. The exact zero-area check is the packet's precomputed nondegenerate mask. */
RS_INLINE int rs_packet_intersect_robust(const RsRobustRay* r, RS_GLOBAL const RsTriPacket* p, float tmax,
                                         rs_f4* t_out, rs_f4* u_out, rs_f4* v_out) {
  RS_GLOBAL const rs_f4* p0 = &p->v0x; /* v0x v0y v0z, then v1, then v2 */
  RS_GLOBAL const rs_f4* p1 = &p->v1x;
  RS_GLOBAL const rs_f4* p2 = &p->v2x;
  const int kx = r->kx, ky = r->ky, kz = r->kz;
  const rs_f4 az = p0[kz] - r->okz, bz = p1[kz] - r->okz, cz = p2[kz] - r->okz;
  rs_f4 ax = (p0[kx] - r->okx) - r->sx * az, ay = (p0[ky] - r->oky) - r->sy * az;
  rs_f4 bx = (p1[kx] - r->okx) - r->sx * bz, by = (p1[ky] - r->oky) - r->sy * bz;
  rs_f4 cx = (p2[kx] - r->okx) - r->sx * cz, cy = (p2[ky] - r->oky) - r->sy * cz;
  rs_f4 u = cx * by - cy * bx;
  rs_f4 v = ax * cy - ay * cx;
  rs_f4 w = bx * ay - by * ax;
#if RS_HAS_FP64
  {
    /* An edge function that rounded to 0: recompute that lane's three in double (exact). */
    const int zero = rs4_bits(p->valid & ((u == 0.0f) | (v == 0.0f) | (w == 0.0f)));
    if (zero) {
      float fax[4], fay[4], fbx[4], fby[4], fcx[4], fcy[4], fu[4], fv[4], fw[4];
      rs4_store(ax, fax);
      rs4_store(ay, fay);
      rs4_store(bx, fbx);
      rs4_store(by, fby);
      rs4_store(cx, fcx);
      rs4_store(cy, fcy);
      rs4_store(u, fu);
      rs4_store(v, fv);
      rs4_store(w, fw);
      for (int i = 0; i < 4; ++i) {
        if (!((zero >> i) & 1)) continue;
        fu[i] = (float)((double)fcx[i] * (double)fby[i] - (double)fcy[i] * (double)fbx[i]);
        fv[i] = (float)((double)fax[i] * (double)fcy[i] - (double)fay[i] * (double)fcx[i]);
        fw[i] = (float)((double)fbx[i] * (double)fay[i] - (double)fby[i] * (double)fax[i]);
      }
      u = rs4_load(fu);
      v = rs4_load(fv);
      w = rs4_load(fw);
    }
  }
#endif
  const int mixed = rs4_bits((u < 0.0f) | (v < 0.0f) | (w < 0.0f)) & rs4_bits((u > 0.0f) | (v > 0.0f) | (w > 0.0f));
  const rs_f4 det = u + v + w;
  int bits = rs4_bits(p->valid & p->nondegenerate & (det != 0.0f)) & ~mixed;
  if (!bits) return 0;
  const rs_f4 safe_det = rs4_select(det, rs4_splat(1.0f), det == 0.0f);
  const rs_f4 azt = r->sz * az, bzt = r->sz * bz, czt = r->sz * cz;
  const rs_f4 t = (u * azt + v * bzt + w * czt) / safe_det;
  bits &= rs4_bits((t > r->tmin) & (t < tmax));
  if (!bits) return 0;
  {
    const rs_f4 max_xt = rs4_max(rs4_max(rs4_abs(ax), rs4_abs(bx)), rs4_abs(cx));
    const rs_f4 max_yt = rs4_max(rs4_max(rs4_abs(ay), rs4_abs(by)), rs4_abs(cy));
    const rs_f4 max_zt = rs4_max(rs4_max(rs4_abs(azt), rs4_abs(bzt)), rs4_abs(czt));
    const rs_f4 max_e = rs4_max(rs4_max(rs4_abs(u), rs4_abs(v)), rs4_abs(w));
    bits &= rs4_bits(t > rs4_robust_t_bound(max_xt, max_yt, max_zt, max_e, rs4_abs(safe_det)));
  }
  *t_out = t;
  *u_out = v / safe_det;
  *v_out = w / safe_det;
  return bits;
}

/* Closest hit (any_hit = 0) or first hit found (any_hit = 1), fast (robust = 0) or robust
 * (robust = 1), on the 4-wide BVH. Nearest child first: a node's hit children are ordered by
 * entry distance (ties by lane), the nearest is visited next and the others pushed with their
 * distance, so a popped subtree that starts beyond the closest hit so far is skipped. Any-hit
 * rays skip the ordering (children in lane order): measured side by side on sibenik's bounce-1
 * shadow rays, 1.13-1.15x faster; primary shadow rays within 2-4 %.
 * *node_visits, when not null, counts the wide nodes and leaves visited (cost heatmaps).
 * Stack bound: RS_WIDE_STACK_SIZE (cl/shared.h). */
RS_INLINE RsHit rs_traverse_wide(RS_GLOBAL const RsWideNode* nodes, RS_GLOBAL const RsTriPacket* packets, RsRay ray,
                                 int robust, int any_hit, rs_u32* node_visits) {
  RsTraversalRay r = rs_prepare_ray(ray);
  RsRobustRay rr = rs_prepare_robust_ray(ray);
  RsHit hit = rs_miss(ray.tmax);
  rs_u32 visits = 0;
  rs_u32 stack[RS_WIDE_STACK_SIZE];
  float stack_t[RS_WIDE_STACK_SIZE];
  int sp = 0;
  rs_u32 ref = 0; /* the root is always an inner node */
  int live = !robust || rr.valid;
  while (live) {
    ++visits;
    if (!(ref & RS_WIDE_LEAF)) {
      RS_GLOBAL const RsWideNode* n = &nodes[ref];
      rs_f4 tnear4;
      const int bits = rs4_bits(robust ? rs_wide_boxes_robust(&rr, n, hit.t, &tnear4) : rs_wide_boxes(r, n, hit.t, &tnear4));
      if (bits && any_hit) {
        /* Shadow rays stop at any hit: visit children in lane order, no sorting. */
        int rest = bits & (bits - 1);
        ref = n->child[rs_lowest_bit(bits)];
        while (rest) {
          stack[sp] = n->child[rs_lowest_bit(rest)];
          stack_t[sp] = r.tmin;
          ++sp;
          rest &= rest - 1;
        }
        continue;
      }
      if (bits) {
        float tnear[4];
        rs4_store(tnear4, tnear);
        rs_u32 refs[4];
        float dist[4];
        int k = 0;
        for (int i = 0; i < 4; ++i) {
          if (!((bits >> i) & 1)) continue;
          int j = k++;
          for (; j > 0 && dist[j - 1] > tnear[i]; --j) {
            dist[j] = dist[j - 1];
            refs[j] = refs[j - 1];
          }
          dist[j] = tnear[i];
          refs[j] = n->child[i];
        }
        for (int j = k - 1; j > 0; --j) {
          stack[sp] = refs[j];
          stack_t[sp] = dist[j];
          ++sp;
        }
        ref = refs[0];
        continue;
      }
    } else {
      const rs_u32 first = (ref & ~RS_WIDE_LEAF) >> 2, end = first + (ref & 3u) + 1u;
      for (rs_u32 pi = first; pi < end; ++pi) {
        rs_f4 t4, u4, v4;
        const int bits = robust ? rs_packet_intersect_robust(&rr, &packets[pi], hit.t, &t4, &u4, &v4)
                                : rs_packet_intersect(r, &packets[pi], hit.t, &t4, &u4, &v4);
        if (!bits) continue;
        float ts[4], us[4], vs[4];
        rs4_store(t4, ts);
        rs4_store(u4, us);
        rs4_store(v4, vs);
        int best = -1;
        float best_t = hit.t;
        for (int i = 0; i < 4; ++i)
          if (((bits >> i) & 1) && ts[i] < best_t) {
            best_t = ts[i];
            best = i;
          }
        hit.t = best_t;
        hit.tri = packets[pi].id[best];
        hit.u = us[best];
        hit.v = vs[best];
        if (any_hit) {
          live = 0;
          break;
        }
      }
      if (!live) break;
    }
    /* Next: the nearest pending subtree that can still hold a closer hit. */
    live = 0;
    while (sp > 0) {
      --sp;
      if (stack_t[sp] <= hit.t) {
        ref = stack[sp];
        live = 1;
        break;
      }
    }
  }
  if (node_visits) *node_visits = visits;
  return hit;
}

#endif /* RAYSORT_TRAVERSE_H */
