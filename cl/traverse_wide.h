/* raysort — traversal of the 4-wide BVH (bvh_layout.h, RsWideNode / RsTriPacket): what the trace
 * kernels (cl/trace.cl) and the host reference (host/trace/tracer.cpp) run by default.
 */
#ifndef RAYSORT_TRAVERSE_WIDE_H
#define RAYSORT_TRAVERSE_WIDE_H

#include "intersect.h"
#include "lanes.h"

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
RS_INLINE int rs_packet_intersect_robust(const RsRobustRay* r, const float* d, RS_GLOBAL const RsTriPacket* p, float tmax,
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
  rs_f4 t = (u * azt + v * bzt + w * czt) / safe_det;
  bits &= rs4_bits((t > r->tmin) & (t < tmax));
  if (!bits) return 0;
  {
    const rs_f4 max_xt = rs4_max(rs4_max(rs4_abs(ax), rs4_abs(bx)), rs4_abs(cx));
    const rs_f4 max_yt = rs4_max(rs4_max(rs4_abs(ay), rs4_abs(by)), rs4_abs(cy));
    const rs_f4 max_zt = rs4_max(rs4_max(rs4_abs(azt), rs4_abs(bzt)), rs4_abs(czt));
    const rs_f4 max_e = rs4_max(rs4_max(rs4_abs(u), rs4_abs(v)), rs4_abs(w));
    const int beyond = rs4_bits(t > rs4_robust_t_bound(max_xt, max_yt, max_zt, max_e, rs4_abs(safe_det)));
#if RS_HAS_FP64
    /* Lanes whose t is within its error bound of the origin (rare: slivers seen edge-on, where the
     * bound is far too pessimistic) are decided again in double, lane by lane, as
     * rs_intersect_triangle_robust does. */
    const int uncertain = bits & ~beyond;
    if (uncertain) {
      float ft[4], f0x[4], f0y[4], f0z[4], f1x[4], f1y[4], f1z[4], f2x[4], f2y[4], f2z[4];
      rs4_store(t, ft);
      rs4_store(p->v0x, f0x), rs4_store(p->v0y, f0y), rs4_store(p->v0z, f0z);
      rs4_store(p->v1x, f1x), rs4_store(p->v1y, f1y), rs4_store(p->v1z, f1z);
      rs4_store(p->v2x, f2x), rs4_store(p->v2y, f2y), rs4_store(p->v2z, f2z);
      for (int i = 0; i < 4; ++i) {
        if (!((uncertain >> i) & 1)) continue;
        if (!rs_robust_t_in_double(r, d, f0x[i], f0y[i], f0z[i], f1x[i], f1y[i], f1z[i], f2x[i], f2y[i], f2z[i], tmax, &ft[i]))
          bits &= ~(1 << i);
      }
      t = rs4_load(ft);
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

/* Closest hit (any_hit = 0) or first hit found (any_hit = 1), fast (robust = 0) or robust
 * (robust = 1), on the 4-wide BVH. Nearest child first: a node's hit children are ordered by
 * entry distance (ties by lane), the nearest is visited next and the others pushed with their
 * distance, so a popped subtree that starts beyond the closest hit so far is skipped. Any-hit
 * rays skip the ordering (children in lane order): measured side by side on sibenik's bounce-1
 * shadow rays, 1.13-1.15x faster; primary shadow rays within 2-4 %.
 * *node_visits, when not null, counts the wide nodes and leaves visited (cost heatmaps).
 * trail, when not null, receives every step's reference in visit order (a wide node's index, or a
 * leaf's RS_WIDE_LEAF reference: one id space, since inner indices never carry that bit), up to
 * trail_cap entries; *trail_len gets the full step count. This is the SIMT model's trail on the
 * layout the kernels walk (host/bench/metrics.cpp; kernels pass null and the recording compiles away).
 * Stack bound: RS_WIDE_STACK_SIZE (bvh_layout.h).
 * The walk itself starts at `start` (a wide node or a leaf reference) with the closest hit so far
 * `hit` (rs_miss(ray.tmax) for a whole traversal): the packet traversal's hybrid classes hand a
 * subtree to a lone ray this way (traverse_packet.h). */
RS_INLINE RsHit rs_traverse_wide_subtree(RS_GLOBAL const RsWideNode* nodes, RS_GLOBAL const RsTriPacket* packets,
                                         RsRay ray, int robust, int any_hit, rs_u32 start, RsHit hit,
                                         rs_u32* node_visits, rs_u32* trail, rs_u32 trail_cap, rs_u32* trail_len) {
  RsTraversalRay r = rs_prepare_ray(ray);
  RsRobustRay rr = rs_prepare_robust_ray(ray);
  rs_u32 visits = 0;
  rs_u32 stack[RS_WIDE_STACK_SIZE];
  float stack_t[RS_WIDE_STACK_SIZE];
  int sp = 0;
  rs_u32 ref = start;
  int live = !robust || rr.valid;
  while (live) {
    if (trail && visits < trail_cap) trail[visits] = ref;
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
        const int bits = robust ? rs_packet_intersect_robust(&rr, ray.d, &packets[pi], hit.t, &t4, &u4, &v4)
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
        if (best < 0) continue; /* every hit lane rounded onto the closest t so far: nothing nearer */
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
  if (trail_len) *trail_len = visits;
  return hit;
}

/* A whole traversal from the root (always an inner node), with a trail. */
RS_INLINE RsHit rs_traverse_wide_recorded(RS_GLOBAL const RsWideNode* nodes, RS_GLOBAL const RsTriPacket* packets,
                                          RsRay ray, int robust, int any_hit, rs_u32* node_visits, rs_u32* trail,
                                          rs_u32 trail_cap, rs_u32* trail_len) {
  return rs_traverse_wide_subtree(nodes, packets, ray, robust, any_hit, 0, rs_miss(ray.tmax), node_visits, trail,
                                  trail_cap, trail_len);
}

/* Without a trail: what the trace kernels call. */
RS_INLINE RsHit rs_traverse_wide(RS_GLOBAL const RsWideNode* nodes, RS_GLOBAL const RsTriPacket* packets, RsRay ray,
                                 int robust, int any_hit, rs_u32* node_visits) {
  return rs_traverse_wide_recorded(nodes, packets, ray, robust, any_hit, node_visits, 0, 0, 0);
}

#endif /* RAYSORT_TRAVERSE_WIDE_H */
