/* raysort — the binary BVH walked in the loop form of the paper's CUDA kernels: "while-while"
 * (Aila and Laine 2009, "Understanding the Efficiency of Ray Traversal on GPUs", section 3): per
 * ray, an inner loop over inner nodes until the ray reaches a leaf, then an inner loop over leaves
 * until an inner node comes up again, and around them the loop that runs until the stack is empty.
 * The binary class (traverse_binary.h) is the other form of that paper, "if-if": one iteration
 * per node, inner or leaf. Both visit the same nodes in the same order (nearest child first, ties
 * left), so the hits, bit for bit, and the visit counts are the same; only how the lanes of a warp
 * wait for each other differs, which is what the GPU model's while-while count (gpu_ww_steps,
 * docs/gpu-model.md) prices. On a CPU the form only changes the code's layout (issue 46, item 2).
 */
#ifndef RAYSORT_TRAVERSE_BINARY_WW_H
#define RAYSORT_TRAVERSE_BINARY_WW_H

#include "traverse_binary.h"

RS_INLINE RsHit rs_traverse_binary_ww(RS_GLOBAL const RsBvhNode* nodes, RS_GLOBAL const RsTriangle* tris, RsRay ray,
                                      int robust, int any_hit, rs_u32* node_visits) {
  const RsTraversalRay r = rs_prepare_ray(ray);
  const RsRobustRay rr = rs_prepare_robust_ray(ray);
  RsHit hit = rs_miss(ray.tmax);
  rs_u32 visits = 1;
  rs_u32 stack[RS_STACK_SIZE];
  int sp = 0;
  rs_u32 node = 0;
  int live = rs_binary_root_entered(nodes, r, &rr, robust, hit.t); /* a node to visit remains */
  while (live) {
    /* Inner nodes, until the ray stands at a leaf or has nowhere left to go. */
    while (live && nodes[node].count == 0) {
      const rs_u32 left = nodes[node].first;
      int hit_l, hit_r;
      const float t_l = robust ? rs_intersect_box_robust(&rr, &nodes[left], hit.t, &hit_l)
                               : rs_intersect_box(r, &nodes[left], hit.t, &hit_l);
      const float t_r = robust ? rs_intersect_box_robust(&rr, &nodes[left + 1], hit.t, &hit_r)
                               : rs_intersect_box(r, &nodes[left + 1], hit.t, &hit_r);
      visits += 2;
      if (hit_l && hit_r) {
        const rs_u32 near_child = t_r < t_l ? left + 1 : left;
        stack[sp++] = near_child == left ? left + 1 : left;
        node = near_child;
      } else if (hit_l) {
        node = left;
      } else if (hit_r) {
        node = left + 1;
      } else if (sp > 0) {
        node = stack[--sp];
      } else {
        live = 0;
      }
    }
    /* Leaves, until an inner node comes off the stack. */
    while (live && nodes[node].count > 0) {
      RS_GLOBAL const RsBvhNode* n = &nodes[node];
      for (rs_u32 i = n->first; i < n->first + n->count; ++i) {
        if (rs_take_triangle(r, &rr, ray.d, &tris[i], robust, &hit) && any_hit) {
          if (node_visits) *node_visits = visits;
          return hit;
        }
      }
      if (sp > 0)
        node = stack[--sp];
      else
        live = 0;
    }
  }
  if (node_visits) *node_visits = visits;
  return hit;
}

#endif /* RAYSORT_TRAVERSE_BINARY_WW_H */
