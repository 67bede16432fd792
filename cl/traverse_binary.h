/* raysort — traversal of the binary BVH (bvh_layout.h, RsBvhNode): the reference structure. The
 * host twin uses it for the SIMT model's trails, `raysort trace --layout binary` runs it on the
 * device, and it is what the 4-wide traversal (traverse_wide.h) must agree with.
 *
 * Algorithm: stack-based traversal, one ray per work-item, nearest child first (Aila & Laine 2009,
 * "Understanding the Efficiency of Ray Traversal on GPUs"), with the tests of intersect.h. Its loop
 * is their "if-if" form (one iteration per node, inner or leaf), not the "while-while" form of their
 * CUDA kernels, which traverse_binary_ww.h writes out (the binary-ww class: the same nodes in the
 * same order). The variant is an int argument (OpenCL C has
 * no templates); the kernels pass a constant, so each kernel compiles to one variant only.
 */
#ifndef RAYSORT_TRAVERSE_BINARY_H
#define RAYSORT_TRAVERSE_BINARY_H

#include "intersect.h"

/* The variant argument of rs_traverse_variant_recorded beyond fast (0) and robust (1): the fast variant
 * with the encoders' unfused box test (rs_intersect_box_unfused), for the node traffic the learned
 * encoders read (host/trace/tracer.cpp, node_traffic), so that their keys keep their bits. */
#define RS_VARIANT_FAST_UNFUSED 2

/* A child's box test in the variant (0, 1 or RS_VARIANT_FAST_UNFUSED): entry distance and *hit. */
RS_INLINE float rs_binary_box(RS_GLOBAL const RsBvhNode* n, RsTraversalRay r, const RsRobustRay* rr, int variant,
                              float tmax, int* hit) {
  return variant == 1                         ? rs_intersect_box_robust(rr, n, tmax, hit)
         : variant == RS_VARIANT_FAST_UNFUSED ? rs_intersect_box_unfused(r, n, tmax, hit)
                                              : rs_intersect_box(r, n, tmax, hit);
}

/* Whether the ray enters the root's box (and, robust, has a valid direction): where the binary
 * traversals start (this one and the while-while one, traverse_binary_ww.h). variant as rs_binary_box's. */
RS_INLINE int rs_binary_root_entered(RS_GLOBAL const RsBvhNode* nodes, RsTraversalRay r, const RsRobustRay* rr, int variant,
                                     float tmax) {
  int hit;
  rs_binary_box(&nodes[0], r, rr, variant, tmax, &hit);
  return hit && (variant != 1 || rr->valid);
}

/* Closest hit (any_hit = 0) or first hit found (any_hit = 1, shadow rays), fast (variant = 0) or
 * robust (variant = 1), or the fast one with the encoders' box test (RS_VARIANT_FAST_UNFUSED).
 * *node_visits, when not null, counts the nodes whose box was fetched (for cost heatmaps).
 * trail, when not null, receives the id of every node the loop steps through, in order, up to
 * trail_cap entries; *trail_len gets the full step count (the SIMT model, host only: kernels pass
 * null and the compiler drops the recording). */
RS_INLINE RsHit rs_traverse_variant_recorded(RS_GLOBAL const RsBvhNode* nodes, RS_GLOBAL const RsTriangle* tris,
                                             RsRay ray, int variant, int any_hit, rs_u32* node_visits, rs_u32* trail,
                                             rs_u32 trail_cap, rs_u32* trail_len) {
  rs_u32 steps = 0;
  RsTraversalRay r = rs_prepare_ray(ray);
  RsRobustRay rr = rs_prepare_robust_ray(ray);
  RsHit hit = rs_miss(ray.tmax);
  rs_u32 visits = 1;

  const int robust = variant == 1; /* the triangle test's variant */
  if (!rs_binary_root_entered(nodes, r, &rr, variant, hit.t)) {
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
        if (rs_take_triangle(r, &rr, ray.d, &tris[i], robust, &hit) && any_hit) {
          if (node_visits) *node_visits = visits;
          if (trail_len) *trail_len = steps;
          return hit;
        }
      }
    } else {
      rs_u32 left = n->first;
      int hit_l, hit_r;
      float t_l = rs_binary_box(&nodes[left], r, &rr, variant, hit.t, &hit_l);
      float t_r = rs_binary_box(&nodes[left + 1], r, &rr, variant, hit.t, &hit_r);
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
  return rs_traverse_variant_recorded(nodes, tris, ray, 0, any_hit, node_visits, 0, 0, 0);
}

RS_INLINE RsHit rs_traverse_robust(RS_GLOBAL const RsBvhNode* nodes, RS_GLOBAL const RsTriangle* tris, RsRay ray,
                                   int any_hit, rs_u32* node_visits) {
  return rs_traverse_variant_recorded(nodes, tris, ray, 1, any_hit, node_visits, 0, 0, 0);
}

#endif /* RAYSORT_TRAVERSE_BINARY_H */
