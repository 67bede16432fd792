/* raysort — the prefix path code (Xiang et al. section 4.1): the first box tests of a traversal of
 * the binary BVH in fixed left-first order, with the trace kernels' triangle test (intersect.h) and
 * the encoders' slab test (rs_intersect_box_unfused).
 */
#ifndef RAYSORT_KEYS_PPC_H
#define RAYSORT_KEYS_PPC_H

#include "intersect.h"
#include "keys.h"

/* PPC (Xiang et al. section 4.1): the first `bits` box-test results of a closest-hit traversal
 * that visits children in fixed order, left first: the root's test, then at each inner node the
 * left and the right child's tests (rs_intersect_box_unfused, the encoders' box test, against the
 * current closest hit); leaves test their triangles, which shortens the segment as in a trace.
 * 1 = hit, most significant first; a traversal that ends early leaves 0s. */
RS_KEY_INLINE rs_u64 rs_prefix_path_code(RS_GLOBAL const RsBvhNode* nodes, RS_GLOBAL const RsTriangle* tris, RsRay ray,
                                     rs_u32 bits) {
  RsTraversalRay r = rs_prepare_ray(ray);
  float tmax = ray.tmax;
  RsBitWriter w = rs_bit_writer();
  int hit;
  rs_intersect_box_unfused(r, &nodes[0], tmax, &hit);
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
      rs_intersect_box_unfused(r, &nodes[left], tmax, &hit_l);
      rs_intersect_box_unfused(r, &nodes[left + 1], tmax, &hit_r);
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

#endif /* RAYSORT_KEYS_PPC_H */
