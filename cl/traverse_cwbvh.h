/* raysort — traversal of the compressed 8-wide BVH (bvh_layout.h, RsCwbvhNode; the cwbvh trace
 * class): the GPU kernel of Ylitie, Karras and Laine (HPG 2017), one ray per work-item, written for
 * OpenCL (docs/trace.md, "cwbvh"). On a GPU its 80-byte nodes are what a warp fetches; on PoCL it
 * only has to be correct.
 *
 * - Node groups, not single nodes, on the stack (the paper's section 3.2): a node's inner children
 *   that the ray entered are one group, a base index and a bit per child; the traversal takes the
 *   group's next child and pushes the rest of the group back only while some remain, so one entry
 *   stands for up to seven pending siblings and the stack grows by at most one per level.
 * - No sort: children sit in slots by octant (host/bvh/cwbvh.cpp), and a ray of octant o takes the
 *   bits of its group in the order of slot ^ o (the group keeps bit slot ^ o for each child).
 * - A node's leaves (its triangle group, at most 24 triangles) are tested when the node is fetched,
 *   before its inner children, with the binary tree's triangle tests (intersect.h), so a triangle
 *   is hit or missed exactly as in every other class; only the order of the tests differs.
 * - Boxes are dequantised as p + q * 2^(e - 127): q * 2^k is exact, so the box is the one the
 *   builder checked to contain the child (rounded outward), and the robust slab test on it stays
 *   conservative: the robust variant is watertight as the binary one is.
 */
#ifndef RAYSORT_TRAVERSE_CWBVH_H
#define RAYSORT_TRAVERSE_CWBVH_H

#include "bvh_layout.h"
#include "intersect.h"
#include "lanes.h"

/* The grid step of an axis, 2^(e - 127), from its exponent byte (1..254: a normal float). */
RS_INLINE float rs_cwbvh_scale(rs_u8 e) { return rs_int_as_float((rs_i32)e << 23); }

/* Slot s's box, dequantised. */
RS_INLINE void rs_cwbvh_box_of(RS_GLOBAL const RsCwbvhNode* n, int s, float lo[3], float hi[3]) {
  const float sx = rs_cwbvh_scale(n->e[0]), sy = rs_cwbvh_scale(n->e[1]), sz = rs_cwbvh_scale(n->e[2]);
  lo[0] = n->p[0] + (float)n->q_lo_x[s] * sx;
  lo[1] = n->p[1] + (float)n->q_lo_y[s] * sy;
  lo[2] = n->p[2] + (float)n->q_lo_z[s] * sz;
  hi[0] = n->p[0] + (float)n->q_hi_x[s] * sx;
  hi[1] = n->p[1] + (float)n->q_hi_y[s] * sy;
  hi[2] = n->p[2] + (float)n->q_hi_z[s] * sz;
}

/* rs_intersect_box's slab test on a box in private memory (the fast variant). */
RS_INLINE int rs_cwbvh_slab(RsTraversalRay r, const float lo[3], const float hi[3], float tmax) {
  const float tx0 = rs_fma(lo[0], r.inv_d.x, r.o_inv_d.x), tx1 = rs_fma(hi[0], r.inv_d.x, r.o_inv_d.x);
  const float ty0 = rs_fma(lo[1], r.inv_d.y, r.o_inv_d.y), ty1 = rs_fma(hi[1], r.inv_d.y, r.o_inv_d.y);
  const float tz0 = rs_fma(lo[2], r.inv_d.z, r.o_inv_d.z), tz1 = rs_fma(hi[2], r.inv_d.z, r.o_inv_d.z);
  const float tnear = rs_max(rs_max(rs_min(tx0, tx1), rs_min(ty0, ty1)), rs_max(rs_min(tz0, tz1), r.tmin));
  const float tfar = rs_min(rs_min(rs_max(tx0, tx1), rs_max(ty0, ty1)), rs_min(rs_max(tz0, tz1), tmax));
  return tnear <= tfar;
}

/* rs_intersect_box_robust's conservative slab test (Ize 2013) on a box in private memory. */
RS_INLINE int rs_cwbvh_slab_robust(const RsRobustRay* r, const float lo[3], const float hi[3], float tmax) {
  float tnear = r->tmin;
  float tfar = tmax;
  int inside = 1;
  RS_UNROLL
  for (int a = 0; a < 3; ++a) {
    const float t0 = (lo[a] - r->o[a]) * r->inv_d[a];
    const float t1 = (hi[a] - r->o[a]) * r->inv_d[a];
    if (r->parallel[a]) {
      inside = inside && lo[a] <= r->o[a] && r->o[a] <= hi[a];
    } else {
      tnear = rs_max(tnear, rs_min(t0, t1));
      tfar = rs_min(tfar, rs_max(t0, t1) * RS_SLAB_FAR_SCALE);
    }
  }
  return inside && tnear <= tfar;
}

/* Closest hit (any_hit = 0) or any hit, fast (robust = 0) or robust. *steps, when not null, counts
 * the steps of the paper's loop: node fetches and triangle tests (one triangle per iteration, as
 * its kernel takes them). trail, when not null, receives each step, up to trail_cap: a node's index,
 * or RS_WIDE_LEAF | triangle index << 2 for a triangle test (the wide layouts' leaf reference of one
 * packet, so the SIMT and GPU models read it as a leaf step of one 48-byte triangle); *trail_len
 * gets the step count (host only). */
RS_INLINE RsHit rs_traverse_cwbvh_recorded(RS_GLOBAL const RsCwbvhNode* nodes, RS_GLOBAL const RsTriangle* tris, RsRay ray,
                                           int robust, int any_hit, rs_u32* steps_out, rs_u32* trail, rs_u32 trail_cap,
                                           rs_u32* trail_len) {
  const RsTraversalRay r = rs_prepare_ray(ray);
  const RsRobustRay rr = rs_prepare_robust_ray(ray);
  RsHit hit = rs_miss(ray.tmax);
  rs_u32 steps = 0;
  /* The ray's octant: bit a set when d[a] < 0. */
  const rs_u32 oct = (ray.d[0] < 0.0f ? 1u : 0u) | (ray.d[1] < 0.0f ? 2u : 0u) | (ray.d[2] < 0.0f ? 4u : 0u);
  /* A node group: `base`, the index of the node's first inner child, and `bits`: the node's imask
   * at bits 0-7 and, at bit 8 + (slot ^ oct), each inner child entered and not yet visited. The
   * root is the one child of a group of its own (slot 0). */
  rs_u32 group_base = 0, group_bits = (1u << (8u + oct)) | 1u;
  rs_u32 stack_base[RS_CWBVH_STACK_SIZE], stack_bits[RS_CWBVH_STACK_SIZE];
  int sp = 0;
  if (robust && !rr.valid) group_bits = 0;
  for (;;) {
    if (!(group_bits >> 8)) {
      if (sp == 0) break;
      --sp;
      group_base = stack_base[sp];
      group_bits = stack_bits[sp];
    }
    const int key = rs_lowest_bit((int)(group_bits >> 8));
    group_bits &= ~(1u << (8 + key));
    const rs_u32 slot = (rs_u32)key ^ oct;
    const rs_u32 index = group_base + (rs_u32)rs_popcount((int)(group_bits & 0xffu & ((1u << slot) - 1u)));
    if (group_bits >> 8) {
      stack_base[sp] = group_base;
      stack_bits[sp] = group_bits;
      ++sp;
    }
    RS_GLOBAL const RsCwbvhNode* n = &nodes[index];
    if (trail && steps < trail_cap) trail[steps] = index;
    ++steps;
    rs_u32 entered = 0, triangles = 0;
    for (int s = 0; s < 8; ++s) {
      const rs_u32 inner = ((rs_u32)n->imask >> s) & 1u;
      const rs_u32 meta = n->meta[s];
      if (!inner && !meta) continue;
      float lo[3], hi[3];
      rs_cwbvh_box_of(n, s, lo, hi);
      const int in = robust ? rs_cwbvh_slab_robust(&rr, lo, hi, hit.t) : rs_cwbvh_slab(r, lo, hi, hit.t);
      if (!in) continue;
      if (inner)
        entered |= 1u << ((rs_u32)s ^ oct);
      else
        triangles |= ((1u << (meta >> 5)) - 1u) << (meta & 31u);
    }
    for (; triangles; triangles &= triangles - 1u) {
      const rs_u32 i = n->triangle_base + (rs_u32)rs_lowest_bit_u(triangles);
      if (trail && steps < trail_cap) trail[steps] = RS_WIDE_LEAF | (i << 2);
      ++steps;
      if (rs_take_triangle(r, &rr, ray.d, &tris[i], robust, &hit) && any_hit) {
        if (steps_out) *steps_out = steps;
        if (trail_len) *trail_len = steps;
        return hit;
      }
    }
    group_base = n->child_base;
    group_bits = (entered << 8) | (rs_u32)n->imask;
  }
  if (steps_out) *steps_out = steps;
  if (trail_len) *trail_len = steps;
  return hit;
}

RS_INLINE RsHit rs_traverse_cwbvh(RS_GLOBAL const RsCwbvhNode* nodes, RS_GLOBAL const RsTriangle* tris, RsRay ray, int robust,
                                  int any_hit, rs_u32* steps) {
  return rs_traverse_cwbvh_recorded(nodes, tris, ray, robust, any_hit, steps, 0, 0, 0);
}

#endif
