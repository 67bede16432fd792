/* raysort — ray-stream traversal of the 8-wide BVH: a work-item deals RS_STREAM_CHUNK consecutive rays
 * of the batch's order, in that order, into streams of up to RS_STREAM_RAYS (64) rays of one direction
 * octant, and each stream walks the tree together, node by node, each ray tested alone against a
 * node's eight child boxes (docs/trace.md, "Trace classes"). The scheme is the ray-stream traversal of
 * Fuetterling, Lojewski, Pfreundt and Ebert (HPG 2015, "Efficient Ray Tracing Kernels for Modern
 * CPU Architectures"), what Embree's incoherent streams (rtcIntersect1M / rtcOccluded1M) run: the
 * SIMD lanes hold a node's children, as in the single-ray wide8 class, and the stream's rays share
 * the node's fetch. So a node costs one memory access for every ray of the stream that reaches it,
 * and the order of the rays decides how many of them reach the same nodes: on a CPU this is the
 * memory side of a warp's coherence, as the packet classes are its SIMD side. Dealing by octant (as
 * Embree 3's rtcOccluded1M deals its rays before it traces them) lets a stream's rays share a node's
 * near and far planes: in pixel order, 32 consecutive rays after a bounce lie in 4.4-6.8 octants
 * (sibenik and breakfast_room at 1080p).
 *
 * - A node is visited with the mask of the stream's rays that entered it (a bit per ray). Each of
 *   those rays runs the wide8 class's slab test (rs_wide8_boxes / rs_wide8_boxes_robust) with its
 *   own closest hit so far as the far bound; a child is entered with the rays that hit its box.
 * - Children nearest first by the smallest entry distance among their rays (ties by slot); any hit
 *   keeps slot order (largest box first, host/bvh/wide8.cpp). The others are pushed with their ray
 *   masks.
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

/* Child c's rays as one 64-bit mask, from the halves a node's test gathers lane-wise (rays 0-31, 32-63). */
RS_INLINE rs_u64 rs_stream_child_rays(const int* lo, const int* hi, int c) {
  return (rs_u64)(rs_u32)lo[c] | (rs_u64)(rs_u32)hi[c] << 32;
}

/* Starts the fetch of a child the stream has entered, on a CPU (RS_PREFETCH, shared.h): an inner node's
 * four lines, or a leaf's first packet up to its valid lanes (the vertex rows the leaf test reads,
 * five lines). The nearest child is visited next and the others when popped: a stream spends long
 * enough on a node's rays for the fetch to arrive in time, where a single ray's next node is loaded
 * at once anyway (results/history/trace-kernels.md, "Streams: the children prefetched, and placed by
 * rank"). */
RS_INLINE void rs_stream_prefetch_child(RS_GLOBAL const RsWide8Node* nodes, RS_GLOBAL const RsTriPacket8* packets,
                                        rs_u32 ref) {
  if (ref & RS_WIDE_LEAF) {
    RS_GLOBAL const char* p = (RS_GLOBAL const char*)&packets[RS_WIDE8_LEAF_FIRST(ref)];
    RS_UNROLL for (int line = 0; line < 5; ++line) RS_PREFETCH(p + 64 * line);
  } else {
    RS_GLOBAL const char* p = (RS_GLOBAL const char*)&nodes[ref];
    RS_UNROLL for (int line = 0; line < 4; ++line) RS_PREFETCH(p + 64 * line);
  }
}

/* rs_wide8_keep_nearest without a branch per lane, the same lane and so the same bits: the hit lanes'
 * t, +inf elsewhere; a lane is nearest where its t is at most every lane's, and of those the lowest
 * is kept (the first lane of least t, which rs_wide8_keep_nearest's scan with < keeps). Which lane is
 * nearest is data the branch predictor cannot learn; in the stream, whose rays meet a leaf one after
 * another, the scan's branches cost more than the eight compares (bounce rays 3-10 %), where the
 * single-ray walks run the scan faster (results/history/trace-kernels.md, "The nearest lane without a
 * branch"). */
RS_INLINE int rs_stream_keep_nearest(int bits, rs_f8 tw, rs_f8 uw, rs_f8 vw, RS_GLOBAL const RsTriPacket8* p,
                                     RsHit* hit) {
  float ts[8], us[8], vs[8], m[8];
  rs8_store(tw, ts);
  rs8_store(uw, us);
  rs8_store(vw, vs);
  for (int i = 0; i < 8; ++i) m[i] = (bits >> i) & 1 ? ts[i] : INFINITY;
  const rs_f8 mw = rs8_load(m);
  int nearest = bits;
  for (int j = 0; j < 8; ++j) nearest &= rs8_bits(mw <= rs8_splat(m[j]));
  if (!nearest) return 0;
  const int best = rs_lowest_bit(nearest);
  if (!(ts[best] < hit->t)) return 0;
  hit->t = ts[best];
  hit->tri = p->id[best];
  hit->u = us[best];
  hit->v = vs[best];
  return 1;
}

/* Traces the rays at positions pos[0..n) of the order (n <= RS_STREAM_RAYS), dealt by the octant
 * dealt_octant of d's signs, as one stream into their hits: closest hit (any_hit = 0) or any hit, fast
 * (robust = 0) or robust. visits, when not null, receives per ray its steps. */
RS_INLINE void rs_trace_stream(RS_GLOBAL const RsWide8Node* nodes, RS_GLOBAL const RsTriPacket8* packets,
                               RS_GLOBAL const RsRay* rays, RS_GLOBAL const rs_u32* order, const rs_u32* pos, int n,
                               int dealt_octant, int robust, int any_hit, RS_GLOBAL RsHit* hits,
                               RS_GLOBAL rs_u32* visits) {
  RsRay ray[RS_STREAM_RAYS];
  RsTraversalRay tr[RS_STREAM_RAYS];
  RsRobustRay rr[RS_STREAM_RAYS];
  RsHit hit[RS_STREAM_RAYS];
  rs_u32 steps[RS_STREAM_RAYS];
  rs_u64 live = 0; /* rays still looking (any hit: those without one yet) */
  rs_u64 in_octant[8] = {0, 0, 0, 0, 0, 0, 0, 0}; /* the rays of each 1/d octant */
  rs_u64 elsewhere = 0; /* rays whose 1/d octant is not the one they were dealt by (rare) */
  int octant_of[RS_STREAM_RAYS];
  for (int i = 0; i < RS_STREAM_RAYS; ++i) {
    steps[i] = 0;
    if (i >= n) continue;
    ray[i] = rays[order[pos[i]]];
    hit[i] = rs_miss(ray[i].tmax);
    if (robust) {
      rr[i] = rs_prepare_robust_ray(ray[i]);
      if (!rr[i].valid) continue; /* a zero or non-finite direction hits nothing */
    } else {
      tr[i] = rs_prepare_ray(ray[i]);
    }
    live |= (rs_u64)1 << i;
    octant_of[i] = robust ? rs_octant(rr[i].inv_d[0], rr[i].inv_d[1], rr[i].inv_d[2])
                          : rs_octant(tr[i].inv_d.x, tr[i].inv_d.y, tr[i].inv_d.z);
    elsewhere |= (rs_u64)(octant_of[i] != dealt_octant) << i;
  }
  /* The octants' rays after the loop, the same sets as an `in_octant[octant_of[i]] |= bit` per ray in it,
   * which was a read-modify-write through memory on the same word for nearly every ray: one dependent
   * chain through the whole set-up (results/history/trace-kernels.md, "The stream's octant sets"). */
  in_octant[dealt_octant] = live & ~elsewhere;
  for (rs_u64 rest = live & elsewhere; rest; rest &= rest - 1) {
    const int i = rs_lowest_bit_ul(rest);
    in_octant[octant_of[i]] |= (rs_u64)1 << i;
  }
  rs_u32 stack[RS_WIDE8_STACK_SIZE];
  rs_u64 stack_rays[RS_WIDE8_STACK_SIZE];
  int sp = 0;
  rs_u32 ref = 0; /* the root is always an inner node */
  rs_u64 m = live;
  while (m) {
    if (visits)
      for (rs_u64 rest = m; rest; rest &= rest - 1) ++steps[rs_lowest_bit_ul(rest)];
    if (!(ref & RS_WIDE_LEAF)) {
      RS_GLOBAL const RsWide8Node* n = &nodes[ref];
      /* The node's planes for the first ray's octant (rs_wide8_planes, what rs_wide8_boxes reads), read
       * once for the mask; a ray of another octant (rare: the rays are dealt by the signs of d,
       * those of 1/d but for d = -inf and a robust ray's near-parallel axis, whose 1/d is 0) chooses its
       * own. Each ray then runs rs_wide8_boxes's slab arithmetic
       * (rs_wide8_slabs / rs_wide8_slabs_robust), so the same bits. */
      const int octant = octant_of[rs_lowest_bit_ul(m)];
      const RsWide8Planes planes = rs_wide8_planes(n, octant);
      const rs_u64 others = m & ~in_octant[octant];
      /* Each ray of the mask against the eight boxes; per child, its rays (a bit per ray, gathered
       * lane-wise, so no loop over a ray's hit children: rays 0-31 in rays_lo, 32-63 in rays_hi) and
       * their nearest entry. */
      rs_i8 rays_lo = rs8_splati(0), rays_hi = rays_lo, any_in = rays_lo;
      rs_f8 nearest = rs8_splat(3.4028235e38f);
      for (rs_u64 rest = m; rest; rest &= rest - 1) {
        const int i = rs_lowest_bit_ul(rest);
        rs_f8 tnear;
        rs_i8 h;
        if (robust && !rr[i].oblique) {
          h = rs_wide8_boxes_robust(&rr[i], n, hit[i].t, &tnear);
        } else {
          const RsWide8Planes own = others & ((rs_u64)1 << i) ? rs_wide8_planes(n, octant_of[i]) : planes;
          h = robust ? rs_wide8_slabs_robust(&own, &rr[i], hit[i].t, &tnear) : rs_wide8_slabs(&own, &tr[i], hit[i].t, &tnear);
        }
        /* The ray's bit in both halves (one of them 0): no branch on which half holds it. */
        const rs_u64 bit = (rs_u64)1 << i;
        rays_lo = rays_lo | (h & rs8_splati((int)(rs_u32)bit));
        rays_hi = rays_hi | (h & rs8_splati((int)(rs_u32)(bit >> 32)));
        any_in = any_in | h;
        nearest = rs8_min(nearest, rs8_select(rs8_splat(3.4028235e38f), tnear, h));
      }
      const int entered = rs8_bits(any_in);
      for (int b = entered; b; b &= b - 1) rs_stream_prefetch_child(nodes, packets, n->child[rs_lowest_bit(b)]);
      if (entered) {
        int child_lo[8], child_hi[8];
        rs8_storei(rays_lo, child_lo);
        rs8_storei(rays_hi, child_hi);
        if (any_hit) {
          /* Slot order: the lowest entered child next, the others pushed highest first so that the
           * next lowest is on top; what the sort below gives with every key 0, without its arrays. */
          const int first = rs_lowest_bit(entered);
          for (int b = entered & (entered - 1); b;) {
            const int c = rs_highest_bit(b);
            b &= ~(1 << c);
            stack[sp] = n->child[c];
            stack_rays[sp] = rs_stream_child_rays(child_lo, child_hi, c);
            ++sp;
          }
          ref = n->child[first];
          m = rs_stream_child_rays(child_lo, child_hi, first);
          continue;
        }
        float dist[8];
        rs8_store(nearest, dist);
        /* Nearest first, ties by slot: a child's place is the number of entered children nearer than it,
         * and of those as near in a lower slot (the order an insertion sort by entry distance gives, in
         * two popcounts per child instead of its data-dependent loop). No key is NaN: a ray enters a
         * child only when its entry distance compares. */
        rs_u32 refs[8];
        rs_u64 masks[8];
        const int k = rs_popcount(entered);
        for (int b = entered; b; b &= b - 1) {
          const int c = rs_lowest_bit(b);
          const rs_f8 key = rs8_splat(dist[c]);
          const int r = rs_popcount(rs8_bits(nearest < key) & entered) +
                        rs_popcount(rs8_bits(nearest == key) & entered & ((1 << c) - 1));
          refs[r] = n->child[c];
          masks[r] = rs_stream_child_rays(child_lo, child_hi, c);
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
      const rs_u32 first_packet = RS_WIDE8_LEAF_FIRST(ref), end_packet = RS_WIDE8_LEAF_END(ref);
      const int lanes = RS_WIDE8_LEAF_LANES(ref); /* the leaf's own lanes of a shared packet */
      rs_u64 looking = m;
      for (rs_u32 pi = first_packet; pi < end_packet && looking; ++pi) {
        RS_GLOBAL const RsTriPacket8* p = &packets[pi];
        const RsTriEdges8 e = rs_tri_edges8(p);
        for (rs_u64 rest = looking; rest; rest &= rest - 1) {
          const int i = rs_lowest_bit_ul(rest);
          rs_f8 tw, uw, vw;
          const int bits = lanes & (robust ? rs_packet8_intersect_robust(&rr[i], ray[i].d, p, hit[i].t, &tw, &uw, &vw)
                                           : rs_packet8_intersect_edges(tr[i], &e, hit[i].t, &tw, &uw, &vw));
          if (bits && rs_stream_keep_nearest(bits, tw, uw, vw, p, &hit[i]) && any_hit) {
            looking &= ~((rs_u64)1 << i);
            live &= ~((rs_u64)1 << i);
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
  for (int i = 0; i < n; ++i) {
    hits[pos[i]] = hit[i];
    if (visits) visits[pos[i]] = steps[i];
  }
}

/* Traces the rays at positions [first, first + RS_STREAM_CHUNK) of the order (those below count): dealt
 * in order into one stream per octant of d's signs, a stream traced when it holds RS_STREAM_RAYS rays,
 * the rest at the end, octant by octant (as Embree's rtcOccluded1M deals its rays). d's sign bits are
 * those of the 1/d the stream's node test reads (rs_safe_rcp keeps the sign), so a stream's rays share
 * their planes; a ray whose 1/d still lands in another octant (d = -inf; a robust ray's near-parallel
 * axis, whose 1/d is 0) chooses its own, as in a mixed stream. One call site of rs_trace_stream, so
 * the kernel holds one copy of it. */
RS_INLINE void rs_traverse_stream(RS_GLOBAL const RsWide8Node* nodes, RS_GLOBAL const RsTriPacket8* packets,
                                  RS_GLOBAL const RsRay* rays, RS_GLOBAL const rs_u32* order, rs_u32 first,
                                  rs_u32 count, int robust, int any_hit, RS_GLOBAL RsHit* hits,
                                  RS_GLOBAL rs_u32* visits) {
  rs_u32 dealt[8][RS_STREAM_RAYS];
  int held[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  const rs_u32 end = count - first < RS_STREAM_CHUNK ? count : first + RS_STREAM_CHUNK;
  rs_u32 next = first;
  int rest = 0; /* after the last ray: the octant whose partial stream goes next */
  for (;;) {
    int full = -1;
    while (next < end && full < 0) {
      RS_GLOBAL const float* d = rays[order[next]].d;
      const int o = rs_octant_of_signs(rs_float_as_int(d[0]) < 0, rs_float_as_int(d[1]) < 0, rs_float_as_int(d[2]) < 0);
      dealt[o][held[o]++] = next++;
      if (held[o] == RS_STREAM_RAYS) full = o;
    }
    if (full < 0) {
      while (rest < 8 && held[rest] == 0) ++rest;
      if (rest == 8) break;
      full = rest;
    }
    rs_trace_stream(nodes, packets, rays, order, dealt[full], held[full], full, robust, any_hit, hits, visits);
    held[full] = 0;
  }
}

#endif /* RAYSORT_TRAVERSE_STREAM_H */
