#pragma once
// The region-cut family, hcc-region (issue 21, after Xiang et al. §6.1 and §6.6; docs/encoders.md):
// r key bits name the region of the ray's origin (a k-d tree split at a previous frame's median
// origins), and the bits below are the HCC of that region's own cut, chosen by the traffic of the
// rays that started there (cl/keys_cut.h, rs_region_cut_code).
#include <cstdint>
#include <utility>
#include <vector>

#include "bvh/bvh.h"
#include "encode/encode_scene.h"
#include "encode/encoder_family.h"
#include "keys_cut.h"

namespace raysort {

// hcc-region's regions: a k-d tree of r levels over `box`, split k in heap order
// (cl/keys_cut.h, RsRegionSplit). median_region_splits places each split, along its cell's longest
// axis (ties: the lower axis), at the median origin of the rays in that cell (the upper median;
// rays with o[axis] ≥ at go to the second child, as rs_region_of sends them), or at the cell's
// middle when no ray is in it; with no rays every split halves its cell. Deterministic.
std::vector<RsRegionSplit> median_region_splits(const Aabb& box, const std::vector<RsRay>& rays, unsigned r);
// The 2^r cells of a split tree, in region order.
std::vector<Aabb> region_boxes(const Aabb& box, const std::vector<RsRegionSplit>& splits, unsigned r);
// The same cells unbounded by the scene box, as the key kernel tests them (cl/keys_cut.h,
// RsRegionCells: lo = −∞ and hi = NaN where the walk to a leaf passed no split on that side of an
// axis), sixteen to a group. Throws on a split that is not finite or names no axis, and on fewer
// than 2^r − 1 splits.
std::vector<RsRegionCells> region_cells(const std::vector<RsRegionSplit>& splits, unsigned r);

// hcc-region's input from a previous frame's batch: the splits at its rays' median origins, and per
// region the node traffic (trace/tracer.h, node_traffic) of the rays that start there, kept sparse:
// (node, visits) pairs of the visited nodes, by node.
struct RegionStatistics {
  std::vector<RsRegionSplit> splits;
  std::vector<std::vector<std::pair<std::uint32_t, std::uint64_t>>> visits;
  bool empty() const { return visits.empty(); }  // no statistics (visits has 2^r entries otherwise)
};
// The statistics of one batch of a previous frame: the split tree at the batch's median origins
// (median_region_splits of `box`, r levels) and, per region, the node traffic of the batch's rays
// that start in it.
RegionStatistics region_statistics(const Bvh& bvh, const Aabb& box, const std::vector<RsRay>& rays, bool any_hit,
                                   unsigned r);
// The same over given splits (tools/region_study compares them with the halving ones).
RegionStatistics region_statistics(const Bvh& bvh, std::vector<RsRegionSplit> splits, unsigned r,
                                   const std::vector<RsRay>& rays, bool any_hit);

// hcc-region's previous-frame input for the scene's region bits. Without it (the default) each
// split halves its cell and each region's cut is HAD's among the nodes overlapping it. Setting it
// drops hcc-region's cached regions; the other encoders' inputs stay.
void set_region_statistics(EncodeScene& scene, RegionStatistics stats);

// hcc-region for keys of `bits` bits: the split tree (2^r − 1 splits), its leaves as the kernel
// tests them (region_cells), each region's box (region_boxes), its cut of row_size = bits − r nodes
// and the cuts as sixteen-box groups, rs_cut_group_count(row_size) per region. With statistics a
// region's cut is priority_cut by traffic_priority(HAD, the region's traffic, β), else region_cut.
struct RegionInputs {
  rs_u32 region_bits = 0;
  rs_u32 row_size = 0;
  std::vector<RsRegionSplit> splits;
  std::vector<RsRegionCells> cells;
  std::vector<Aabb> boxes;
  std::vector<std::vector<std::uint32_t>> cuts;
  std::vector<RsCutGroup> groups;
  std::vector<rs_u32> counts;
};
const RegionInputs& region_inputs(const EncodeScene& scene, unsigned bits);

// What hcc-region learns from the same batch of a previous frame (LearnsFrom::PreviousFrame).
struct LearnedRegions : LearnedInput {
  RegionStatistics stats;
};

}  // namespace raysort
