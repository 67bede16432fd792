/* raysort — the cut keys (Xiang et al. Alg. 1, sections 4.2–4.3 and 5): one bit per box the ray
 * segment overlaps, for HCC (cut nodes by descending HAD), RegularGrid (grid cells) and HCC_DIR
 * (cut bits, then direction bits from keys_spatial.h), and MLHCC's two-level cut. Boxes come in
 * sixteen-lane groups (RsCutGroup) tested with lanes.h's sixteen-lane operations.
 */
#ifndef RAYSORT_KEYS_CUT_H
#define RAYSORT_KEYS_CUT_H

#include "keys.h"
#include "keys_spatial.h"
#include "lanes.h"

/* Does the segment [tmin, tmax] of r overlap box b? The same slab arithmetic, in the same order,
 * as rs_intersect_box_unfused in intersect.h (which takes a __global node; this takes a box by value),
 * the encoders' form of the slab test: a cut-node bit is 1 when the fast traversal would enter the
 * node, up to a ray that grazes it within an ulp of a plane (the trace fuses its distances).
 * (The key kernels test sixteen boxes at once, rs_cut_mask; this one-box form is kept for
 * reference and tests.) */
RS_KEY_INLINE int rs_segment_overlaps_box(RsTraversalRay r, RsBox b) {
  float tx0 = (b.bmin[0] - r.o.x) * r.inv_d.x, tx1 = (b.bmax[0] - r.o.x) * r.inv_d.x;
  float ty0 = (b.bmin[1] - r.o.y) * r.inv_d.y, ty1 = (b.bmax[1] - r.o.y) * r.inv_d.y;
  float tz0 = (b.bmin[2] - r.o.z) * r.inv_d.z, tz1 = (b.bmax[2] - r.o.z) * r.inv_d.z;
  float tnear = rs_max(rs_max(rs_min(tx0, tx1), rs_min(ty0, ty1)), rs_max(rs_min(tz0, tz1), r.tmin));
  float tfar = rs_min(rs_min(rs_max(tx0, tx1), rs_max(ty0, ty1)), rs_min(rs_max(tz0, tz1), r.tmax));
  return tnear <= tfar;
}

/* Sixteen cut boxes, one axis bound per vector (SoA), so one pass of the slab test serves sixteen
 * boxes. Box j of a group sits in lane 15 − j, so that the group's hit mask, as bits (lane l ->
 * bit l, rs16_mask_bits), is the group's field of the code: shifted into place, lane l of group k is
 * code bit 48 + l − first_bit − 16k. An empty lane is a zero box, masked off by the box count.
 * 384 bytes. Built on the host (host/encode/encode.cpp, rs_cut_groups). The bounds must come in
 * this order: rs_cut_mask indexes them as (&lo_x)[2·axis + side]. */
#define RS_CUT_LANES 16u
typedef struct {
  rs_f16 lo_x, hi_x, lo_y, hi_y, lo_z, hi_z;
} RsCutGroup;

/* The number of groups holding n boxes. */
RS_KEY_INLINE rs_u32 rs_cut_group_count(rs_u32 n) { return (n + RS_CUT_LANES - 1u) / RS_CUT_LANES; }

/* A ray broadcast to sixteen lanes, and per axis the side of the box its slab enters first
 * (near_x = 1: the hi plane, where 1/d < 0). */
typedef struct {
  rs_f16 ox, oy, oz, ix, iy, iz, tmin, tmax;
  rs_u32 near_x, near_y, near_z;
} RsCutRay;

RS_KEY_INLINE RsCutRay rs_cut_ray(RsTraversalRay r) {
  RsCutRay c;
  c.ox = rs16_splat(r.o.x), c.oy = rs16_splat(r.o.y), c.oz = rs16_splat(r.o.z);
  c.ix = rs16_splat(r.inv_d.x), c.iy = rs16_splat(r.inv_d.y), c.iz = rs16_splat(r.inv_d.z);
  c.tmin = rs16_splat(r.tmin), c.tmax = rs16_splat(r.tmax);
  c.near_x = r.inv_d.x < 0.0f, c.near_y = r.inv_d.y < 0.0f, c.near_z = r.inv_d.z < 0.0f;
  return c;
}

/* rs_segment_overlaps_box on the sixteen boxes of g: -1 in each lane whose box the segment overlaps.
 * The same values as there, with the near and far plane of each axis picked by the sign of 1/d
 * instead of a min and a max per box (the trace kernels' rs_wide_boxes does the same): for
 * lo <= hi, (lo − o)·inv and (hi − o)·inv keep their order after rounding, so the min is the near
 * plane's t. inv is never 0 or NaN (rs_safe_rcp) and rays are finite; a box must have lo <= hi
 * (rs_cut_groups checks). min/max are selects, see rs16_min. */
#define RS_DEFINE_CUT_MASK(NAME, SPACE, MASK_T, VEC_T, BOX, RAY, MIN, MAX)                                 \
  RS_KEY_INLINE MASK_T NAME(const RsCutRay* r, SPACE const RsCutGroup* g) {                                   \
    SPACE const rs_f16* b = &g->lo_x;                                                                         \
    const VEC_T tnx = (BOX(SPACE, b + r->near_x) - RAY(r->ox)) * RAY(r->ix);                                  \
    const VEC_T tfx = (BOX(SPACE, b + 1u - r->near_x) - RAY(r->ox)) * RAY(r->ix);                             \
    const VEC_T tny = (BOX(SPACE, b + 2u + r->near_y) - RAY(r->oy)) * RAY(r->iy);                             \
    const VEC_T tfy = (BOX(SPACE, b + 3u - r->near_y) - RAY(r->oy)) * RAY(r->iy);                             \
    const VEC_T tnz = (BOX(SPACE, b + 4u + r->near_z) - RAY(r->oz)) * RAY(r->iz);                             \
    const VEC_T tfz = (BOX(SPACE, b + 5u - r->near_z) - RAY(r->oz)) * RAY(r->iz);                             \
    const VEC_T tnear = MAX(MAX(tnx, tny), MAX(tnz, RAY(r->tmin)));                                           \
    const VEC_T tfar = MIN(MIN(tfx, tfy), MIN(tfz, RAY(r->tmax)));                                            \
    return tnear <= tfar;                                                                                     \
  }

/* The code bits of the n boxes of g that the segment overlaps (n <= 64; box i in group i / 16,
 * code bit 63 − first_bit − i): each group's hit mask as bits (rs16_mask_bits: one kmovd on
 * AVX-512 devices, lanes.h), restricted to its boxes' lanes and shifted into place.
 * On the device, a last group with at most eight boxes (in lanes 8..15) is tested on its upper
 * eight lanes only (rs_cut_mask_half_*): with AVX-512, PoCL runs a sixteen-lane operation as one
 * zmm instruction, which Zen 4 executes in two halves, so a half-empty group would cost a full one
 * (MLHCC at 16 bits has two such groups per key). The host tests every group whole; the code is
 * the same.
 * One definition per address space (OpenCL C 1.2 has no generic pointers): _p private/host,
 * _c constant, _g global. */
#ifdef __OPENCL_VERSION__
#define RS_CUT_WHOLE_ABOVE (RS_CUT_LANES / 2u) /* a last group with more boxes is tested whole */
/* The upper eight lanes: box bounds loaded as such (vload8 of floats 8..15), the ray's from its low
 * half, which holds the same values (every RsCutRay vector is one value in all lanes). Taking
 * .hi of the sixteen-lane vectors gives the same bits, but Oclgrind's uninitialised-value check
 * then reports every half-group key as uninitialised (a false positive), hiding real findings. */
#define RS_CUT_BOX_HI8(SPACE, p) vload8(1, (SPACE const float*)(p))
#define RS_CUT_RAY_HI8(x) ((x).lo)
#define RS_DEFINE_CUT_MASK_HALF(SUFFIX, SPACE)                                                       \
  RS_DEFINE_CUT_MASK(rs_cut_mask_half_##SUFFIX, SPACE, int8, float8, RS_CUT_BOX_HI8, RS_CUT_RAY_HI8, rs8_min, rs8_max)
#define RS_CUT_BITS_HALF(SUFFIX)                                                                     \
  if (rest > 0u && rest <= RS_CUT_WHOLE_ABOVE) {                                                     \
    const rs_u32 m = rs8_mask_bits(rs_cut_mask_half_##SUFFIX(r, &g[full])) & (0xFF00u >> rest);      \
    code |= (RS_U64(m) << 56) >> (first_bit + RS_CUT_LANES * full);                                  \
  }
#else
#define RS_CUT_WHOLE_ABOVE 0u
#define RS_DEFINE_CUT_MASK_HALF(SUFFIX, SPACE)
#define RS_CUT_BITS_HALF(SUFFIX)
#endif
#define RS_CUT_BOX16(SPACE, p) (*(p))
#define RS_CUT_RAY16(x) (x)
#define RS_DEFINE_CUT_BITS(SUFFIX, SPACE)                                                            \
  RS_DEFINE_CUT_MASK(rs_cut_mask_##SUFFIX, SPACE, rs_i16, rs_f16, RS_CUT_BOX16, RS_CUT_RAY16, rs16_min, rs16_max) \
  RS_DEFINE_CUT_MASK_HALF(SUFFIX, SPACE)                                                             \
  RS_KEY_INLINE rs_u64 rs_cut_bits_##SUFFIX(const RsCutRay* r, SPACE const RsCutGroup* g, rs_u32 n,  \
                                            rs_u32 first_bit) {                                      \
    rs_u64 code = 0;                                                                                 \
    const rs_u32 full = n / RS_CUT_LANES, rest = n % RS_CUT_LANES;                                   \
    for (rs_u32 k = 0; k < full + (rest > RS_CUT_WHOLE_ABOVE); ++k) {                                \
      const rs_u32 left = n - RS_CUT_LANES * k; /* boxes from this group on, in lanes 15, 14, ... */   \
      const rs_u32 boxes = left < RS_CUT_LANES ? left : RS_CUT_LANES;                                \
      const rs_u32 m = rs16_mask_bits(rs_cut_mask_##SUFFIX(r, &g[k])) & (0xFFFF0000u >> boxes);      \
      code |= (RS_U64(m) << 48) >> (first_bit + RS_CUT_LANES * k);                                   \
    }                                                                                                \
    RS_CUT_BITS_HALF(SUFFIX)                                                                         \
    return code;                                                                                     \
  }
#ifdef __OPENCL_VERSION__
RS_DEFINE_CUT_BITS(c, __constant)
RS_DEFINE_CUT_BITS(g, __global)
#define RS_CUT_BITS_TOP rs_cut_bits_c
#else
RS_DEFINE_CUT_BITS(p, )
#define RS_CUT_BITS_TOP rs_cut_bits_p
#define rs_cut_bits_g rs_cut_bits_p
#endif

/* The space the box-set kernels read the cut groups from (HCC, grid, HCC_DIR, MLHCC top level). */
#define RS_CUT_SPACE RS_CONSTANT

/* HCC / RegularGrid / HCC_DIR: bit 63 − i = overlap with box i of the set (n boxes in
 * ceil(n / 16) groups, built on the host by rs_cut_groups; n ≤ 64 − dir_bits); then dir_bits
 * direction bits right below the box field of `field` bits (HCC_DIR). Every group is tested:
 * testing a group's union box first and skipping the groups it misses (a summary group, tried with
 * eight-box groups, in bit order and in Morton order) gave the same bits but was 1.2–1.9x slower
 * on PoCL for HCC and no faster for grid cells: sibenik's shadow rays are long and meet most of the
 * union boxes, and the data-dependent loop costs more than the groups it skips. */
RS_KEY_INLINE rs_u64 rs_box_set_code(RsRay ray, RS_CUT_SPACE const RsCutGroup* set, rs_u32 n, rs_u32 field,
                                     rs_u32 dir_bits) {
  RsTraversalRay r = rs_prepare_ray(ray);
  RsCutRay c = rs_cut_ray(r);
  rs_u64 code = RS_CUT_BITS_TOP(&c, set, n, 0u);
  if (dir_bits > 0u) code |= rs_direction_field(ray, dir_bits) << (64u - field - dir_bits);
  return code;
}

/* The code bits of the first n boxes of a row whose box 0 is at code bit 63 − first_bit. A row is
 * tested as if full (rs_cut_bits over its whole width, the same loop for every ray) and this drops
 * the bits past its n boxes: on PoCL a trip count that differed per ray, the row's own count, cost
 * about a tenth of hcc-region's key (docs/encoders.md, "The third kernel"). */
RS_KEY_INLINE rs_u64 rs_row_kept(rs_u32 n, rs_u32 first_bit) {
  return n == 0u ? RS_U64(0) : (~RS_U64(0) << (64u - n)) >> first_bit;
}

/* The two-level code with `top_bits` bits for the top level and rows of `low_bits` boxes (row rep
 * of `low`, ceil(low_bits / 16) groups, box j at code bit 63 − top_bits − j): MLHCC below with
 * both half the key, mlhcc-cost's cut with a shorter low level. */
RS_KEY_INLINE rs_u64 rs_two_level_split_code(RsRay ray, RS_CUT_SPACE const RsCutGroup* top, rs_u32 n_top,
                                             RS_GLOBAL const RsCutGroup* low, RS_GLOBAL const rs_u32* low_count,
                                             rs_u32 top_bits, rs_u32 low_bits) {
  RsTraversalRay r = rs_prepare_ray(ray);
  RsCutRay c = rs_cut_ray(r);
  const rs_u64 code = RS_CUT_BITS_TOP(&c, top, n_top, 0u);
  const rs_u32 rep = code != 0u ? rs_clz64(code) : 0u;
  return code | (rs_cut_bits_g(&c, low + rep * rs_cut_group_count(low_bits), low_bits, top_bits) &
                 rs_row_kept(code != 0u ? low_count[rep] : 0u, top_bits));
}

/* MLHCC (Xiang et al. section 4.3): the top `half_bits` bits are the HCC of the top-level cut; the
 * representative top node is the first one hit (top nodes are in descending HAD order); the next
 * `half_bits` bits are the HCC of its low-level cut: row rep of `low` (ceil(half_bits / 16)
 * groups, box j in group j / 16, j < low_count[rep], its code bit already 63 − half_bits − j). No
 * top node hit: the low bits are 0. */
RS_KEY_INLINE rs_u64 rs_two_level_cut_code(RsRay ray, RS_CUT_SPACE const RsCutGroup* top, rs_u32 n_top,
                                           RS_GLOBAL const RsCutGroup* low, RS_GLOBAL const rs_u32* low_count,
                                           rs_u32 half_bits) {
  return rs_two_level_split_code(ray, top, n_top, low, low_count, half_bits, half_bits);
}

/* HCC_REGION (issue 21; the paper's §6 suggestion for open scenes, "dividing the scene into
 * different regions ... and encoding rays in different regions separately"): the scene is split
 * into 2^r regions by a k-d tree of r levels, a ray's region is the cell its origin falls in, and
 * each region has its own cut of b − r nodes. Code: | region (r bits) | overlap bits of the
 * region's cut nodes | 0 … |. The host (host/encode/region_cut_family.cpp, region_inputs) places the
 * splits at the median origin of a previous frame's rays, so the regions hold equal shares of the
 * rays, and picks each region's cut by the traffic of that region's rays (or, with no previous
 * frame, halves each cell and cuts by HAD among the nodes overlapping it).
 *
 * Split k of the tree (2^r − 1 of them, heap order: the children of k are 2k + 1 and 2k + 2) sends
 * a ray whose origin has o[axis] ≥ at to the second child. Only comparisons: exact on every device,
 * and an origin outside the scene box still falls in a region. The kernel tests the tree's leaves
 * as cells (RsRegionCells below) instead of walking it. */
typedef struct {
  float at;
  rs_u32 axis;
} RsRegionSplit;

/* The region of a ray, 0 … 2^region_bits − 1: the leaf of the split tree its origin reaches. This
 * walk is the definition; the key kernel finds the same leaf by testing the origin against the
 * leaves' cells (rs_region_in_cells below), and the host bins a previous frame's rays with it. */
RS_KEY_INLINE rs_u32 rs_region_of(RS_GLOBAL const RsRegionSplit* splits, rs_u32 region_bits, RsRay ray) {
  rs_u32 k = 0u;
  for (rs_u32 level = 0u; level < region_bits; ++level) {
    const RsRegionSplit s = splits[k];
    k = 2u * k + (ray.o[s.axis] >= s.at ? 2u : 1u);
  }
  return k + 1u - (1u << region_bits);
}

/* The leaves of the split tree as cells, sixteen to a group, cell j of group g (region 16g + j) in
 * lane j. Per axis, lo is the largest split value on that axis that the walk to the leaf took the
 * second child of (−∞ when none), and hi the smallest it took the first child of (NaN when none).
 * An origin is in a cell when, per axis, o' ≥ lo and not o' ≥ hi, where o' = fmax(o, −∞) (NaN read
 * as −∞; rs_region_coordinate). These are the walk's own comparisons, each split of the path once:
 * on one axis, o ≥ a1 and o ≥ a2 is o ≥ max(a1, a2), and not o ≥ b1 and not o ≥ b2 is not
 * o ≥ min(b1, b2). A NaN coordinate, which the walk never sends to a second child, is −∞, which
 * is ≥ only the missing lo. So every origin (on a split plane, outside the scene box, ±∞ or NaN) is
 * in exactly the cell of the leaf the walk reaches; the host test Encode.RegionCellsAreTheWalk checks
 * it. Built on the host (host/encode/encode.cpp, region_cells), which accepts only finite split
 * values. Lanes past the last region hold lo = +∞ and hi = −∞, which no o' is in.
 * Why cells: on PoCL the walk is r dependent loads before the region's row of cut boxes can be
 * read. It cost hcc-region about as much as HCC's whole key (docs/encoders.md, "Encode cost"); the
 * cells are one sixteen-lane test of bounds that are the same for every ray, as HCC's cut boxes
 * are, and held in __constant memory as they are. */
typedef struct {
  rs_f16 lo_x, hi_x, lo_y, hi_y, lo_z, hi_z;
} RsRegionCells;

/* A coordinate as the cells compare it: NaN as −∞ (fmax returns the other operand of a NaN). */
#ifdef __OPENCL_VERSION__
RS_KEY_INLINE float rs_region_coordinate(float o) { return fmax(o, -INFINITY); }
#else
RS_KEY_INLINE float rs_region_coordinate(float o) { return std::fmax(o, -INFINITY); }
#endif

/* The cells of group g that hold the point (x, y, z) (coordinates through rs_region_coordinate),
 * as lane bits: lane j -> bit j. */
#ifdef __OPENCL_VERSION__
RS_KEY_INLINE rs_u32 rs_region_cell_mask(RS_CONSTANT const RsRegionCells* g, float x, float y, float z) {
  const float16 vx = (float16)(x), vy = (float16)(y), vz = (float16)(z);
  return rs16_mask_bits((vx >= g->lo_x) & ~(vx >= g->hi_x) & (vy >= g->lo_y) & ~(vy >= g->hi_y) & (vz >= g->lo_z) &
                        ~(vz >= g->hi_z));
}
#else
RS_KEY_INLINE rs_u32 rs_region_cell_mask(const RsRegionCells* g, float x, float y, float z) {
  rs_u32 m = 0u;
  for (int j = 0; j < 16; ++j)
    m |= static_cast<rs_u32>(x >= g->lo_x.s[j] && !(x >= g->hi_x.s[j]) && y >= g->lo_y.s[j] &&
                             !(y >= g->hi_y.s[j]) && z >= g->lo_z.s[j] && !(z >= g->hi_z.s[j]))
         << j;
  return m;
}
#endif

/* The number of cell groups of 2^region_bits regions. */
RS_KEY_INLINE rs_u32 rs_region_cell_groups(rs_u32 region_bits) { return ((1u << region_bits) + 15u) / 16u; }

/* rs_region_of's region, found from the cells: the one cell, over all groups, that holds the origin.
 * (A branch on each group's mask measured as fast as a select on PoCL, and skips nothing at r ≤ 4.) */
RS_KEY_INLINE rs_u32 rs_region_in_cells(RS_CONSTANT const RsRegionCells* cells, rs_u32 region_bits, RsRay ray) {
  const float x = rs_region_coordinate(ray.o[0]), y = rs_region_coordinate(ray.o[1]),
              z = rs_region_coordinate(ray.o[2]);
  rs_u32 region = 0u;
  for (rs_u32 g = 0u; g < rs_region_cell_groups(region_bits); ++g) {
    const rs_u32 m = rs_region_cell_mask(&cells[g], x, y, z);
    if (m != 0u) region = 16u * g + 63u - rs_clz64(RS_U64(m & (0u - m))); /* its lowest (only) bit */
  }
  return region;
}

/* The HCC_REGION code: the region in the top region_bits bits, then the overlap bits of row
 * `region` of `cuts` (rows of row_size boxes, rs_cut_group_count(row_size) groups each; row
 * `region` holds count[region] ≤ row_size boxes, box i at code bit 63 − region_bits − i), tested
 * as if full (rs_row_kept). With region_bits = 0 there is one region. */
RS_KEY_INLINE rs_u64 rs_region_cut_code(RsRay ray, RS_CONSTANT const RsRegionCells* cells, rs_u32 region_bits,
                                        RS_GLOBAL const RsCutGroup* cuts, RS_GLOBAL const rs_u32* count,
                                        rs_u32 row_size) {
  const rs_u32 region = rs_region_in_cells(cells, region_bits, ray);
  const RsCutRay c = rs_cut_ray(rs_prepare_ray(ray));
  rs_u64 code = region_bits > 0u ? RS_U64(region) << (64u - region_bits) : RS_U64(0);
  code |= rs_cut_bits_g(&c, cuts + region * rs_cut_group_count(row_size), row_size, region_bits) &
          rs_row_kept(count[region], region_bits);
  return code;
}

/* MLHCC_COST (issue 21, beyond the paper): MLHCC's two-level cut (Alg. 3) with a shorter low
 * level: in the top `top_bits` bits (half the key) the top-level nodes overlapped, searched as
 * MLHCC's but for nodes of at least `low_bits` leaves; below them the representative's low-level
 * cut of `low_bits` nodes (box j at code bit 63 − top_bits − j); and in the key's last bits an estimate of how long the ray's traversal
 * is: the quantised mean step count, in a previous frame, of the rays that started in the same
 * origin cell and went in the same direction cell (rs_cost_bin). The cut groups rays that walk the
 * same part of the tree; within a group, the estimate puts rays of similar traversal length in the
 * same warps, so fewer lanes idle while the longest one finishes (the order study: docs/encoders.md).
 * `cost` holds, per bin, the estimate already quantised to the key's cost field on the host
 * (host/encode/encode.cpp), at code bits 64 − key_bits and up. */
#define RS_COST_CELL_LEVELS 4u    /* 16 x 16 x 16 origin cells of the scene box */
#define RS_COST_DIRECTION_LEVELS 3u /* 8 x 8 direction cells on the octahedral map */
#define RS_COST_DIRECTION_BITS (2u * RS_COST_DIRECTION_LEVELS)
#define RS_COST_BINS (1u << (3u * RS_COST_CELL_LEVELS + RS_COST_DIRECTION_BITS))

/* The direction's cell on the octahedral map (Praun and Hoppe 2003; Engelhardt and Dachsbacher
 * 2008): d / (|dx| + |dy| + |dz|) seen from above, the lower half folded out over the diagonals, in
 * 2^levels x 2^levels cells of [-1, 1]^2 (u cell in the high bits). Only + − × ÷, where Reis's (φ, θ)
 * cells need atan2 and acos, and the cells' solid angles differ far less than (φ, θ)'s near the
 * poles. A −0 component counts as +0; a zero direction is cell (2^(levels−1), 2^(levels−1)). */
RS_KEY_INLINE rs_u32 rs_octahedral_cell(RsRay ray, rs_u32 levels) {
  const float x = ray.d[0], y = ray.d[1], z = ray.d[2];
  const float s = rs_abs(x) + rs_abs(y) + rs_abs(z);
  const float inv = s > 0.0f ? 1.0f / s : 0.0f;
  float u = x * inv, v = y * inv;
  if (z < 0.0f) {
    const float fu = (1.0f - rs_abs(v)) * (u < 0.0f ? -1.0f : 1.0f);
    const float fv = (1.0f - rs_abs(u)) * (v < 0.0f ? -1.0f : 1.0f);
    u = fu;
    v = fv;
  }
  return (rs_quantize(u * 0.5f + 0.5f, levels) << levels) | rs_quantize(v * 0.5f + 0.5f, levels);
}

/* The bin of a ray: its origin's cell (x, y, z, 4 bits each) then its direction's cell. */
RS_KEY_INLINE rs_u32 rs_cost_bin(const RsEncodeFrame* f, RsRay ray) {
  rs_u32 q[3];
  rs_quantize_point(f, rs_load3(ray.o), RS_COST_CELL_LEVELS, q);
  const rs_u32 cell = (q[0] << (2u * RS_COST_CELL_LEVELS)) | (q[1] << RS_COST_CELL_LEVELS) | q[2];
  return (cell << RS_COST_DIRECTION_BITS) | rs_octahedral_cell(ray, RS_COST_DIRECTION_LEVELS);
}

RS_KEY_INLINE rs_u64 rs_cost_cut_code(RsRay ray, const RsEncodeFrame* f, RS_CUT_SPACE const RsCutGroup* top,
                                      rs_u32 n_top, RS_GLOBAL const RsCutGroup* low,
                                      RS_GLOBAL const rs_u32* low_count, rs_u32 top_bits, rs_u32 low_bits,
                                      RS_GLOBAL const rs_u32* cost, rs_u32 key_bits) {
  return rs_two_level_split_code(ray, top, n_top, low, low_count, top_bits, low_bits) |
         (RS_U64(cost[rs_cost_bin(f, ray)]) << (64u - key_bits));
}

/* Rays per work-item of the MLHCC kernel (rs_two_level_cut_code2 below; the host sizes the launch). */
#define RS_TWO_LEVEL_RAYS 2u
#ifdef __OPENCL_VERSION__
/* rs_two_level_cut_code for two rays, a and b (the device kernel's form; the host twin is the
 * one-ray function above, and the tests compare the two). A key's low-level test needs its own
 * top-level result first (which row), so one ray's work is a chain of dependent steps longer than
 * the processor can look ahead over; placed one after the other, two rays' chains overlap. The row
 * test runs with no branch on whether a top node was hit; its bits are dropped if not. (Four rays,
 * through private arrays, measured slower than one.) */
RS_KEY_INLINE void rs_two_level_cut_code2(RsRay ray_a, RsRay ray_b, RS_CUT_SPACE const RsCutGroup* top, rs_u32 n_top,
                                          RS_GLOBAL const RsCutGroup* low, RS_GLOBAL const rs_u32* low_count,
                                          rs_u32 half_bits, rs_u64* code_a, rs_u64* code_b) {
  const RsCutRay a = rs_cut_ray(rs_prepare_ray(ray_a));
  const RsCutRay b = rs_cut_ray(rs_prepare_ray(ray_b));
  const rs_u64 top_a = RS_CUT_BITS_TOP(&a, top, n_top, 0u);
  const rs_u64 top_b = RS_CUT_BITS_TOP(&b, top, n_top, 0u);
  const rs_u32 rep_a = top_a != 0u ? rs_clz64(top_a) : 0u, rep_b = top_b != 0u ? rs_clz64(top_b) : 0u;
  const rs_u32 row = rs_cut_group_count(half_bits);
  const rs_u64 low_a = rs_cut_bits_g(&a, low + rep_a * row, half_bits, half_bits);
  const rs_u64 low_b = rs_cut_bits_g(&b, low + rep_b * row, half_bits, half_bits);
  *code_a = top_a | (low_a & rs_row_kept(top_a != 0u ? low_count[rep_a] : 0u, half_bits));
  *code_b = top_b | (low_b & rs_row_kept(top_b != 0u ? low_count[rep_b] : 0u, half_bits));
}
#endif

#endif /* RAYSORT_KEYS_CUT_H */
