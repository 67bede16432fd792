/* raysort — ray-stream traversal of the 8-wide BVH: RS_STREAM_RAYS (32) consecutive rays of the
 * batch's order walk the tree together, node by node, each ray tested alone against a node's eight
 * child boxes (docs/trace.md, "Trace classes"). The scheme is the ray-stream traversal of
 * Fuetterling, Lojewski, Pfreundt and Ebert (HPG 2015, "Efficient Ray Tracing Kernels for Modern
 * CPU Architectures"), what Embree's incoherent streams (rtcIntersect1M / rtcOccluded1M) run: the
 * SIMD lanes hold a node's children, as in the single-ray wide8 class, and the stream's rays share
 * the node's fetch. So a node costs one memory access for every ray of the stream that reaches it,
 * and the order of the rays decides how many of them reach the same nodes: on a CPU this is the
 * memory side of a warp's coherence, as the packet classes are its SIMD side.
 *
 * - A node is visited with the mask of the stream's rays that entered it (a bit per ray). Each of
 *   those rays runs the wide8 class's slab test (rs_wide8_boxes / rs_wide8_boxes_robust) with its
 *   own closest hit so far as the far bound; a child is entered with the rays that hit its box.
 * - Children nearest first by the smallest entry distance among their rays (ties by slot); any hit
 *   keeps slot order. The others are pushed with their ray masks.
 * - Leaves: each ray of the mask tests the leaf's triangle packets as the wide8 class does
 *   (rs_wide8_leaf: Möller–Trumbore or the watertight test on eight triangles at once; a packet's
 *   edges computed once for the mask); any hit: a ray that finds one leaves the stream, which ends
 *   when no ray is left.
 * Per ray the arithmetic is that of the wide8 class, so a triangle is hit or missed as there; only
 * the order in which a ray meets the nodes of its path differs (its stream's companions decide
 * it), so which of two equally near triangles it keeps may differ. Steps per ray: the nodes and
 * leaves at which it was in the mask.
 * Stack: a node pushes at most seven children and the 8-wide tree is at most 22 deep
 * (RS_WIDE8_STACK_SIZE entries of reference and ray mask).
 */
#ifndef RAYSORT_TRAVERSE_STREAM_H
#define RAYSORT_TRAVERSE_STREAM_H

#include "traverse_wide8.h"

/* Rays per stream: one bit each in a 32-bit mask. */
#define RS_STREAM_RAYS 32

/* A node's eight child boxes as the near and far planes of one ray octant (bit a set: 1/d < 0 on
 * axis a, so the upper bound is the near plane), read once for every ray of the stream that reaches
 * the node, as Embree's stream kernels hold a node in registers while its rays pass (Fuetterling et
 * al. 2015, section 4). */
typedef struct {
  rs_f8 near_x, far_x, near_y, far_y, near_z, far_z;
  rs_i8 valid;
} RsStreamPlanes;

RS_INLINE RsStreamPlanes rs_stream_planes(RS_GLOBAL const RsWide8Node* n, int octant) {
  RsStreamPlanes b;
  b.near_x = (octant & 1) ? n->hi_x : n->lo_x, b.far_x = (octant & 1) ? n->lo_x : n->hi_x;
  b.near_y = (octant & 2) ? n->hi_y : n->lo_y, b.far_y = (octant & 2) ? n->lo_y : n->hi_y;
  b.near_z = (octant & 4) ? n->hi_z : n->lo_z, b.far_z = (octant & 4) ? n->lo_z : n->hi_z;
  b.valid = n->valid;
  return b;
}

/* The octant of a ray's 1/d (the bits rs_wide8_boxes and rs_wide8_boxes_robust choose planes by). */
RS_INLINE int rs_stream_octant(float ix, float iy, float iz) {
  return (ix < 0.0f) | ((iy < 0.0f) << 1) | ((iz < 0.0f) << 2);
}

/* rs_wide8_boxes (fast) or rs_wide8_boxes_robust (robust, a ray with no parallel axis) with the
 * planes of the ray's octant already chosen: per lane the same operations in the same order, so the
 * same bits. A robust ray with a parallel axis takes rs_wide8_boxes_robust itself (the caller). */
RS_INLINE rs_i8 rs_stream_boxes(const RsStreamPlanes* b, const RsTraversalRay* tr, const RsRobustRay* rr, int robust,
                                float tmax, rs_f8* tnear_out) {
  const float ox = robust ? rr->o[0] : tr->o.x, oy = robust ? rr->o[1] : tr->o.y, oz = robust ? rr->o[2] : tr->o.z;
  const float ix = robust ? rr->inv_d[0] : tr->inv_d.x, iy = robust ? rr->inv_d[1] : tr->inv_d.y,
              iz = robust ? rr->inv_d[2] : tr->inv_d.z;
  const float tmin = robust ? rr->tmin : tr->tmin;
  const rs_f8 tnx = (b->near_x - ox) * ix, tfx = (b->far_x - ox) * ix;
  const rs_f8 tny = (b->near_y - oy) * iy, tfy = (b->far_y - oy) * iy;
  const rs_f8 tnz = (b->near_z - oz) * iz, tfz = (b->far_z - oz) * iz;
  rs_f8 tnear, tfar;
  if (robust) {
    /* rsw_boxes_robust's axis loop, unrolled: near planes into tmin, scaled far planes into tmax. */
    tnear = rs8_max(rs8_max(rs8_max(rs8_splat(tmin), tnx), tny), tnz);
    tfar = rs8_min(rs8_min(rs8_min(rs8_splat(tmax), tfx * RS_SLAB_FAR_SCALE), tfy * RS_SLAB_FAR_SCALE),
                   tfz * RS_SLAB_FAR_SCALE);
    *tnear_out = tnear;
    return b->valid & (tnear <= tfar);
  }
  tnear = rs8_max(rs8_max(tnx, tny), rs8_max(tnz, rs8_splat(tmin)));
  tfar = rs8_min(rs8_min(tfx, tfy), rs8_min(tfz, rs8_splat(tmax)));
  *tnear_out = tnear;
  return (tnear <= tfar) & b->valid;
}

/* Traces rays[order[first + i]], i < RS_STREAM_RAYS (and first + i < count), as one stream into
 * hits[first + i]: closest hit (any_hit = 0) or any hit, fast (robust = 0) or robust. visits, when
 * not null, receives per ray its steps. */
RS_INLINE void rs_traverse_stream(RS_GLOBAL const RsWide8Node* nodes, RS_GLOBAL const RsTriPacket8* packets,
                                  RS_GLOBAL const RsRay* rays, RS_GLOBAL const rs_u32* order, rs_u32 first,
                                  rs_u32 count, int robust, int any_hit, RS_GLOBAL RsHit* hits,
                                  RS_GLOBAL rs_u32* visits) {
  RsRay ray[RS_STREAM_RAYS];
  RsTraversalRay tr[RS_STREAM_RAYS];
  RsRobustRay rr[RS_STREAM_RAYS];
  RsHit hit[RS_STREAM_RAYS];
  rs_u32 steps[RS_STREAM_RAYS];
  rs_u32 live = 0; /* rays still looking (any hit: those without one yet) */
  rs_u32 in_octant[8] = {0, 0, 0, 0, 0, 0, 0, 0}; /* the rays of each 1/d octant */
  int octant_of[RS_STREAM_RAYS];
  for (int i = 0; i < RS_STREAM_RAYS; ++i) {
    steps[i] = 0;
    if (first + (rs_u32)i >= count) continue;
    ray[i] = rays[order[first + (rs_u32)i]];
    hit[i] = rs_miss(ray[i].tmax);
    if (robust) {
      rr[i] = rs_prepare_robust_ray(ray[i]);
      if (!rr[i].valid) continue; /* a zero or non-finite direction hits nothing */
    } else {
      tr[i] = rs_prepare_ray(ray[i]);
    }
    live |= 1u << i;
    octant_of[i] = robust ? rs_stream_octant(rr[i].inv_d[0], rr[i].inv_d[1], rr[i].inv_d[2])
                          : rs_stream_octant(tr[i].inv_d.x, tr[i].inv_d.y, tr[i].inv_d.z);
    in_octant[octant_of[i]] |= 1u << i;
  }
  rs_u32 stack[RS_WIDE8_STACK_SIZE];
  rs_u32 stack_rays[RS_WIDE8_STACK_SIZE];
  int sp = 0;
  rs_u32 ref = 0; /* the root is always an inner node */
  rs_u32 m = live;
  while (m) {
    if (visits)
      for (rs_u32 rest = m; rest; rest &= rest - 1) ++steps[rs_lowest_bit_u(rest)];
    if (!(ref & RS_WIDE_LEAF)) {
      RS_GLOBAL const RsWide8Node* n = &nodes[ref];
      /* The planes of the first ray's octant; a ray of another octant (rare in a coherent stream:
       * none when the mask lies in one octant) chooses its own. */
      const int octant = octant_of[rs_lowest_bit_u(m)];
      const RsStreamPlanes planes = rs_stream_planes(n, octant);
      const rs_u32 others = m & ~in_octant[octant];
      /* Each ray of the mask against the eight boxes; per child, its rays (a bit per ray, gathered
       * lane-wise, so no loop over a ray's hit children) and their nearest entry. */
      rs_i8 rays_in = rs8_splati(0), any_in = rays_in;
      rs_f8 nearest = rs8_splat(3.4028235e38f);
      for (rs_u32 rest = m; rest; rest &= rest - 1) {
        const int i = rs_lowest_bit_u(rest);
        rs_f8 tnear;
        rs_i8 h;
        if (robust && !rr[i].oblique) {
          h = rs_wide8_boxes_robust(&rr[i], n, hit[i].t, &tnear);
        } else if (others & (1u << i)) {
          const RsStreamPlanes own = rs_stream_planes(n, octant_of[i]);
          h = rs_stream_boxes(&own, &tr[i], &rr[i], robust, hit[i].t, &tnear);
        } else {
          h = rs_stream_boxes(&planes, &tr[i], &rr[i], robust, hit[i].t, &tnear);
        }
        rays_in = rays_in | (h & rs8_splati((int)(1u << i)));
        any_in = any_in | h;
        nearest = rs8_min(nearest, rs8_select(rs8_splat(3.4028235e38f), tnear, h));
      }
      const int entered = rs8_bits(any_in);
      if (entered) {
        int child_rays[8];
        rs8_storei(rays_in, child_rays);
        float dist[8];
        rs8_store(nearest, dist);
        rs_u32 refs[8], masks[8];
        float keys[8];
        int k = 0;
        for (int b = entered; b; b &= b - 1) {
          const int c = rs_lowest_bit(b);
          const float key = any_hit ? 0.0f : dist[c];
          int j = k++;
          for (; j > 0 && keys[j - 1] > key; --j) {
            keys[j] = keys[j - 1];
            refs[j] = refs[j - 1];
            masks[j] = masks[j - 1];
          }
          keys[j] = key;
          refs[j] = n->child[c];
          masks[j] = (rs_u32)child_rays[c];
        }
        for (int j = k - 1; j > 0; --j) {
          stack[sp] = refs[j];
          stack_rays[sp] = masks[j];
          ++sp;
        }
        ref = refs[0];
        m = masks[0];
        continue;
      }
    } else {
      /* rs_wide8_leaf for each ray of the mask, packets outer and rays inner, so a packet's edges
       * are computed once for all of them (fast variant): per ray the packets in the same order,
       * the same tests and the same choice of the nearest lane; an any-hit ray leaves at its first
       * hit. */
      const rs_u32 first_packet = (ref & ~RS_WIDE_LEAF) >> 2, end_packet = first_packet + (ref & 3u) + 1u;
      rs_u32 looking = m;
      for (rs_u32 pi = first_packet; pi < end_packet && looking; ++pi) {
        RS_GLOBAL const RsTriPacket8* p = &packets[pi];
        const RsTriEdges8 e = rs_tri_edges8(p);
        for (rs_u32 rest = looking; rest; rest &= rest - 1) {
          const int i = rs_lowest_bit_u(rest);
          rs_f8 tw, uw, vw;
          const int bits = robust ? rs_packet8_intersect_robust(&rr[i], ray[i].d, p, hit[i].t, &tw, &uw, &vw)
                                  : rs_packet8_intersect_edges(tr[i], &e, hit[i].t, &tw, &uw, &vw);
          if (bits && rs_wide8_keep_nearest(bits, tw, uw, vw, p, &hit[i]) && any_hit) {
            looking &= ~(1u << i);
            live &= ~(1u << i);
          }
        }
      }
    }
    /* Next: the nearest pending subtree with a ray still looking. */
    m = 0;
    while (sp > 0) {
      --sp;
      m = stack_rays[sp] & live;
      if (m) {
        ref = stack[sp];
        break;
      }
    }
  }
  for (int i = 0; i < RS_STREAM_RAYS; ++i) {
    if (first + (rs_u32)i >= count) break;
    hits[first + (rs_u32)i] = hit[i];
    if (visits) visits[first + (rs_u32)i] = steps[i];
  }
}

#endif /* RAYSORT_TRAVERSE_STREAM_H */
