/* raysort — BVH traversal and intersection, shared by cl/trace.cl and the host reference
 * (host/trace/reference.cpp). One source, so the host twin runs the same arithmetic in the same
 * order as the kernel; tests check that PoCL and the host compiler agree bit for bit.
 *
 * Algorithm: stack-based traversal of a binary BVH, one ray per work-item, nearest child first
 * (Aila & Laine 2009, "Understanding the Efficiency of Ray Traversal on GPUs", the "while-while"
 * loop without persistent threads). Slab test for boxes (Kay & Kajiya 1986, as in Williams et al.
 * 2005) and Möller–Trumbore for triangles (1997): the fast variant of DESIGN.md section 3.
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

/* Closest hit (any_hit = 0) or first hit found (any_hit = 1, shadow rays).
 * *node_visits, when not null, counts the nodes whose box was fetched (for cost heatmaps).
 * trail, when not null, receives the id of every node the loop steps through, in order, up to
 * trail_cap entries; *trail_len gets the full step count (the SIMT model, host only: kernels pass
 * null and the compiler drops the recording). */
RS_INLINE RsHit rs_traverse_recorded(RS_GLOBAL const RsBvhNode* nodes, RS_GLOBAL const RsTriangle* tris, RsRay ray,
                                     int any_hit, rs_u32* node_visits, rs_u32* trail, rs_u32 trail_cap,
                                     rs_u32* trail_len) {
  rs_u32 steps = 0;
  RsTraversalRay r = rs_prepare_ray(ray);
  RsHit hit;
  hit.t = ray.tmax;
  hit.tri = RS_NO_HIT;
  hit.u = 0.0f;
  hit.v = 0.0f;
  rs_u32 visits = 1;

  int root_hit;
  rs_intersect_box(r, &nodes[0], hit.t, &root_hit);
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
        if (rs_intersect_triangle(r, &tris[i], hit.t, &t, &u, &v)) {
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
      float t_l = rs_intersect_box(r, &nodes[left], hit.t, &hit_l);
      float t_r = rs_intersect_box(r, &nodes[left + 1], hit.t, &hit_r);
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

RS_INLINE RsHit rs_traverse(RS_GLOBAL const RsBvhNode* nodes, RS_GLOBAL const RsTriangle* tris, RsRay ray, int any_hit,
                            rs_u32* node_visits) {
  return rs_traverse_recorded(nodes, tris, ray, any_hit, node_visits, 0, 0, 0);
}

#endif /* RAYSORT_TRAVERSE_H */
