/* raysort — single-ray traversal of a W-wide BVH, W = RS_WIDE_W (4 or 8): the box tests of a
 * node's W children, the triangle tests of a W-triangle leaf packet, and the nearest-first walk.
 * One source for both widths, so the 8-wide class (traverse_wide8.h) runs per lane exactly the
 * arithmetic of the 4-wide one (traverse_wide.h): the same slab tests and the same Möller–Trumbore
 * and watertight triangle tests, only on eight lanes (float8) instead of four (float4).
 *
 * No include guard: traverse_wide.h includes it with RS_WIDE_W 4, traverse_wide8.h with 8. The
 * names below are aliases for the width's types, lane helpers (lanes.h) and layout (bvh_layout.h);
 * the functions it defines get the width's names:
 *   W = 4: rs_wide_planes (RsWidePlanes), rs_wide_slabs[_robust], rs_wide_boxes[_robust],
 *          rs_packet_intersect[_robust|_edges], rs_tri_edges (RsTriEdges),
 *          rs_wide_keep_nearest, rs_wide_leaf, rs_traverse_wide[_recorded|_subtree]
 *   W = 8: rs_wide8_planes (RsWide8Planes), rs_wide8_slabs[_robust], rs_wide8_boxes[_robust],
 *          rs_packet8_intersect[_robust|_edges], rs_tri_edges8 (RsTriEdges8),
 *          rs_wide8_keep_nearest, rs_wide8_leaf, rs_traverse_wide8[_recorded|_subtree]
 * All aliases are undefined again at the end.
 */
#if RS_WIDE_W == 4
#define rsw_f rs_f4
#define rsw_i rs_i4
#define rsw_splat rs4_splat
#define rsw_min rs4_min
#define rsw_max rs4_max
#define rsw_select rs4_select
#define rsw_fma rs4_fma
#define rsw_abs rs4_abs
#define rsw_bits rs4_bits
#define rsw_store rs4_store
#define rsw_load rs4_load
#define rsw_robust_t_bound rs4_robust_t_bound
#define RsWNode RsWideNode
#define RsWPacket RsTriPacket
#define RS_WSTACK RS_WIDE_STACK_SIZE
#define RsWPlanes RsWidePlanes
#define rsw_planes rs_wide_planes
#define rsw_slabs rs_wide_slabs
#define rsw_slabs_robust rs_wide_slabs_robust
#define rsw_boxes rs_wide_boxes
#define rsw_boxes_robust rs_wide_boxes_robust
#define rsw_intersect rs_packet_intersect
#define RsWEdges RsTriEdges
#define rsw_edges rs_tri_edges
#define rsw_intersect_edges rs_packet_intersect_edges
#define rsw_keep_nearest rs_wide_keep_nearest
#define rsw_intersect_robust rs_packet_intersect_robust
#define rsw_traverse_subtree rs_traverse_wide_subtree
#define rsw_traverse_recorded rs_traverse_wide_recorded
#define rsw_traverse rs_traverse_wide
#define rsw_leaf rs_wide_leaf
#define RSW_LEAF_FIRST RS_WIDE_LEAF_FIRST
#define RSW_LEAF_END RS_WIDE_LEAF_END
#define RSW_LEAF_LANES RS_WIDE_LEAF_LANES
#elif RS_WIDE_W == 8
#define rsw_f rs_f8
#define rsw_i rs_i8
#define rsw_splat rs8_splat
#define rsw_min rs8_min
#define rsw_max rs8_max
#define rsw_select rs8_select
#define rsw_fma rs8_fma
#define rsw_abs rs8_abs
#define rsw_bits rs8_bits
#define rsw_store rs8_store
#define rsw_load rs8_load
#define rsw_robust_t_bound rs8_robust_t_bound
#define RsWNode RsWide8Node
#define RsWPacket RsTriPacket8
#define RS_WSTACK RS_WIDE8_STACK_SIZE
#define RsWPlanes RsWide8Planes
#define rsw_planes rs_wide8_planes
#define rsw_slabs rs_wide8_slabs
#define rsw_slabs_robust rs_wide8_slabs_robust
#define rsw_boxes rs_wide8_boxes
#define rsw_boxes_robust rs_wide8_boxes_robust
#define rsw_intersect rs_packet8_intersect
#define RsWEdges RsTriEdges8
#define rsw_edges rs_tri_edges8
#define rsw_intersect_edges rs_packet8_intersect_edges
#define rsw_keep_nearest rs_wide8_keep_nearest
#define rsw_intersect_robust rs_packet8_intersect_robust
#define rsw_traverse_subtree rs_traverse_wide8_subtree
#define rsw_traverse_recorded rs_traverse_wide8_recorded
#define rsw_traverse rs_traverse_wide8
#define rsw_leaf rs_wide8_leaf
#define RSW_LEAF_FIRST RS_WIDE8_LEAF_FIRST
#define RSW_LEAF_END RS_WIDE8_LEAF_END
#define RSW_LEAF_LANES RS_WIDE8_LEAF_LANES
#else
#error "RS_WIDE_W must be 4 or 8 (traverse_wide.h, traverse_wide8.h)"
#endif

/* A node's RS_WIDE_W child boxes as the near and far planes of one 1/d octant (rs_octant), and its
 * valid lanes: choosing the near plane of each axis by the sign of 1/d once, instead of a min and a
 * max per box (lo <= hi, so the result is the same). The box tests below read a node through it; the
 * stream class (traverse_stream.h) reads it once for all the rays of one octant that reach a node. */
typedef struct {
  rsw_f near_x, far_x, near_y, far_y, near_z, far_z;
  rsw_i valid;
} RsWPlanes;

RS_INLINE RsWPlanes rsw_planes(RS_GLOBAL const RsWNode* n, int octant) {
  RS_GLOBAL const rsw_f* b = &n->lo_x; /* lo_x hi_x lo_y hi_y lo_z hi_z */
  const int nx = octant & 1, ny = (octant >> 1) & 1, nz = (octant >> 2) & 1;
  RsWPlanes p;
  p.near_x = b[nx], p.far_x = b[1 - nx];
  p.near_y = b[2 + ny], p.far_y = b[3 - ny];
  p.near_z = b[4 + nz], p.far_z = b[5 - nz];
  p.valid = n->valid;
  return p;
}

/* Slab test of the boxes (fast variant) for a ray of the planes' octant, rs_intersect_box's fused
 * distances per lane. Returns the hit lanes (with the node's valid lanes) and each box's entry distance. */
RS_INLINE rsw_i rsw_slabs(const RsWPlanes* b, const RsTraversalRay* r, float tmax, rsw_f* tnear_out) {
  const rsw_f ix = rsw_splat(r->inv_d.x), iy = rsw_splat(r->inv_d.y), iz = rsw_splat(r->inv_d.z);
  const rsw_f ax = rsw_splat(r->o_inv_d.x), ay = rsw_splat(r->o_inv_d.y), az = rsw_splat(r->o_inv_d.z);
  rsw_f tnx = rsw_fma(b->near_x, ix, ax), tfx = rsw_fma(b->far_x, ix, ax);
  rsw_f tny = rsw_fma(b->near_y, iy, ay), tfy = rsw_fma(b->far_y, iy, ay);
  rsw_f tnz = rsw_fma(b->near_z, iz, az), tfz = rsw_fma(b->far_z, iz, az);
  rsw_f tnear = rsw_max(rsw_max(tnx, tny), rsw_max(tnz, rsw_splat(r->tmin)));
  rsw_f tfar = rsw_min(rsw_min(tfx, tfy), rsw_min(tfz, rsw_splat(tmax)));
  *tnear_out = tnear;
  return (tnear <= tfar) & b->valid;
}

RS_INLINE rsw_i rsw_boxes(RsTraversalRay r, RS_GLOBAL const RsWNode* n, float tmax, rsw_f* tnear_out) {
  const RsWPlanes b = rsw_planes(n, rs_octant(r.inv_d.x, r.inv_d.y, r.inv_d.z));
  return rsw_slabs(&b, &r, tmax, tnear_out);
}

/* The conservative slab test (Ize 2013, as rs_intersect_box_robust) for an oblique ray (no axis
 * parallel: r->oblique) of the planes' octant: x, then y, then z into (tmin, tmax), far planes
 * scaled. */
RS_INLINE rsw_i rsw_slabs_robust(const RsWPlanes* b, const RsRobustRay* r, float tmax, rsw_f* tnear_out) {
  const rsw_f t0x = (b->near_x - r->o[0]) * r->inv_d[0], t1x = (b->far_x - r->o[0]) * r->inv_d[0];
  const rsw_f t0y = (b->near_y - r->o[1]) * r->inv_d[1], t1y = (b->far_y - r->o[1]) * r->inv_d[1];
  const rsw_f t0z = (b->near_z - r->o[2]) * r->inv_d[2], t1z = (b->far_z - r->o[2]) * r->inv_d[2];
  const rsw_f tnear = rsw_max(rsw_max(rsw_max(rsw_splat(r->tmin), t0x), t0y), t0z);
  const rsw_f tfar = rsw_min(rsw_min(rsw_min(rsw_splat(tmax), t1x * RS_SLAB_FAR_SCALE), t1y * RS_SLAB_FAR_SCALE),
                             t1z * RS_SLAB_FAR_SCALE);
  *tnear_out = tnear;
  return b->valid & (tnear <= tfar);
}

/* The conservative slab test on RS_WIDE_W boxes for any ray. Most rays have no parallel axis
 * (r->oblique) and take rsw_slabs_robust, straight-line code whose per-axis values stay in registers
 * across the traversal (docs/trace.md: 0.79–0.91x the time of the rolled loop); a ray with a parallel
 * axis takes the axis loop, where such an axis contributes only bmin <= o <= bmax. */
RS_INLINE rsw_i rsw_boxes_robust(const RsRobustRay* r, RS_GLOBAL const RsWNode* n, float tmax,
                                 rsw_f* tnear_out) {
  if (r->oblique) {
    const RsWPlanes planes = rsw_planes(n, rs_octant(r->inv_d[0], r->inv_d[1], r->inv_d[2]));
    return rsw_slabs_robust(&planes, r, tmax, tnear_out);
  }
  RS_GLOBAL const rsw_f* b = &n->lo_x;
  rsw_f tnear = rsw_splat(r->tmin);
  rsw_f tfar = rsw_splat(tmax);
  rsw_i inside = n->valid;
  RS_UNROLL
  for (int a = 0; a < 3; ++a) {
    if (r->parallel[a]) {
      inside = inside & (b[2 * a] <= r->o[a]) & (b[2 * a + 1] >= r->o[a]);
      continue;
    }
    const int neg = r->inv_d[a] < 0.0f;
    rsw_f t0 = (b[2 * a + neg] - r->o[a]) * r->inv_d[a];
    rsw_f t1 = (b[2 * a + 1 - neg] - r->o[a]) * r->inv_d[a];
    tnear = rsw_max(tnear, t0);
    tfar = rsw_min(tfar, t1 * RS_SLAB_FAR_SCALE);
  }
  *tnear_out = tnear;
  return inside & (tnear <= tfar);
}

/* A packet's first vertices and two edges (Möller–Trumbore's e1 = v1 - v0, e2 = v2 - v0) and its
 * valid lanes: what the test reads of the packet, so a caller testing many rays against one packet
 * (the stream class, traverse_stream.h) computes it once. */
typedef struct {
  rsw_f v0x, v0y, v0z, e1x, e1y, e1z, e2x, e2y, e2z;
  rsw_i valid;
} RsWEdges;

RS_INLINE RsWEdges rsw_edges(RS_GLOBAL const RsWPacket* p) {
  RsWEdges e;
  e.v0x = p->v0x, e.v0y = p->v0y, e.v0z = p->v0z;
  e.e1x = p->v1x - e.v0x, e.e1y = p->v1y - e.v0y, e.e1z = p->v1z - e.v0z;
  e.e2x = p->v2x - e.v0x, e.e2y = p->v2y - e.v0y, e.e2z = p->v2z - e.v0z;
  e.valid = p->valid;
  return e;
}

/* Möller–Trumbore on a packet of RS_WIDE_W triangles: per lane the operations of
 * rs_intersect_triangle in the same order. Returns the bits of the lanes hit within (tmin, tmax), with
 * t, u, v per lane. Every lane is carried to the end and tested once: a packet's lanes mostly fail, and
 * early exits after det, u and v mispredicted (without them: the stream 3-9 % faster on shadow rays,
 * 2-7 % on bounce rays; results/history/trace-kernels.md). */
RS_INLINE int rsw_intersect_edges(RsTraversalRay r, const RsWEdges* e, float tmax, rsw_f* t_out, rsw_f* u_out,
                                  rsw_f* v_out) {
  const rsw_f v0x = e->v0x, v0y = e->v0y, v0z = e->v0z;
  const rsw_f e1x = e->e1x, e1y = e->e1y, e1z = e->e1z;
  const rsw_f e2x = e->e2x, e2y = e->e2y, e2z = e->e2z;
  const rsw_f px = r.d.y * e2z - r.d.z * e2y, py = r.d.z * e2x - r.d.x * e2z, pz = r.d.x * e2y - r.d.y * e2x;
  const rsw_f det = e1x * px + e1y * py + e1z * pz;
  /* Lanes with det == 0 divide by 1 instead (and stay rejected): no inf in any lane. */
  const rsw_f inv_det = rsw_splat(1.0f) / rsw_select(det, rsw_splat(1.0f), det == 0.0f);
  const rsw_f sx = r.o.x - v0x, sy = r.o.y - v0y, sz = r.o.z - v0z;
  const rsw_f u = (sx * px + sy * py + sz * pz) * inv_det;
  const rsw_f qx = sy * e1z - sz * e1y, qy = sz * e1x - sx * e1z, qz = sx * e1y - sy * e1x;
  const rsw_f v = (r.d.x * qx + r.d.y * qy + r.d.z * qz) * inv_det;
  const rsw_f t = (e2x * qx + e2y * qy + e2z * qz) * inv_det;
  const int bits = rsw_bits(e->valid & (det != 0.0f) & (u >= 0.0f) & (u <= 1.0f) & (v >= 0.0f) & (u + v <= 1.0f) &
                            (t > r.tmin) & (t < tmax));
  *t_out = t;
  *u_out = u;
  *v_out = v;
  return bits;
}

RS_INLINE int rsw_intersect(RsTraversalRay r, RS_GLOBAL const RsWPacket* p, float tmax, rsw_f* t_out, rsw_f* u_out,
                            rsw_f* v_out) {
  const RsWEdges e = rsw_edges(p);
  return rsw_intersect_edges(r, &e, tmax, t_out, u_out, v_out);
}

/* The watertight test (Woop et al. 2013, as rs_intersect_triangle_robust) on a packet of RS_WIDE_W
 * triangles. The exact zero-area check is the packet's precomputed nondegenerate mask. */
RS_INLINE int rsw_intersect_robust(const RsRobustRay* r, const float* d, RS_GLOBAL const RsWPacket* p, float tmax,
                                   rsw_f* t_out, rsw_f* u_out, rsw_f* v_out) {
  RS_GLOBAL const rsw_f* p0 = &p->v0x; /* v0x v0y v0z, then v1, then v2 */
  RS_GLOBAL const rsw_f* p1 = &p->v1x;
  RS_GLOBAL const rsw_f* p2 = &p->v2x;
  const int kx = r->kx, ky = r->ky, kz = r->kz;
  const rsw_f az = p0[kz] - r->okz, bz = p1[kz] - r->okz, cz = p2[kz] - r->okz;
  rsw_f ax = (p0[kx] - r->okx) - r->sx * az, ay = (p0[ky] - r->oky) - r->sy * az;
  rsw_f bx = (p1[kx] - r->okx) - r->sx * bz, by = (p1[ky] - r->oky) - r->sy * bz;
  rsw_f cx = (p2[kx] - r->okx) - r->sx * cz, cy = (p2[ky] - r->oky) - r->sy * cz;
  rsw_f u = cx * by - cy * bx;
  rsw_f v = ax * cy - ay * cx;
  rsw_f w = bx * ay - by * ax;
#if RS_HAS_FP64
  {
    /* An edge function that rounded to 0: recompute that lane's three in double (exact). */
    const int zero = rsw_bits(p->valid & ((u == 0.0f) | (v == 0.0f) | (w == 0.0f)));
    if (zero) {
      float fax[RS_WIDE_W], fay[RS_WIDE_W], fbx[RS_WIDE_W], fby[RS_WIDE_W], fcx[RS_WIDE_W], fcy[RS_WIDE_W];
      float fu[RS_WIDE_W], fv[RS_WIDE_W], fw[RS_WIDE_W];
      rsw_store(ax, fax);
      rsw_store(ay, fay);
      rsw_store(bx, fbx);
      rsw_store(by, fby);
      rsw_store(cx, fcx);
      rsw_store(cy, fcy);
      rsw_store(u, fu);
      rsw_store(v, fv);
      rsw_store(w, fw);
      for (int i = 0; i < RS_WIDE_W; ++i) {
        if (!((zero >> i) & 1)) continue;
        fu[i] = (float)((double)fcx[i] * (double)fby[i] - (double)fcy[i] * (double)fbx[i]);
        fv[i] = (float)((double)fax[i] * (double)fcy[i] - (double)fay[i] * (double)fcx[i]);
        fw[i] = (float)((double)fbx[i] * (double)fay[i] - (double)fby[i] * (double)fax[i]);
      }
      u = rsw_load(fu);
      v = rsw_load(fv);
      w = rsw_load(fw);
    }
  }
#endif
  const int mixed = rsw_bits((u < 0.0f) | (v < 0.0f) | (w < 0.0f)) & rsw_bits((u > 0.0f) | (v > 0.0f) | (w > 0.0f));
  const rsw_f det = u + v + w;
  int bits = rsw_bits(p->valid & p->nondegenerate & (det != 0.0f)) & ~mixed;
  if (!bits) return 0;
  const rsw_f safe_det = rsw_select(det, rsw_splat(1.0f), det == 0.0f);
  const rsw_f azt = r->sz * az, bzt = r->sz * bz, czt = r->sz * cz;
  rsw_f t = (u * azt + v * bzt + w * czt) / safe_det;
  bits &= rsw_bits((t > r->tmin) & (t < tmax));
  if (!bits) return 0;
  {
    const rsw_f max_xt = rsw_max(rsw_max(rsw_abs(ax), rsw_abs(bx)), rsw_abs(cx));
    const rsw_f max_yt = rsw_max(rsw_max(rsw_abs(ay), rsw_abs(by)), rsw_abs(cy));
    const rsw_f max_zt = rsw_max(rsw_max(rsw_abs(azt), rsw_abs(bzt)), rsw_abs(czt));
    const rsw_f max_e = rsw_max(rsw_max(rsw_abs(u), rsw_abs(v)), rsw_abs(w));
    const int beyond = rsw_bits(t > rsw_robust_t_bound(max_xt, max_yt, max_zt, max_e, rsw_abs(safe_det)));
#if RS_HAS_FP64
    /* Lanes whose t is within its error bound of the origin (rare: slivers seen edge-on, where the
     * bound is far too pessimistic) are decided again in double, lane by lane, as
     * rs_intersect_triangle_robust does. */
    const int uncertain = bits & ~beyond;
    if (uncertain) {
      float ft[RS_WIDE_W], f0x[RS_WIDE_W], f0y[RS_WIDE_W], f0z[RS_WIDE_W], f1x[RS_WIDE_W], f1y[RS_WIDE_W];
      float f1z[RS_WIDE_W], f2x[RS_WIDE_W], f2y[RS_WIDE_W], f2z[RS_WIDE_W];
      rsw_store(t, ft);
      rsw_store(p->v0x, f0x), rsw_store(p->v0y, f0y), rsw_store(p->v0z, f0z);
      rsw_store(p->v1x, f1x), rsw_store(p->v1y, f1y), rsw_store(p->v1z, f1z);
      rsw_store(p->v2x, f2x), rsw_store(p->v2y, f2y), rsw_store(p->v2z, f2z);
      for (int i = 0; i < RS_WIDE_W; ++i) {
        if (!((uncertain >> i) & 1)) continue;
        if (!rs_robust_t_in_double(r, d, f0x[i], f0y[i], f0z[i], f1x[i], f1y[i], f1z[i], f2x[i], f2y[i], f2z[i], tmax,
                                   &ft[i]))
          bits &= ~(1 << i);
      }
      t = rsw_load(ft);
    }
#else
    bits &= beyond;
#endif
  }
  *t_out = t;
  *u_out = v / safe_det;
  *v_out = w / safe_det;
  return bits;
}

/* Of a packet's hit lanes (bits, with their t, u, v), the nearest one below the ray's closest hit so
 * far (the lowest lane among equal t) becomes its hit. Returns whether one did: every hit lane may
 * have rounded onto the closest t so far, and then nothing is nearer. */
RS_INLINE int rsw_keep_nearest(int bits, rsw_f tw, rsw_f uw, rsw_f vw, RS_GLOBAL const RsWPacket* p, RsHit* hit) {
  float ts[RS_WIDE_W], us[RS_WIDE_W], vs[RS_WIDE_W];
  rsw_store(tw, ts);
  rsw_store(uw, us);
  rsw_store(vw, vs);
  int best = -1;
  float best_t = hit->t;
  for (int i = 0; i < RS_WIDE_W; ++i)
    if (((bits >> i) & 1) && ts[i] < best_t) {
      best_t = ts[i];
      best = i;
    }
  if (best < 0) return 0;
  hit->t = best_t;
  hit->tri = p->id[best];
  hit->u = us[best];
  hit->v = vs[best];
  return 1;
}

/* The triangle packets of the leaf `ref` against one ray: hit becomes the closest hit so far (the
 * lane of smallest t below hit->t, ties by lane). Any hit (any_hit = 1) stops at the first packet
 * with a hit and returns 1; otherwise returns 0. Only the leaf's own lanes count (an 8-wide leaf may
 * share its packet: RS_WIDE8_LEAF_LANES, bvh_layout.h). */
RS_INLINE int rsw_leaf(RS_GLOBAL const RsWPacket* packets, rs_u32 ref, RsTraversalRay r, const RsRobustRay* rr,
                       const float* d, int robust, int any_hit, RsHit* hit) {
  const rs_u32 first = RSW_LEAF_FIRST(ref), end = RSW_LEAF_END(ref);
  const int lanes = RSW_LEAF_LANES(ref);
  for (rs_u32 pi = first; pi < end; ++pi) {
    rsw_f tw, uw, vw;
    const int bits = lanes & (robust ? rsw_intersect_robust(rr, d, &packets[pi], hit->t, &tw, &uw, &vw)
                                     : rsw_intersect(r, &packets[pi], hit->t, &tw, &uw, &vw));
    if (bits && rsw_keep_nearest(bits, tw, uw, vw, &packets[pi], hit) && any_hit) return 1;
  }
  return 0;
}

/* Closest hit (any_hit = 0) or first hit found (any_hit = 1), fast (robust = 0) or robust
 * (robust = 1), on the RS_WIDE_W-wide BVH. Nearest child first: a node's hit children are ordered
 * by entry distance (ties by lane), the nearest is visited next and the others pushed with their
 * distance, so a popped subtree that starts beyond the closest hit so far is skipped. Any-hit
 * rays skip the ordering (children in lane order): measured side by side on sibenik's bounce-1
 * shadow rays (4-wide), 1.13-1.15x faster; primary shadow rays within 2-4 %.
 * *node_visits, when not null, counts the wide nodes and leaves visited (cost heatmaps).
 * trail, when not null, receives every step's reference in visit order (a wide node's index, or a
 * leaf's RS_WIDE_LEAF reference: one id space, since inner indices never carry that bit), up to
 * trail_cap entries; *trail_len gets the full step count. This is the SIMT model's trail on the
 * layout the kernels walk (host/bench/metrics.cpp; kernels pass null and the recording compiles away).
 * Stack bound: RS_WIDE_STACK_SIZE / RS_WIDE8_STACK_SIZE (bvh_layout.h): a node pushes at most
 * RS_WIDE_W - 1 children, and the collapse bounds the tree's depth.
 * The walk itself starts at `start` (a wide node or a leaf reference) with the closest hit so far
 * `hit` (rs_miss(ray.tmax) for a whole traversal): the packet traversal's hybrid classes hand a
 * 4-wide subtree to a lone ray this way (traverse_packet.h). */
RS_INLINE RsHit rsw_traverse_subtree(RS_GLOBAL const RsWNode* nodes, RS_GLOBAL const RsWPacket* packets, RsRay ray,
                                     int robust, int any_hit, rs_u32 start, RsHit hit, rs_u32* node_visits,
                                     rs_u32* trail, rs_u32 trail_cap, rs_u32* trail_len) {
  RsTraversalRay r = rs_prepare_ray(ray);
  RsRobustRay rr = rs_prepare_robust_ray(ray);
  rs_u32 visits = 0;
  rs_u32 stack[RS_WSTACK];
  float stack_t[RS_WSTACK];
  int sp = 0;
  rs_u32 ref = start;
  int live = !robust || rr.valid;
  while (live) {
    if (trail && visits < trail_cap) trail[visits] = ref;
    ++visits;
    if (!(ref & RS_WIDE_LEAF)) {
      RS_GLOBAL const RsWNode* n = &nodes[ref];
      rsw_f tnear_w;
      const int bits =
          rsw_bits(robust ? rsw_boxes_robust(&rr, n, hit.t, &tnear_w) : rsw_boxes(r, n, hit.t, &tnear_w));
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
        float tnear[RS_WIDE_W];
        rsw_store(tnear_w, tnear);
        rs_u32 refs[RS_WIDE_W];
        float dist[RS_WIDE_W];
        int k = 0;
        /* The hit lanes in lane order, insertion-sorted by entry distance. At eight lanes the loop
         * walks the set bits (a ray enters few of a node's eight children): on sibenik 640x360,
         * fast, wide8 over wide went from 1.10-1.13x to 1.18-1.28x on primary and bounce1 rays (two
         * runs each, paired). At four lanes the unrolled lane loop stays: the bit loop gained
         * nothing measurable there (primary possibly slower, within the noise). */
#if RS_WIDE_W == 8
        for (int rest = bits; rest; rest &= rest - 1) {
          const int i = rs_lowest_bit(rest);
#else
        for (int i = 0; i < RS_WIDE_W; ++i) {
          if (!((bits >> i) & 1)) continue;
#endif
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
    } else if (rsw_leaf(packets, ref, r, &rr, ray.d, robust, any_hit, &hit)) {
      break; /* any hit: found */
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
  if (trail_len) *trail_len = visits;
  return hit;
}

/* A whole traversal from the root (always an inner node), with a trail. */
RS_INLINE RsHit rsw_traverse_recorded(RS_GLOBAL const RsWNode* nodes, RS_GLOBAL const RsWPacket* packets, RsRay ray,
                                      int robust, int any_hit, rs_u32* node_visits, rs_u32* trail, rs_u32 trail_cap,
                                      rs_u32* trail_len) {
  return rsw_traverse_subtree(nodes, packets, ray, robust, any_hit, 0, rs_miss(ray.tmax), node_visits, trail, trail_cap,
                              trail_len);
}

/* Without a trail: what the trace kernels call. */
RS_INLINE RsHit rsw_traverse(RS_GLOBAL const RsWNode* nodes, RS_GLOBAL const RsWPacket* packets, RsRay ray, int robust,
                             int any_hit, rs_u32* node_visits) {
  return rsw_traverse_recorded(nodes, packets, ray, robust, any_hit, node_visits, 0, 0, 0);
}

#undef rsw_f
#undef rsw_i
#undef rsw_splat
#undef rsw_min
#undef rsw_max
#undef rsw_select
#undef rsw_fma
#undef rsw_abs
#undef rsw_bits
#undef rsw_store
#undef rsw_load
#undef rsw_robust_t_bound
#undef RsWNode
#undef RsWPacket
#undef RS_WSTACK
#undef RsWPlanes
#undef rsw_planes
#undef rsw_slabs
#undef rsw_slabs_robust
#undef rsw_boxes
#undef rsw_boxes_robust
#undef rsw_intersect
#undef RsWEdges
#undef rsw_edges
#undef rsw_intersect_edges
#undef rsw_keep_nearest
#undef rsw_intersect_robust
#undef rsw_traverse_subtree
#undef rsw_traverse_recorded
#undef rsw_traverse
#undef rsw_leaf
#undef RSW_LEAF_FIRST
#undef RSW_LEAF_END
#undef RSW_LEAF_LANES
