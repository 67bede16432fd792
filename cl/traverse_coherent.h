/* raysort — coherent ray packets over the 8-wide BVH: RS_PACKET_W consecutive rays of the batch's
 * order walk the 8-wide collapse together, one ray per vector lane, and a node's eight children are
 * first tested against the packet's frustum in one 8-lane operation, so the per-lane slab test runs
 * only on the children the frustum does not rule out (docs/trace.md, "Trace classes"). This is the
 * scheme of Embree's coherent packet kernels (rtcIntersect16 with a coherent context,
 * `intersectCoherent`: a frustum test of an N-wide node, lanes only for the children it hits), the
 * path that runs primary rays 3x faster than its incoherent packets on the same rays.
 *
 * Two modes per packet:
 * - One origin (every lane's origin has the same bits: a pinhole camera's packets): the frustum is
 *   as tight as its 1/d bounds, so it alone decides the inner nodes. Every active lane goes on into
 *   each child it admits, nearest first by the frustum's entry bound, pushed with that bound in
 *   every lane; a popped entry keeps the lanes whose closest hit is not nearer. Lanes meet
 *   triangles, and (fast variant) the leaf children of a node that admits more than one child.
 * - Otherwise: the packet class's traversal (traverse_packet.h) over the 8-wide tree, per-lane slab
 *   tests and masks, nearest child first by the first active lane's entry distance, but only for
 *   the children the frustum admits (if the packet has one): the frustum skips only children no
 *   lane's own test enters, so hits and steps are those of the same walk without it.
 * Either way each lane meets triangles with the single-ray arithmetic (rs_packet_triangle[_robust]).
 * A lane's own box test (fast variant) keeps the unfused distances (plane − o) · 1/d
 * (rs_packet_box_unfused), which the frustum below bounds exactly; the other fast classes fuse them
 * (rs_intersect_box), so this class equals them up to ties and a ray that grazes a box within an
 * ulp, as the binary and the wide trees (whose boxes differ) equal each other.
 *
 * The frustum (Reshetov, Soupikov and Hurley 2005; Embree's Frustum): the bounds, over the packet's
 * active lanes, of the origin, of 1/d and of the interval [tmin, closest hit so far]. A lane's entry
 * distance on an axis is fl(fl(plane - o) * inv_d) with the near plane of its 1/d sign; with one
 * sign for all lanes on every axis (else no frustum for that packet) both roundings are monotone, so
 * fl(plane - o) lies between the values at the origin bounds, and the product between its values at
 * the 1/d bounds: min(a * id_lo, a * id_hi) <= every lane's entry distance and max(...) >= every
 * lane's exit distance, exactly in floating point. A child whose largest lower entry bound exceeds
 * its smallest upper exit bound is entered by no lane. Rays with a non-finite origin or 1/d, or
 * (robust) a parallel axis, leave their packet without a frustum.
 *
 * The leaf loop, the pop and the write-out repeat rs_traverse_packet's on purpose: as shared
 * functions (the triangle call with a stride, the hit update and the write-out through pointers) PoCL
 * made coherent16 1.5-2.5 % slower on sibenik's primary rays (results/history/trace-kernels.md).
 *
 * Include after traverse_packet.h (same RS_PACKET_W) and traverse_wide8.h; no include guard, for the
 * same reason as traverse_packet.h.
 */

/* The packet's frustum: per axis the origin bound the near (far) planes are taken from and the
 * bounds of 1/d, the octant of the near planes, the smallest tmin and the largest far bound. */
typedef struct {
  float o_near[3], o_far[3], id_lo[3], id_hi[3];
  float tmin_lo, tmax_hi;
  int octant;
  int one_origin; /* every lane starts at the same point: the frustum is exact up to its 1/d bounds */
} RsPacketFrustum;

/* The largest of a's lanes in `lanes` (nonzero), the smallest. */
RS_INLINE float rs_packet_lanes_max(rs_pf a, int lanes) {
  return rsp_max_lane(rsp_select(rsp_splat(-3.4028235e38f), a, rsp_mask(lanes)));
}
RS_INLINE float rs_packet_lanes_min(rs_pf a, int lanes) {
  return rsp_min_lane(rsp_select(rsp_splat(3.4028235e38f), a, rsp_mask(lanes)));
}

/* Sets f for the lanes in `lanes` (nonzero) and returns 1, or returns 0 when the packet gets no
 * frustum: a lane with a non-finite origin or 1/d, robust lanes with a parallel axis, or lanes whose
 * 1/d signs differ on some axis. */
RS_INLINE int rs_packet_frustum(const RsRayPacket* p, int lanes, int robust, rs_pf tmax, RsPacketFrustum* f) {
  if (robust && p->any_parallel) return 0;
  const rs_pf big = rsp_splat(3.4028235e38f);
  /* |x| <= FLT_MAX is false for inf and NaN. */
  const rs_pi finite = (rsp_abs(p->ox) <= big) & (rsp_abs(p->oy) <= big) & (rsp_abs(p->oz) <= big) &
                       (rsp_abs(p->ix) <= big) & (rsp_abs(p->iy) <= big) & (rsp_abs(p->iz) <= big);
  if ((rsp_bits(finite) & lanes) != lanes) return 0;
  const int neg_x = rsp_bits(p->neg_x) & lanes, neg_y = rsp_bits(p->neg_y) & lanes, neg_z = rsp_bits(p->neg_z) & lanes;
  if ((neg_x && neg_x != lanes) || (neg_y && neg_y != lanes) || (neg_z && neg_z != lanes)) return 0;
  f->octant = (neg_x ? 1 : 0) | (neg_y ? 2 : 0) | (neg_z ? 4 : 0);
  /* 1/d > 0: the entry distance falls as o grows, so its lower bound takes the largest o, and the
   * exit distance's upper bound the smallest; 1/d < 0 the other way round. */
  const float ox_lo = rs_packet_lanes_min(p->ox, lanes), ox_hi = rs_packet_lanes_max(p->ox, lanes);
  const float oy_lo = rs_packet_lanes_min(p->oy, lanes), oy_hi = rs_packet_lanes_max(p->oy, lanes);
  const float oz_lo = rs_packet_lanes_min(p->oz, lanes), oz_hi = rs_packet_lanes_max(p->oz, lanes);
  f->o_near[0] = neg_x ? ox_lo : ox_hi, f->o_far[0] = neg_x ? ox_hi : ox_lo;
  f->o_near[1] = neg_y ? oy_lo : oy_hi, f->o_far[1] = neg_y ? oy_hi : oy_lo;
  f->o_near[2] = neg_z ? oz_lo : oz_hi, f->o_far[2] = neg_z ? oz_hi : oz_lo;
  f->id_lo[0] = rs_packet_lanes_min(p->ix, lanes), f->id_hi[0] = rs_packet_lanes_max(p->ix, lanes);
  f->id_lo[1] = rs_packet_lanes_min(p->iy, lanes), f->id_hi[1] = rs_packet_lanes_max(p->iy, lanes);
  f->id_lo[2] = rs_packet_lanes_min(p->iz, lanes), f->id_hi[2] = rs_packet_lanes_max(p->iz, lanes);
  f->tmin_lo = rs_packet_lanes_min(p->tmin, lanes);
  f->tmax_hi = rs_packet_lanes_max(tmax, lanes);
  /* One origin: every lane's coordinates have the bits of the first's (so no +0 beside -0). */
  const int lead = rs_lowest_bit(lanes);
  const rs_pi same = (rsp_as_int(p->ox) == rsp_splati(rs_float_as_int(rsp_lane(p->ox, lead)))) &
                     (rsp_as_int(p->oy) == rsp_splati(rs_float_as_int(rsp_lane(p->oy, lead)))) &
                     (rsp_as_int(p->oz) == rsp_splati(rs_float_as_int(rsp_lane(p->oz, lead))));
  f->one_origin = (rsp_bits(same) & lanes) == lanes;
  return 1;
}

/* The children of n (bits) that some lane of the frustum's packet may enter: every child a lane's
 * own slab test (rs_packet_box_unfused, rs_packet_box_robust, with the far planes scaled as there)
 * enters is among them. */
RS_INLINE int rs_packet_frustum_children(const RsPacketFrustum* f, RS_GLOBAL const RsWide8Node* n, int robust,
                                         float* tnear_out) {
  const RsWide8Planes b = rs_wide8_planes(n, f->octant);
  const rs_f8 near_x = b.near_x - rs8_splat(f->o_near[0]), far_x = b.far_x - rs8_splat(f->o_far[0]);
  const rs_f8 near_y = b.near_y - rs8_splat(f->o_near[1]), far_y = b.far_y - rs8_splat(f->o_far[1]);
  const rs_f8 near_z = b.near_z - rs8_splat(f->o_near[2]), far_z = b.far_z - rs8_splat(f->o_far[2]);
  const rs_f8 tnx = rs8_min(near_x * rs8_splat(f->id_lo[0]), near_x * rs8_splat(f->id_hi[0]));
  const rs_f8 tny = rs8_min(near_y * rs8_splat(f->id_lo[1]), near_y * rs8_splat(f->id_hi[1]));
  const rs_f8 tnz = rs8_min(near_z * rs8_splat(f->id_lo[2]), near_z * rs8_splat(f->id_hi[2]));
  rs_f8 tfx = rs8_max(far_x * rs8_splat(f->id_lo[0]), far_x * rs8_splat(f->id_hi[0]));
  rs_f8 tfy = rs8_max(far_y * rs8_splat(f->id_lo[1]), far_y * rs8_splat(f->id_hi[1]));
  rs_f8 tfz = rs8_max(far_z * rs8_splat(f->id_lo[2]), far_z * rs8_splat(f->id_hi[2]));
  if (robust) {
    const rs_f8 scale = rs8_splat(RS_SLAB_FAR_SCALE);
    tfx = tfx * scale, tfy = tfy * scale, tfz = tfz * scale;
  }
  const rs_f8 tnear = rs8_max(rs8_max(tnx, tny), rs8_max(tnz, rs8_splat(f->tmin_lo)));
  const rs_f8 tfar = rs8_min(rs8_min(tfx, tfy), rs8_min(tfz, rs8_splat(f->tmax_hi)));
  rs8_store(tnear, tnear_out);
  return rs8_bits((tnear <= tfar) & b.valid);
}

/* Traces rays[order[first + i]], i < RS_PACKET_W (and first + i < count), as one coherent packet into
 * hits[first + i]: closest hit (any_hit = 0) or any hit, fast (robust = 0) or robust. visits, when not
 * null, receives per ray the steps (8-wide nodes and leaves) at which its lane was active. */
RS_INLINE void rs_traverse_coherent(RS_GLOBAL const RsWide8Node* nodes, RS_GLOBAL const RsTriPacket8* packets,
                                    RS_GLOBAL const RsRay* rays, RS_GLOBAL const rs_u32* order, rs_u32 first,
                                    rs_u32 count, int robust, int any_hit, RS_GLOBAL RsHit* hits,
                                    RS_GLOBAL rs_u32* visits) {
  RsRay lane_rays[RS_PACKET_W];
  RsRayPacket p;
  rs_pf hit_t;
  const int live = rs_packet_load(rays, order, first, count, robust, lane_rays, &p, &hit_t);
  rs_pi hit_tri = rsp_splati((int)RS_NO_HIT);
  rs_pf hit_u = rsp_splat(0.0f), hit_v = rsp_splat(0.0f);
  rs_pi steps = rsp_splati(0);
  RsPacketFrustum f;
  const int frustum = live ? rs_packet_frustum(&p, live, robust, hit_t, &f) : 0;
  /* Lanes of one origin: the frustum alone decides the inner nodes (docs/trace.md, "coherent8, coherent16"). */
  const int frustum_only = frustum && f.one_origin;
  int finished = 0; /* any hit: lanes that found theirs */
  rs_u32 stack[RS_WIDE8_STACK_SIZE];
  int stack_lanes[RS_WIDE8_STACK_SIZE];
  rs_pf stack_t[RS_WIDE8_STACK_SIZE];
  int sp = 0;
  rs_u32 ref = 0; /* the root is always an inner node */
  int lanes = live;
  while (lanes) {
    if (visits) steps = steps - rsp_mask(lanes);
    if (!(ref & RS_WIDE_LEAF)) {
      RS_GLOBAL const RsWide8Node* n = &nodes[ref];
      RS_GLOBAL const float* b = (RS_GLOBAL const float*)n; /* lo_x hi_x lo_y hi_y lo_z hi_z, eight each */
      float fnear[8];
      const int candidates = frustum ? rs_packet_frustum_children(&f, n, robust, fnear) : rs8_bits(n->valid);
      rs_pf tnear[8];
      int child_lanes[8];
      int entered = 0;
      if (frustum_only) {
        /* Every active lane goes on into each child the frustum admits. */
        entered = candidates;
        for (int c = 0; c < 8; ++c) child_lanes[c] = lanes;
        /* Fast variant, two or more admitted children: a leaf child keeps only the lanes whose own
         * slab test enters it, and is skipped when none does (a leaf costs a sixteen-lane triangle
         * test per triangle). A lone admitted child is where the packet's rays go, so its lanes
         * rarely miss it; the robust variant's box test costs more than it saves
         * (results/history/trace-kernels.md, "Coherent packets"). */
        for (int rest = robust || !(candidates & (candidates - 1)) ? 0 : candidates; rest; rest &= rest - 1) {
          const int c = rs_lowest_bit(rest);
          if (!(n->child[c] & RS_WIDE_LEAF)) continue;
          rs_pf tn;
          const rs_pi m = rs_packet_box_unfused(&p, b[c], b[8 + c], b[16 + c], b[24 + c], b[32 + c], b[40 + c], hit_t, &tn);
          child_lanes[c] = lanes & rsp_bits(m);
          if (!child_lanes[c]) entered &= ~(1 << c);
        }
      } else {
        for (int rest = candidates; rest; rest &= rest - 1) {
          const int c = rs_lowest_bit(rest);
          const rs_pi m = robust ? rs_packet_box_robust(&p, b[c], b[8 + c], b[16 + c], b[24 + c], b[32 + c], b[40 + c], hit_t, &tnear[c])
                                 : rs_packet_box_unfused(&p, b[c], b[8 + c], b[16 + c], b[24 + c], b[32 + c], b[40 + c], hit_t, &tnear[c]);
          child_lanes[c] = lanes & rsp_bits(m);
          if (child_lanes[c]) entered |= 1 << c;
        }
      }
      if (entered) {
        /* The children in visiting order: by the frustum's entry bound, or with lane tests by the first
         * active lane's entry distance (children it does not enter after the others); ties by slot, and
         * any hit keeps slot order. The others are pushed with their lanes and entry distances (the
         * frustum's bound in every lane). */
        int slot[8];
        float key[8];
        int k = 0;
        const int lead = rs_lowest_bit(lanes);
        for (int rest = entered; rest; rest &= rest - 1) {
          const int c = rs_lowest_bit(rest);
          float d = 3.4028235e38f;
          if (!any_hit && frustum_only) d = fnear[c];
          else if (!any_hit && ((child_lanes[c] >> lead) & 1)) d = rsp_lane(tnear[c], lead);
          int j = k++;
          for (; j > 0 && key[j - 1] > d; --j) {
            key[j] = key[j - 1];
            slot[j] = slot[j - 1];
          }
          key[j] = d;
          slot[j] = c;
        }
        for (int j = k - 1; j > 0; --j) {
          stack[sp] = n->child[slot[j]];
          stack_lanes[sp] = child_lanes[slot[j]];
          stack_t[sp] = frustum_only ? rsp_splat(fnear[slot[j]]) : tnear[slot[j]];
          ++sp;
        }
        ref = n->child[slot[0]];
        lanes = child_lanes[slot[0]];
        continue;
      }
    } else {
      const rs_u32 first_packet = RS_WIDE8_LEAF_FIRST(ref), end = RS_WIDE8_LEAF_END(ref);
      const int leaf_lanes = RS_WIDE8_LEAF_LANES(ref); /* the leaf's own triangles of a shared packet */
      int found_any = 0;
      for (rs_u32 pi = first_packet; pi < end && lanes; ++pi) {
        RS_GLOBAL const RsTriPacket8* tp = &packets[pi];
        RS_GLOBAL const float* v0x = (RS_GLOBAL const float*)&tp->v0x; /* v0x v0y v0z v1x ... v2z, eight each */
        RS_GLOBAL const rs_i32* tri_valid = (RS_GLOBAL const rs_i32*)&tp->valid;
        RS_GLOBAL const rs_i32* nondegenerate = (RS_GLOBAL const rs_i32*)&tp->nondegenerate;
        for (int j = 0; j < 8 && lanes; ++j) {
          if (!((leaf_lanes >> j) & 1) || !tri_valid[j] || (robust && !nondegenerate[j])) continue;
          rs_pf t = hit_t, u = hit_u, v = hit_v;
          const int found =
              robust ? rs_packet_triangle_robust(&p, lane_rays, lanes, v0x[j], v0x[8 + j], v0x[16 + j], v0x[24 + j],
                                                 v0x[32 + j], v0x[40 + j], v0x[48 + j], v0x[56 + j], v0x[64 + j], hit_t,
                                                 &t, &u, &v)
                     : rs_packet_triangle(&p, lanes, v0x[j], v0x[8 + j], v0x[16 + j], v0x[24 + j], v0x[32 + j],
                                          v0x[40 + j], v0x[48 + j], v0x[56 + j], v0x[64 + j], hit_t, &t, &u, &v);
          /* Fast variant: the hit taken in without a branch (found or not); robust: only when found. */
          if (robust && !found) continue;
          found_any |= found;
          const rs_pi m = rsp_mask(found);
          hit_t = rsp_select(hit_t, t, m);
          hit_tri = rsp_selecti(hit_tri, rsp_splati((int)tp->id[j]), m);
          hit_u = rsp_select(hit_u, u, m);
          hit_v = rsp_select(hit_v, v, m);
          if (any_hit) {
            finished |= found;
            lanes &= ~found;
          }
        }
      }
      /* Closer hits pull the frustum's far bound in (Embree's updateMaxDist); it stays at or beyond
       * the closest hit so far of every lane that may still test a box. */
      if (frustum && found_any && !any_hit) f.tmax_hi = rs_packet_lanes_max(hit_t, live);
    }
    /* Next: the nearest pending subtree with a lane that can still find a closer hit there. */
    lanes = 0;
    while (sp > 0) {
      --sp;
      lanes = stack_lanes[sp] & ~finished & rsp_bits(stack_t[sp] <= hit_t);
      if (lanes) {
        ref = stack[sp];
        break;
      }
    }
  }
#ifdef RS_PACKET_ROWS
  if (first + (rs_u32)RS_PACKET_W <= count && !visits) {
    rs_packet_store_hits_in_a_row(hit_t, hit_tri, hit_u, hit_v, hits + first);
    return;
  }
#endif
  float ft[RS_PACKET_W], fu[RS_PACKET_W], fv[RS_PACKET_W];
  int tri[RS_PACKET_W], nsteps[RS_PACKET_W];
  rsp_store(hit_t, ft), rsp_store(hit_u, fu), rsp_store(hit_v, fv);
  rsp_storei(hit_tri, tri);
  rsp_storei(steps, nsteps);
  for (int i = 0; i < RS_PACKET_W; ++i) {
    if (first + (rs_u32)i >= count) break;
    RsHit h;
    h.t = ft[i];
    h.tri = (rs_u32)tri[i];
    h.u = fu[i];
    h.v = fv[i];
    hits[first + (rs_u32)i] = h;
    if (visits) visits[first + (rs_u32)i] = (rs_u32)nsteps[i];
  }
}
