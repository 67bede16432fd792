/* raysort — ray-packet traversal of the 4-wide BVH: RS_PACKET_W consecutive rays of the batch's
 * order (4, 8 or 16) walk the tree together, one ray per vector lane (docs/trace.md, "Trace
 * classes"). On a CPU this is what a warp is on a GPU: the packet visits every node that any of
 * its active rays enters, so its cost is that of the union of its rays' paths, and the order of
 * the rays decides how much of that union each ray shares. The scheme is the packet traversal of
 * Wald, Slusallek, Benthin and Wagner (2001), over the 4-wide tree as Embree's packet kernels do.
 *
 * - An active mask per node: the lanes whose ray entered the node's box and whose interval still
 *   reaches it. A child is entered when any active lane's slab test hits its box (with that lane's
 *   closest hit so far as the far bound); the child's active lanes are those lanes.
 * - Nearest child first, by the packet's first active ray: the entered children are ordered by that
 *   lane's entry distance (a child it does not enter comes last; ties by child slot), the nearest
 *   visited, the others pushed with their per-lane entry distances and active lanes; a popped entry
 *   keeps only the lanes whose entry distance does not lie beyond their closest hit so far.
 * - Leaves: each triangle is tested against every active lane at once, with per lane exactly the
 *   arithmetic of the single-ray tests (rs_packet_intersect, rs_packet_intersect_robust, which are
 *   those of intersect.h), so a triangle is hit or missed as there; which of two equally near
 *   triangles a lane keeps may differ from the single-ray traversal, because the order differs.
 * - Any hit (shadow rays): a lane that finds a hit is finished; the packet ends when every lane is.
 * - Hybrid (single_at > 0, the hybrid classes): a node or leaf reached by at most single_at active
 *   lanes is handed to each of them alone (rs_traverse_wide_subtree, the single-ray traversal from
 *   that node with the lane's closest hit so far), as Embree's hybrid kernels switch from packets
 *   to single rays when too few stay active (Benthin, Wald, Woop, Ernst and Wächter 2012).
 *
 * Per lane the box test is that of rs_wide_boxes / rs_wide_boxes_robust (the near plane chosen by
 * the sign of the lane's 1/d), so the only difference to a ray traced alone is the order in which
 * it meets the nodes its path holds; the stack bound is the single-ray one (a node pushes at most
 * three children, the wide tree is at most 32 deep: RS_WIDE_STACK_SIZE).
 *
 * Include with RS_PACKET_W defined; no include guard (see packet_lanes.h).
 */
#include "intersect.h"
#include "lanes.h"
#include "packet_lanes.h"
#include "traverse_wide.h"

/* The packet's rays, transposed: one lane per ray. Fast variant: inv_d = rs_safe_rcp(d) and ax..az
 * = −(o · 1/d), rs_prepare_ray's o_inv_d (the fused slab test's offsets, rs_packet_box). Robust:
 * inv_d = 0 where the lane's axis is parallel (par_*), the Woop et al. ray-space transform as
 * per-lane selectors of the permuted axes, okx..oky the permuted origin, sx..sz the shear. */
typedef struct {
  rs_pf ox, oy, oz, dx, dy, dz, ix, iy, iz, tmin;
  rs_pf ax, ay, az;                      /* fast: −(o · 1/d) */
  rs_pi neg_x, neg_y, neg_z;             /* 1/d < 0: the lane's near plane is the box's upper bound */
  rs_pi par_x, par_y, par_z;             /* robust: parallel axes */
  rs_pi kx1, kx2, ky1, ky2, kz1, kz2;    /* robust: kx == 1, kx == 2, ... */
  rs_pf okx, oky, okz, sx, sy, sz;       /* robust */
  int any_parallel;                      /* robust: some active lane has a parallel axis */
} RsRayPacket;

/* The robust variant's per-ray set-up (rs_prepare_robust_ray) for every lane at once: the same
 * comparisons, selections and IEEE divisions per lane, so each lane gets the bits the single-ray
 * set-up gives its ray, without a call and a spill per lane. (Called per lane it was a third of
 * the robust packet kernels' samples in `make bench`, whose small scenes need few steps a ray.)
 * Sets the robust fields of p (inv_d, parallel axes, axis selectors, origin and shear) and returns
 * the lanes whose direction is valid (a largest |d| component above 0 and finite). */
RS_INLINE int rs_packet_prepare_robust(rs_pf dx, rs_pf dy, rs_pf dz, RsRayPacket* p, int* parallel_bits) {
  const rs_pf zero = rsp_splat(0.0f), one = rsp_splat(1.0f);
  const rs_pf adx = rsp_abs(dx), ady = rsp_abs(dy), adz = rsp_abs(dz);
  /* kz: the axis of largest |d| (ad0 > ad1 ? (ad0 > ad2 ? 0 : 2) : (ad1 > ad2 ? 1 : 2)). */
  const rs_pi gt01 = adx > ady;
  const rs_pi kz0 = gt01 & (adx > adz), kz1 = ~gt01 & (ady > adz), kz2 = ~(kz0 | kz1);
  const rs_pf dmax = rsp_select(rsp_select(adz, ady, kz1), adx, kz0);
  const rs_pi valid = (dmax > zero) & (dmax <= rsp_splat(3.4028234e38f));
  const rs_pf threshold = dmax * RS_PARALLEL_FRACTION;
  p->par_x = ~(adx > threshold), p->par_y = ~(ady > threshold), p->par_z = ~(adz > threshold);
  p->ix = rsp_select(one / dx, zero, p->par_x);
  p->iy = rsp_select(one / dy, zero, p->par_y);
  p->iz = rsp_select(one / dz, zero, p->par_z);
  *parallel_bits = rsp_bits(p->par_x | p->par_y | p->par_z);
  /* kx, ky: the next two axes cyclically (kz 0 -> 1, 2; 1 -> 2, 0; 2 -> 0, 1), swapped where
   * d[kz] < 0 so the ray-space transform keeps its winding. */
  const rs_pf dkz = rsp_select(rsp_select(dz, dy, kz1), dx, kz0);
  const rs_pi neg = dkz < zero, pos = ~neg;
  const rs_pi kx0 = (kz2 & pos) | (kz1 & neg), kx1 = (kz0 & pos) | (kz2 & neg), kx2 = (kz1 & pos) | (kz0 & neg);
  const rs_pi ky0 = (kz1 & pos) | (kz2 & neg), ky1 = (kz2 & pos) | (kz0 & neg), ky2 = (kz0 & pos) | (kz1 & neg);
  p->kx1 = kx1, p->kx2 = kx2, p->ky1 = ky1, p->ky2 = ky2, p->kz1 = kz1, p->kz2 = kz2;
  p->okx = rsp_select(rsp_select(p->oz, p->oy, kx1), p->ox, kx0);
  p->oky = rsp_select(rsp_select(p->oz, p->oy, ky1), p->ox, ky0);
  p->okz = rsp_select(rsp_select(p->oz, p->oy, kz1), p->ox, kz0);
  const rs_pf dkx = rsp_select(rsp_select(dz, dy, kx1), dx, kx0);
  const rs_pf dky = rsp_select(rsp_select(dz, dy, ky1), dx, ky0);
  const rs_pf safe_dz = rsp_select(one, dkz, valid);
  p->sx = rsp_select(zero, dkx / safe_dz, valid);
  p->sy = rsp_select(zero, dky / safe_dz, valid);
  p->sz = one / safe_dz;
  return rsp_bits(valid);
}

/* The rest of a packet's set-up once its rays are in their lanes (and, fast variant, ix..iz hold
 * rs_safe_rcp of their directions): the robust fields, or none, and the octant masks. Returns the
 * active lanes: in_range, and for the robust variant with a valid direction. */
RS_INLINE int rs_packet_prepare(int robust, int in_range, RsRayPacket* p) {
  const rs_pf zero = rsp_splat(0.0f);
  int active = in_range;
  if (robust) {
    int parallel = 0;
    active &= rs_packet_prepare_robust(p->dx, p->dy, p->dz, p, &parallel);
    p->any_parallel = (parallel & active) != 0;
  } else {
    const rs_pi none = rsp_splati(0);
    p->par_x = p->par_y = p->par_z = none;
    p->kx1 = p->kx2 = p->ky1 = p->ky2 = p->kz1 = p->kz2 = none;
    p->okx = p->oky = p->okz = p->sx = p->sy = p->sz = zero;
    p->any_parallel = 0;
    p->ax = rsp_neg(p->ox * p->ix), p->ay = rsp_neg(p->oy * p->iy), p->az = rsp_neg(p->oz * p->iz);
  }
  p->neg_x = p->ix < zero, p->neg_y = p->iy < zero, p->neg_z = p->iz < zero;
  return active;
}

#if defined(__OPENCL_VERSION__) && (RS_PACKET_W == 16 || RS_PACKET_W == 8)
/* Packets of rays in a row (device, 8 or 16 lanes): their rays loaded and their hits stored a row at a
 * time, transposed by shuffles, where the lane loops' loads and stores became gathers per field
 * (vgatherqps) and stores per lane through private memory: on the AMD EPYC a fifth of coherent16's
 * samples on primary rays, whose kernel is 1.2x faster with rows (results/history/trace-kernels.md,
 * "Rays in a row"). The same values in the same lanes, so the same bits as the lane loops. */
#define RS_PACKET_ROWS 1
typedef RS_PACKET_CAT(uint, RS_PACKET_W) rs_pu;

/* Whether the packet's rays lie one after another in memory (order[first + i] = order[first] + i,
 * every lane in range): the batch's own order and every permuted one (docs/trace.md, "Rays in a row"). */
RS_INLINE int rs_packet_rays_in_a_row(RS_GLOBAL const rs_u32* order, rs_u32 first, rs_u32 count) {
  if (first > count || count - first < (rs_u32)RS_PACKET_W) return 0;
  const rs_pu o = RS_PACKET_CAT(vload, RS_PACKET_W)(0, order + first);
#if RS_PACKET_W == 16
  const rs_pu lane = (uint16)(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
#else
  const rs_pu lane = (uint8)(0, 1, 2, 3, 4, 5, 6, 7);
#endif
  return all(o == (rs_pu)(o.s0) + lane);
}

/* rs_safe_rcp (intersect.h) in every lane: the same comparison, sign and IEEE division per lane, so the
 * rows give the bits the lane loop's per-lane rs_prepare_ray gives. Its vector form, kept in step with
 * the scalar one: the lane loop calls the scalar one per lane, which PoCL vectorises there only because
 * the loop is a loop. */
RS_INLINE rs_pf rs_packet_safe_rcp(rs_pf d) {
  const rs_pi sign = rsp_as_int(d) & rsp_splati((int)0x80000000u);
  const rs_pf tiny_signed = RS_PACKET_CAT(as_float, RS_PACKET_W)(rsp_splati(rs_float_as_int(1e-30f)) | sign);
  return rsp_splat(1.0f) / rsp_select(d, tiny_signed, fabs(d) < rsp_splat(1e-30f));
}

/* The packet's rays from row[0..W): 64-byte loads of two rays ([o tmin d tmax] each), then rounds of
 * two-source shuffles. f[k] receives field k (o.x o.y o.z tmin d.x d.y d.z tmax) of every lane, and
 * rays_out each lane's RsRay. */
RS_INLINE void rs_packet_rows_transpose(RS_GLOBAL const RsRay* row, RsRay* rays_out, rs_pf* f) {
  RS_GLOBAL const float* src = (RS_GLOBAL const float*)row;
  float16 a[RS_PACKET_W / 2]; /* rays 2k and 2k + 1 */
  RS_UNROLL
  for (int k = 0; k < RS_PACKET_W / 2; ++k) {
    a[k] = vload16(k, src);
    vstore16(a[k], k, (float*)rays_out);
  }
  /* Round 1: rays 4k..4k+3, fields 0-3 (b[2k]) and 4-7 (b[2k + 1]), lane 4 * field + ray. */
  const uint16 m1lo = (uint16)(0, 8, 16, 24, 1, 9, 17, 25, 2, 10, 18, 26, 3, 11, 19, 27);
  const uint16 m1hi = m1lo + (uint16)(4);
  float16 b[RS_PACKET_W / 2];
  RS_UNROLL
  for (int k = 0; k < RS_PACKET_W / 4; ++k) {
    b[2 * k] = shuffle2(a[2 * k], a[2 * k + 1], m1lo);
    b[2 * k + 1] = shuffle2(a[2 * k], a[2 * k + 1], m1hi);
  }
#if RS_PACKET_W == 8
  /* Round 2: every lane of one field, b[h] holding rays 0-3 and b[2 + h] rays 4-7 of fields 4h..4h+3.
   * (Into eight lanes directly: Oclgrind reads the halves .lo and .hi of a shuffle's result as
   * uninitialized.) */
  const uint8 m2 = (uint8)(0, 1, 2, 3, 16, 17, 18, 19);
  RS_UNROLL
  for (int h = 0; h < 2; ++h) {
    RS_UNROLL
    for (int q = 0; q < 4; ++q) f[4 * h + q] = shuffle2(b[h], b[2 + h], m2 + (uint8)(4 * q));
  }
#else
  /* Round 2: rays 8j..8j+7, two fields each, lane 8 * field + ray: c[4j + 2h + g] holds fields
   * 4h + 2g and 4h + 2g + 1. */
  const uint16 m2lo = (uint16)(0, 1, 2, 3, 16, 17, 18, 19, 4, 5, 6, 7, 20, 21, 22, 23);
  const uint16 m2hi = m2lo + (uint16)(8);
  float16 c[RS_PACKET_W / 2];
  RS_UNROLL
  for (int j = 0; j < RS_PACKET_W / 8; ++j) {
    RS_UNROLL
    for (int h = 0; h < 2; ++h) {
      c[4 * j + 2 * h] = shuffle2(b[4 * j + h], b[4 * j + 2 + h], m2lo);
      c[4 * j + 2 * h + 1] = shuffle2(b[4 * j + h], b[4 * j + 2 + h], m2hi);
    }
  }
  /* Round 3: rays 0..15 of one field. */
  const uint16 m3lo = (uint16)(0, 1, 2, 3, 4, 5, 6, 7, 16, 17, 18, 19, 20, 21, 22, 23);
  const uint16 m3hi = m3lo + (uint16)(8);
  RS_UNROLL
  for (int q = 0; q < 4; ++q) {
    f[2 * q] = shuffle2(c[q], c[4 + q], m3lo);
    f[2 * q + 1] = shuffle2(c[q], c[4 + q], m3hi);
  }
#endif
}

/* The packet's hits into hits[0..W) (RsHit: t, tri, u, v): shuffles interleave the four fields, and
 * 64-byte stores write four hits each. */
RS_INLINE void rs_packet_store_hits_in_a_row(rs_pf t, rs_pi tri, rs_pf u, rs_pf v, RS_GLOBAL RsHit* hits) {
  const rs_pf tri_bits = RS_PACKET_CAT(as_float, RS_PACKET_W)(tri);
  const uint16 quad_lo = (uint16)(0, 1, 16, 17, 2, 3, 18, 19, 4, 5, 20, 21, 6, 7, 22, 23);
  const uint16 quad_hi = quad_lo + (uint16)(8);
  RS_GLOBAL float* out = (RS_GLOBAL float*)hits;
#if RS_PACKET_W == 16
  const uint16 pair_lo = (uint16)(0, 16, 1, 17, 2, 18, 3, 19, 4, 20, 5, 21, 6, 22, 7, 23);
  const uint16 pair_hi = pair_lo + (uint16)(8);
  const float16 t_tri_lo = shuffle2(t, tri_bits, pair_lo), t_tri_hi = shuffle2(t, tri_bits, pair_hi);
  const float16 u_v_lo = shuffle2(u, v, pair_lo), u_v_hi = shuffle2(u, v, pair_hi);
  vstore16(shuffle2(t_tri_lo, u_v_lo, quad_lo), 0, out);
  vstore16(shuffle2(t_tri_lo, u_v_lo, quad_hi), 1, out);
  vstore16(shuffle2(t_tri_hi, u_v_hi, quad_lo), 2, out);
  vstore16(shuffle2(t_tri_hi, u_v_hi, quad_hi), 3, out);
#else
  const uint16 pair = (uint16)(0, 8, 1, 9, 2, 10, 3, 11, 4, 12, 5, 13, 6, 14, 7, 15);
  const float16 t_tri = shuffle2(t, tri_bits, pair), u_v = shuffle2(u, v, pair);
  vstore16(shuffle2(t_tri, u_v, quad_lo), 0, out);
  vstore16(shuffle2(t_tri, u_v, quad_hi), 1, out);
#endif
}
#endif

/* Loads rays[order[first + i]] into lane i (lanes past count stay inactive) and returns the
 * active lanes as bits: in range, and for the robust variant a valid direction (as
 * rs_prepare_robust_ray; an invalid one hits nothing, as in the single-ray traversal). rays_out
 * keeps each lane's RsRay for the rare per-lane paths (the double-precision t). */
RS_INLINE int rs_packet_load(RS_GLOBAL const RsRay* rays, RS_GLOBAL const rs_u32* order, rs_u32 first, rs_u32 count,
                             int robust, RsRay* rays_out, RsRayPacket* p, rs_pf* tmax_out) {
#ifdef RS_PACKET_ROWS
  if (rs_packet_rays_in_a_row(order, first, count)) {
    rs_pf f[8];
    rs_packet_rows_transpose(rays + order[first], rays_out, f);
    p->ox = f[0], p->oy = f[1], p->oz = f[2], p->tmin = f[3];
    p->dx = f[4], p->dy = f[5], p->dz = f[6];
    *tmax_out = f[7];
    if (!robust) p->ix = rs_packet_safe_rcp(f[4]), p->iy = rs_packet_safe_rcp(f[5]), p->iz = rs_packet_safe_rcp(f[6]);
    return rs_packet_prepare(robust, (1 << RS_PACKET_W) - 1, p);
  }
#endif
  float ox[RS_PACKET_W], oy[RS_PACKET_W], oz[RS_PACKET_W], dx[RS_PACKET_W], dy[RS_PACKET_W], dz[RS_PACKET_W];
  float ix[RS_PACKET_W], iy[RS_PACKET_W], iz[RS_PACKET_W], tmin[RS_PACKET_W], tmax[RS_PACKET_W];
  int in_range = 0;
  for (int i = 0; i < RS_PACKET_W; ++i) {
    RsRay ray;
    if (first + (rs_u32)i < count) {
      ray = rays[order[first + (rs_u32)i]];
      in_range |= 1 << i;
    } else {
      /* A lane past the batch's end: a harmless ray that never becomes active. */
      ray.o[0] = ray.o[1] = ray.o[2] = 0.0f;
      ray.d[0] = ray.d[1] = 0.0f;
      ray.d[2] = 1.0f;
      ray.tmin = 0.0f;
      ray.tmax = 0.0f;
    }
    rays_out[i] = ray;
    ox[i] = ray.o[0], oy[i] = ray.o[1], oz[i] = ray.o[2];
    dx[i] = ray.d[0], dy[i] = ray.d[1], dz[i] = ray.d[2];
    tmin[i] = ray.tmin, tmax[i] = ray.tmax;
    if (!robust) {
      const RsTraversalRay tr = rs_prepare_ray(ray);
      ix[i] = tr.inv_d.x, iy[i] = tr.inv_d.y, iz[i] = tr.inv_d.z;
    }
  }
  p->ox = rsp_load(ox), p->oy = rsp_load(oy), p->oz = rsp_load(oz);
  p->dx = rsp_load(dx), p->dy = rsp_load(dy), p->dz = rsp_load(dz);
  p->tmin = rsp_load(tmin);
  *tmax_out = rsp_load(tmax);
  if (!robust) p->ix = rsp_load(ix), p->iy = rsp_load(iy), p->iz = rsp_load(iz);
  return rs_packet_prepare(robust, in_range, p);
}

/* One axis of the slab test for every lane: the distances to the lane's near plane (the box's upper
 * bound where 1/d < 0, as rs_wide_boxes chooses it) and to its far plane, (plane − o) · 1/d: the
 * robust variant's form, and the coherent packets' (rs_packet_box_unfused). */
RS_INLINE void rs_packet_slab(float lo, float hi, rs_pf o, rs_pf inv_d, rs_pi neg, rs_pf* t_near, rs_pf* t_far) {
  const rs_pf bl = rsp_splat(lo), bh = rsp_splat(hi);
  *t_near = (rsp_select(bl, bh, neg) - o) * inv_d;
  *t_far = (rsp_select(bh, bl, neg) - o) * inv_d;
}

/* The same axis with the fast variant's fused distances, fma(plane, 1/d, −o·1/d) (rs_intersect_box). */
RS_INLINE void rs_packet_slab_fused(float lo, float hi, rs_pf inv_d, rs_pf o_inv_d, rs_pi neg, rs_pf* t_near,
                                    rs_pf* t_far) {
  const rs_pf bl = rsp_splat(lo), bh = rsp_splat(hi);
  *t_near = rsp_fma(rsp_select(bl, bh, neg), inv_d, o_inv_d);
  *t_far = rsp_fma(rsp_select(bh, bl, neg), inv_d, o_inv_d);
}

/* Slab test of one child box (lo/hi per axis) against every lane, fast variant: per lane the
 * operations of rs_wide_boxes, with fused distances (rs_packet_box) or unfused ones (plane − o) · 1/d
 * (rs_packet_box_unfused, rs_intersect_box_unfused's, for the coherent packets, traverse_coherent.h:
 * their frustum bounds these exactly, where bounding the fused ones cost coherent16 8-15 % on primary
 * rays; results/history/trace-kernels.md, "The fused slab test"). Returns the lanes hit (as a -1/0
 * mask) and their entry distances. `fused` is a constant at every call. */
RS_INLINE rs_pi rs_packet_box_form(const RsRayPacket* p, float lo_x, float hi_x, float lo_y, float hi_y, float lo_z,
                                   float hi_z, rs_pf tmax, rs_pf* tnear_out, int fused) {
  rs_pf tnx, tfx, tny, tfy, tnz, tfz;
  if (fused) {
    rs_packet_slab_fused(lo_x, hi_x, p->ix, p->ax, p->neg_x, &tnx, &tfx);
    rs_packet_slab_fused(lo_y, hi_y, p->iy, p->ay, p->neg_y, &tny, &tfy);
    rs_packet_slab_fused(lo_z, hi_z, p->iz, p->az, p->neg_z, &tnz, &tfz);
  } else {
    rs_packet_slab(lo_x, hi_x, p->ox, p->ix, p->neg_x, &tnx, &tfx);
    rs_packet_slab(lo_y, hi_y, p->oy, p->iy, p->neg_y, &tny, &tfy);
    rs_packet_slab(lo_z, hi_z, p->oz, p->iz, p->neg_z, &tnz, &tfz);
  }
  const rs_pf tnear = rsp_max(rsp_max(tnx, tny), rsp_max(tnz, p->tmin));
  const rs_pf tfar = rsp_min(rsp_min(tfx, tfy), rsp_min(tfz, tmax));
  *tnear_out = tnear;
  return tnear <= tfar;
}
RS_INLINE rs_pi rs_packet_box(const RsRayPacket* p, float lo_x, float hi_x, float lo_y, float hi_y, float lo_z, float hi_z,
                              rs_pf tmax, rs_pf* tnear_out) {
  return rs_packet_box_form(p, lo_x, hi_x, lo_y, hi_y, lo_z, hi_z, tmax, tnear_out, 1);
}
RS_INLINE rs_pi rs_packet_box_unfused(const RsRayPacket* p, float lo_x, float hi_x, float lo_y, float hi_y, float lo_z,
                                      float hi_z, rs_pf tmax, rs_pf* tnear_out) {
  return rs_packet_box_form(p, lo_x, hi_x, lo_y, hi_y, lo_z, hi_z, tmax, tnear_out, 0);
}

/* The conservative slab test (Ize 2013) of one child box against every lane: per lane the
 * operations of rs_wide_boxes_robust. A lane's parallel axis contributes only bmin <= o <= bmax;
 * packets without such a lane (nearly all) skip those selects. */
RS_INLINE rs_pi rs_packet_box_robust(const RsRayPacket* p, float lo_x, float hi_x, float lo_y, float hi_y, float lo_z,
                                     float hi_z, rs_pf tmax, rs_pf* tnear_out) {
  rs_pf t0x, t1x, t0y, t1y, t0z, t1z;
  rs_packet_slab(lo_x, hi_x, p->ox, p->ix, p->neg_x, &t0x, &t1x);
  rs_packet_slab(lo_y, hi_y, p->oy, p->iy, p->neg_y, &t0y, &t1y);
  rs_packet_slab(lo_z, hi_z, p->oz, p->iz, p->neg_z, &t0z, &t1z);
  const rs_pf bl_x = rsp_splat(lo_x), bh_x = rsp_splat(hi_x);
  const rs_pf bl_y = rsp_splat(lo_y), bh_y = rsp_splat(hi_y);
  const rs_pf bl_z = rsp_splat(lo_z), bh_z = rsp_splat(hi_z);
  const rs_pf scale = rsp_splat(RS_SLAB_FAR_SCALE);
  if (!p->any_parallel) {
    /* rs_wide_boxes_robust's order: x, then y, then z into (tmin, tmax). */
    const rs_pf tnear = rsp_max(rsp_max(rsp_max(p->tmin, t0x), t0y), t0z);
    const rs_pf tfar = rsp_min(rsp_min(rsp_min(tmax, t1x * scale), t1y * scale), t1z * scale);
    *tnear_out = tnear;
    return tnear <= tfar;
  }
  rs_pf tnear = p->tmin, tfar = tmax;
  rs_pi inside = rsp_splati(-1);
  tnear = rsp_select(rsp_max(tnear, t0x), tnear, p->par_x);
  tfar = rsp_select(rsp_min(tfar, t1x * scale), tfar, p->par_x);
  inside = inside & (~p->par_x | ((bl_x <= p->ox) & (bh_x >= p->ox)));
  tnear = rsp_select(rsp_max(tnear, t0y), tnear, p->par_y);
  tfar = rsp_select(rsp_min(tfar, t1y * scale), tfar, p->par_y);
  inside = inside & (~p->par_y | ((bl_y <= p->oy) & (bh_y >= p->oy)));
  tnear = rsp_select(rsp_max(tnear, t0z), tnear, p->par_z);
  tfar = rsp_select(rsp_min(tfar, t1z * scale), tfar, p->par_z);
  inside = inside & (~p->par_z | ((bl_z <= p->oz) & (bh_z >= p->oz)));
  *tnear_out = tnear;
  return inside & (tnear <= tfar);
}

/* Möller–Trumbore of one triangle against the lanes in `lanes` (bits), fast variant: per lane the
 * operations of rs_packet_intersect. Returns the lanes hit within (tmin, tmax), with t, u, v. */
RS_INLINE int rs_packet_triangle(const RsRayPacket* p, int lanes, float v0x, float v0y, float v0z, float v1x, float v1y,
                                 float v1z, float v2x, float v2y, float v2z, rs_pf tmax, rs_pf* t_out, rs_pf* u_out,
                                 rs_pf* v_out) {
  const float e1x = v1x - v0x, e1y = v1y - v0y, e1z = v1z - v0z;
  const float e2x = v2x - v0x, e2y = v2y - v0y, e2z = v2z - v0z;
  const rs_pf E1x = rsp_splat(e1x), E1y = rsp_splat(e1y), E1z = rsp_splat(e1z);
  const rs_pf E2x = rsp_splat(e2x), E2y = rsp_splat(e2y), E2z = rsp_splat(e2z);
  const rs_pf px = p->dy * E2z - p->dz * E2y, py = p->dz * E2x - p->dx * E2z, pz = p->dx * E2y - p->dy * E2x;
  const rs_pf det = E1x * px + E1y * py + E1z * pz;
  const rs_pf zero = rsp_splat(0.0f), one = rsp_splat(1.0f);
  int bits = lanes & rsp_bits(det != zero);
  if (!bits) return 0;
  const rs_pf inv_det = one / rsp_select(det, one, det == zero);
  const rs_pf sx = p->ox - rsp_splat(v0x), sy = p->oy - rsp_splat(v0y), sz = p->oz - rsp_splat(v0z);
  const rs_pf u = (sx * px + sy * py + sz * pz) * inv_det;
  bits &= rsp_bits((u >= zero) & (u <= one));
  const rs_pf qx = sy * E1z - sz * E1y, qy = sz * E1x - sx * E1z, qz = sx * E1y - sy * E1x;
  const rs_pf v = (p->dx * qx + p->dy * qy + p->dz * qz) * inv_det;
  bits &= rsp_bits((v >= zero) & (u + v <= one));
  const rs_pf t = (E2x * qx + E2y * qy + E2z * qz) * inv_det;
  bits &= rsp_bits((t > p->tmin) & (t < tmax));
  *t_out = t;
  *u_out = u;
  *v_out = v;
  return bits;
}

/* One coordinate of a vertex in each lane's permuted axis order (the lane's kx, ky or kz). */
RS_INLINE rs_pf rs_packet_axis(float x, float y, float z, rs_pi is1, rs_pi is2) {
  return rsp_select(rsp_select(rsp_splat(x), rsp_splat(y), is1), rsp_splat(z), is2);
}

RS_DEFINE_T_BOUND(rsp_robust_t_bound, rs_pf)

/* The watertight test (Woop et al. 2013) of one triangle against the lanes in `lanes`: per lane the
 * operations of rs_packet_intersect_robust (so of rs_intersect_triangle_robust), with the lane's own
 * ray-space transform. nondegenerate: the triangle's precomputed exact nonzero-area flag. */
RS_INLINE int rs_packet_triangle_robust(const RsRayPacket* p, const RsRay* rays, int lanes, float v0x, float v0y,
                                        float v0z, float v1x, float v1y, float v1z, float v2x, float v2y, float v2z,
                                        rs_pf tmax, rs_pf* t_out, rs_pf* u_out, rs_pf* v_out) {
  const rs_pf az = rs_packet_axis(v0x, v0y, v0z, p->kz1, p->kz2) - p->okz;
  const rs_pf bz = rs_packet_axis(v1x, v1y, v1z, p->kz1, p->kz2) - p->okz;
  const rs_pf cz = rs_packet_axis(v2x, v2y, v2z, p->kz1, p->kz2) - p->okz;
  rs_pf ax = (rs_packet_axis(v0x, v0y, v0z, p->kx1, p->kx2) - p->okx) - p->sx * az;
  rs_pf ay = (rs_packet_axis(v0x, v0y, v0z, p->ky1, p->ky2) - p->oky) - p->sy * az;
  rs_pf bx = (rs_packet_axis(v1x, v1y, v1z, p->kx1, p->kx2) - p->okx) - p->sx * bz;
  rs_pf by = (rs_packet_axis(v1x, v1y, v1z, p->ky1, p->ky2) - p->oky) - p->sy * bz;
  rs_pf cx = (rs_packet_axis(v2x, v2y, v2z, p->kx1, p->kx2) - p->okx) - p->sx * cz;
  rs_pf cy = (rs_packet_axis(v2x, v2y, v2z, p->ky1, p->ky2) - p->oky) - p->sy * cz;
  rs_pf u = cx * by - cy * bx;
  rs_pf v = ax * cy - ay * cx;
  rs_pf w = bx * ay - by * ax;
  const rs_pf zero = rsp_splat(0.0f), one = rsp_splat(1.0f);
#if RS_HAS_FP64
  {
    /* An edge function that rounded to 0: recompute that lane's three in double (exact). */
    const int zeros = lanes & rsp_bits((u == zero) | (v == zero) | (w == zero));
    if (zeros) {
      float fax[RS_PACKET_W], fay[RS_PACKET_W], fbx[RS_PACKET_W], fby[RS_PACKET_W], fcx[RS_PACKET_W], fcy[RS_PACKET_W];
      float fu[RS_PACKET_W], fv[RS_PACKET_W], fw[RS_PACKET_W];
      rsp_store(ax, fax), rsp_store(ay, fay), rsp_store(bx, fbx), rsp_store(by, fby), rsp_store(cx, fcx), rsp_store(cy, fcy);
      rsp_store(u, fu), rsp_store(v, fv), rsp_store(w, fw);
      for (int i = 0; i < RS_PACKET_W; ++i) {
        if (!((zeros >> i) & 1)) continue;
        fu[i] = (float)((double)fcx[i] * (double)fby[i] - (double)fcy[i] * (double)fbx[i]);
        fv[i] = (float)((double)fax[i] * (double)fcy[i] - (double)fay[i] * (double)fcx[i]);
        fw[i] = (float)((double)fbx[i] * (double)fay[i] - (double)fby[i] * (double)fax[i]);
      }
      u = rsp_load(fu), v = rsp_load(fv), w = rsp_load(fw);
    }
  }
#endif
  const int mixed = rsp_bits((u < zero) | (v < zero) | (w < zero)) & rsp_bits((u > zero) | (v > zero) | (w > zero));
  const rs_pf det = u + v + w;
  int bits = lanes & rsp_bits(det != zero) & ~mixed;
  if (!bits) return 0;
  const rs_pf safe_det = rsp_select(det, one, det == zero);
  const rs_pf azt = p->sz * az, bzt = p->sz * bz, czt = p->sz * cz;
  rs_pf t = (u * azt + v * bzt + w * czt) / safe_det;
  bits &= rsp_bits((t > p->tmin) & (t < tmax));
  if (!bits) return 0;
  {
    const rs_pf max_xt = rsp_max(rsp_max(rsp_abs(ax), rsp_abs(bx)), rsp_abs(cx));
    const rs_pf max_yt = rsp_max(rsp_max(rsp_abs(ay), rsp_abs(by)), rsp_abs(cy));
    const rs_pf max_zt = rsp_max(rsp_max(rsp_abs(azt), rsp_abs(bzt)), rsp_abs(czt));
    const rs_pf max_e = rsp_max(rsp_max(rsp_abs(u), rsp_abs(v)), rsp_abs(w));
    const int beyond = rsp_bits(t > rsp_robust_t_bound(max_xt, max_yt, max_zt, max_e, rsp_abs(safe_det)));
#if RS_HAS_FP64
    /* Lanes whose t lies within its error bound of the origin are decided again in double, lane by
     * lane, with the lane's own prepared ray (rs_robust_t_in_double, as the single-ray tests). */
    const int uncertain = bits & ~beyond;
    if (uncertain) {
      float ft[RS_PACKET_W], ftmax[RS_PACKET_W];
      rsp_store(t, ft);
      rsp_store(tmax, ftmax);
      for (int i = 0; i < RS_PACKET_W; ++i) {
        if (!((uncertain >> i) & 1)) continue;
        const RsRobustRay rr = rs_prepare_robust_ray(rays[i]);
        if (!rs_robust_t_in_double(&rr, rays[i].d, v0x, v0y, v0z, v1x, v1y, v1z, v2x, v2y, v2z, ftmax[i], &ft[i]))
          bits &= ~(1 << i);
      }
      t = rsp_load(ft);
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

/* Each lane in `lanes` walks the subtree at `ref` alone, from its closest hit so far (the hybrid
 * classes' switch to single rays). Returns the lanes that found their any hit. */
RS_INLINE int rs_packet_lanes_alone(RS_GLOBAL const RsWideNode* nodes, RS_GLOBAL const RsTriPacket* packets,
                                    const RsRay* lane_rays, int lanes, rs_u32 ref, int robust, int any_hit, int count_steps,
                                    rs_pf* hit_t, rs_pi* hit_tri, rs_pf* hit_u, rs_pf* hit_v, rs_pi* steps) {
  float ft[RS_PACKET_W], fu[RS_PACKET_W], fv[RS_PACKET_W];
  int tri[RS_PACKET_W], nsteps[RS_PACKET_W];
  rsp_store(*hit_t, ft), rsp_store(*hit_u, fu), rsp_store(*hit_v, fv);
  rsp_storei(*hit_tri, tri), rsp_storei(*steps, nsteps);
  int found = 0;
  for (int rest = lanes; rest; rest &= rest - 1) {
    const int i = rs_lowest_bit(rest);
    RsHit h;
    h.t = ft[i], h.tri = (rs_u32)tri[i], h.u = fu[i], h.v = fv[i];
    rs_u32 walked = 0;
    h = rs_traverse_wide_subtree(nodes, packets, lane_rays[i], robust, any_hit, ref, h, count_steps ? &walked : 0, 0, 0, 0);
    if (any_hit && h.tri != RS_NO_HIT) found |= 1 << i;
    ft[i] = h.t, tri[i] = (int)h.tri, fu[i] = h.u, fv[i] = h.v;
    nsteps[i] += (int)walked;
  }
  *hit_t = rsp_load(ft), *hit_u = rsp_load(fu), *hit_v = rsp_load(fv);
  *hit_tri = rsp_loadi(tri), *steps = rsp_loadi(nsteps);
  return found;
}

/* Traces rays[order[first + i]], i < RS_PACKET_W (and first + i < count), as one packet into
 * hits[first + i]: closest hit (any_hit = 0) or any hit, fast (robust = 0) or robust; single_at > 0:
 * the hybrid (above). visits, when not null, receives per ray the steps (wide nodes and leaves) at
 * which its lane was active, its lone walks included. */
RS_INLINE void rs_traverse_packet(RS_GLOBAL const RsWideNode* nodes, RS_GLOBAL const RsTriPacket* packets,
                                  RS_GLOBAL const RsRay* rays, RS_GLOBAL const rs_u32* order, rs_u32 first, rs_u32 count,
                                  int robust, int any_hit, int single_at, RS_GLOBAL RsHit* hits,
                                  RS_GLOBAL rs_u32* visits) {
  RsRay lane_rays[RS_PACKET_W];
  RsRayPacket p;
  rs_pf hit_t;
  int live = rs_packet_load(rays, order, first, count, robust, lane_rays, &p, &hit_t);
  rs_pi hit_tri = rsp_splati((int)RS_NO_HIT);
  rs_pf hit_u = rsp_splat(0.0f), hit_v = rsp_splat(0.0f);
  rs_pi steps = rsp_splati(0);
  int finished = 0; /* any hit: lanes that found theirs */
  rs_u32 stack[RS_WIDE_STACK_SIZE];
  int stack_lanes[RS_WIDE_STACK_SIZE];
  rs_pf stack_t[RS_WIDE_STACK_SIZE];
  int sp = 0;
  rs_u32 ref = 0; /* the root is always an inner node */
  int lanes = live;
  while (lanes) {
    const int alone = single_at > 0 && rs_popcount(lanes) <= single_at;
    if (visits && !alone) steps = steps - rsp_mask(lanes);
#ifdef RS_PACKET_STEP_HOOK
    /* A host-only study's count of the packet's own steps (tools/packet_study.cpp); never in a kernel. */
    if (!alone) RS_PACKET_STEP_HOOK(lanes, ref);
#endif
    if (alone) {
      /* Too few lanes share this subtree for vector steps to pay: each walks it alone. */
      finished |= rs_packet_lanes_alone(nodes, packets, lane_rays, lanes, ref, robust, any_hit, visits != 0, &hit_t,
                                        &hit_tri, &hit_u, &hit_v, &steps);
    } else if (!(ref & RS_WIDE_LEAF)) {
      RS_GLOBAL const RsWideNode* n = &nodes[ref];
      RS_GLOBAL const float* b = (RS_GLOBAL const float*)n; /* lo_x hi_x lo_y hi_y lo_z hi_z, four each */
      RS_GLOBAL const rs_i32* valid = (RS_GLOBAL const rs_i32*)&n->valid;
      rs_pf tnear[4];
      int hit_lanes[4];
      int entered = 0;
      for (int c = 0; c < 4; ++c) {
        hit_lanes[c] = 0;
        tnear[c] = p.tmin;
        if (!valid[c]) continue;
        const rs_pi m = robust ? rs_packet_box_robust(&p, b[c], b[4 + c], b[8 + c], b[12 + c], b[16 + c], b[20 + c], hit_t, &tnear[c])
                               : rs_packet_box(&p, b[c], b[4 + c], b[8 + c], b[12 + c], b[16 + c], b[20 + c], hit_t, &tnear[c]);
        hit_lanes[c] = lanes & rsp_bits(m);
        if (hit_lanes[c]) entered |= 1 << c;
      }
      if (entered) {
        /* The children in visiting order: by the first active lane's entry distance (children it
         * does not enter after the others), ties by slot; any hit keeps slot order. */
        int slot[4];
        float key[4];
        int k = 0;
        const int lead = rs_lowest_bit(lanes);
        for (int c = 0; c < 4; ++c) {
          if (!((entered >> c) & 1)) continue;
          float d = 3.4028235e38f;
          if (!any_hit && ((hit_lanes[c] >> lead) & 1)) d = rsp_lane(tnear[c], lead);
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
          stack_lanes[sp] = hit_lanes[slot[j]];
          stack_t[sp] = tnear[slot[j]];
          ++sp;
        }
        ref = n->child[slot[0]];
        lanes = hit_lanes[slot[0]];
        continue;
      }
    } else {
      const rs_u32 first_packet = RS_WIDE_LEAF_FIRST(ref), end = RS_WIDE_LEAF_END(ref);
      for (rs_u32 pi = first_packet; pi < end && lanes; ++pi) {
        RS_GLOBAL const RsTriPacket* tp = &packets[pi];
        RS_GLOBAL const float* v0x = (RS_GLOBAL const float*)&tp->v0x; /* v0x v0y v0z v1x ... v2z, four each */
        RS_GLOBAL const rs_i32* tri_valid = (RS_GLOBAL const rs_i32*)&tp->valid;
        RS_GLOBAL const rs_i32* nondegenerate = (RS_GLOBAL const rs_i32*)&tp->nondegenerate;
        for (int j = 0; j < 4 && lanes; ++j) {
          if (!tri_valid[j] || (robust && !nondegenerate[j])) continue;
          rs_pf t, u, v;
          const int found =
              robust ? rs_packet_triangle_robust(&p, lane_rays, lanes, v0x[j], v0x[4 + j], v0x[8 + j], v0x[12 + j],
                                                 v0x[16 + j], v0x[20 + j], v0x[24 + j], v0x[28 + j], v0x[32 + j], hit_t,
                                                 &t, &u, &v)
                     : rs_packet_triangle(&p, lanes, v0x[j], v0x[4 + j], v0x[8 + j], v0x[12 + j], v0x[16 + j],
                                          v0x[20 + j], v0x[24 + j], v0x[28 + j], v0x[32 + j], hit_t, &t, &u, &v);
          if (!found) continue;
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
