// The region-cut family: hcc-region (see region_cut_family.h).
#include "encode/region_cut_family.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>

#include "bvh/cut.h"
#include "encode/cut_tables.h"
#include "trace/tracer.h"
#include "util/error.h"

namespace raysort {

namespace {

// The axis along which a k-d cell is split: its longest (ties: the lower axis).
rs_u32 longest_axis(const Aabb& cell) {
  rs_u32 axis = 0;
  for (rs_u32 a = 1; a < 3; ++a)
    if (cell.max[a] - cell.min[a] > cell.max[axis] - cell.min[axis]) axis = a;
  return axis;
}

// The two children of a k-d cell at a split: below `at` on its axis, and from `at` on.
std::pair<Aabb, Aabb> split_cell(const Aabb& cell, RsRegionSplit s) {
  Aabb low = cell, high = cell;
  low.max[s.axis] = s.at;
  high.min[s.axis] = s.at;
  return {low, high};
}

// Walks a split tree of r levels (rs_region_of's heap order) from `root`: split(cell, split k)
// gives the two children's cells, and leaf(region, cell) sees each of the 2^r leaves.
template <class Cell, class Split, class Leaf>
void walk_split_tree(const std::vector<RsRegionSplit>& splits, unsigned r, const Cell& root, Split split, Leaf leaf) {
  auto walk = [&](auto&& self, std::size_t k, const Cell& cell, unsigned level) -> void {
    if (level == r) return leaf(k + 1 - (std::size_t{1} << r), cell);
    const auto [first, second] = split(cell, splits.at(k));
    self(self, 2 * k + 1, first, level + 1);
    self(self, 2 * k + 2, second, level + 1);
  };
  walk(walk, 0, root, 0);
}

// region_cells' input check: 2^r − 1 splits, each finite and on the x, y or z axis.
void check_region_splits(const std::vector<RsRegionSplit>& splits, unsigned r) {
  const std::size_t needed = (std::size_t{1} << r) - 1;
  if (splits.size() < needed)
    throw Error("hcc-region: " + std::to_string(splits.size()) + " region splits for " + std::to_string(r) +
                " region bits, which need " + std::to_string(needed));
  for (std::size_t k = 0; k < needed; ++k)
    if (splits[k].axis > 2 || !std::isfinite(splits[k].at))
      throw Error("hcc-region: region split " + std::to_string(k) + " (axis " + std::to_string(splits[k].axis) +
                  " at " + std::to_string(splits[k].at) + ") is not a finite split on the x, y or z axis");
}

// hcc-region's inputs: the statistics it learned, and its regions per key length.
struct RegionState : EncoderState {
  RegionStatistics stats;
  std::map<unsigned, RegionInputs> by_bits;
};

class RegionCutFamily final : public EncoderFamily {
 public:
  std::string key_bits_problem(Encoder, unsigned bits, const EncoderParams& params) const override {
    if (params.region_bits > kMaxRegionBits)
      return "hcc-region takes 0 to " + std::to_string(kMaxRegionBits) + " region bits (--region-bits), not " +
             std::to_string(params.region_bits);
    if (params.region_bits >= bits)
      return "hcc-region with " + std::to_string(params.region_bits) + " region bits needs keys of more than " +
             std::to_string(params.region_bits) + " bits, not " + std::to_string(bits);
    return "";
  }

  HostKey host_key(Encoder, unsigned bits, const EncodeScene& scene) const override {
    const RegionInputs& g = region_inputs(scene, bits);
    return [&g, bits](const RsRay& ray) {
      return rs_key_from_code(
          rs_region_cut_code(ray, g.cells.data(), g.region_bits, g.groups.data(), g.counts.data(), g.row_size), bits);
    };
  }

  std::vector<KernelArg> upload(Encoder, unsigned bits, const EncodeScene& scene, DeviceUploads& up) const override {
    const RegionInputs& g = region_inputs(scene, bits);
    const cl::Buffer cuts = up.buffer("region cut boxes", g.groups), sizes = up.buffer("region cut sizes", g.counts);
    return {up.buffer("region cells", g.cells), g.region_bits, cuts, sizes, g.row_size};
  }

  LearnsFrom learns_from(Encoder) const override { return LearnsFrom::PreviousFrame; }
  std::shared_ptr<const LearnedInput> study(Encoder, const EncodeScene& scene, const RayBatch& before) const override {
    auto learned = std::make_shared<LearnedRegions>();
    learned->stats = region_statistics(scene.bvh(), scene.box(), before.rays, before.any_hit(), scene.params().region_bits);
    return learned;
  }
  void use(Encoder, const LearnedInput* learned, EncodeScene& scene) const override {
    set_region_statistics(scene, learned ? dynamic_cast<const LearnedRegions&>(*learned).stats : RegionStatistics{});
  }
};

}  // namespace

const EncoderFamily& encoder_family_region_cut() {
  static const RegionCutFamily family;
  return family;
}

std::vector<RsRegionSplit> median_region_splits(const Aabb& box, const std::vector<RsRay>& rays, unsigned r) {
  std::vector<RsRegionSplit> splits((std::size_t{1} << r) - 1);
  std::vector<std::array<float, 3>> origins;
  origins.reserve(rays.size());
  for (const RsRay& ray : rays) origins.push_back({ray.o[0], ray.o[1], ray.o[2]});
  // Split k of a cell holding origins [begin, end); its children are 2k + 1 and 2k + 2.
  auto split = [&](auto&& self, std::size_t k, Aabb cell, std::size_t begin, std::size_t end, unsigned level) -> void {
    if (level == r) return;
    const rs_u32 axis = longest_axis(cell);
    float at = 0.5f * (cell.min[axis] + cell.max[axis]);
    if (end > begin) {
      const auto mid = origins.begin() + static_cast<std::ptrdiff_t>(begin + (end - begin) / 2);
      std::nth_element(origins.begin() + static_cast<std::ptrdiff_t>(begin), mid,
                       origins.begin() + static_cast<std::ptrdiff_t>(end),
                       [axis](const auto& p, const auto& q) { return p[axis] < q[axis]; });
      at = std::clamp((*mid)[axis], cell.min[axis], cell.max[axis]);
    }
    splits[k] = RsRegionSplit{at, axis};
    // The children's origins as rs_region_of sends them (ties to the second child).
    const auto second = std::partition(origins.begin() + static_cast<std::ptrdiff_t>(begin),
                                       origins.begin() + static_cast<std::ptrdiff_t>(end),
                                       [&](const auto& p) { return !(p[axis] >= at); });
    const auto middle = static_cast<std::size_t>(second - origins.begin());
    const auto [low, high] = split_cell(cell, splits[k]);
    self(self, 2 * k + 1, low, begin, middle, level + 1);
    self(self, 2 * k + 2, high, middle, end, level + 1);
  };
  split(split, 0, box, 0, origins.size(), 0);
  return splits;
}

std::vector<Aabb> region_boxes(const Aabb& box, const std::vector<RsRegionSplit>& splits, unsigned r) {
  std::vector<Aabb> cells(std::size_t{1} << r);
  walk_split_tree(splits, r, box, split_cell, [&](std::size_t region, const Aabb& cell) { cells[region] = cell; });
  return cells;
}

std::vector<RsRegionCells> region_cells(const std::vector<RsRegionSplit>& splits, unsigned r) {
  check_region_splits(splits, r);
  const float none = std::numeric_limits<float>::infinity();
  std::vector<RsRegionCells> groups(rs_region_cell_groups(r));
  for (RsRegionCells& g : groups)
    for (int j = 0; j < 16; ++j) {  // a lane past the last region: lo = +∞, hi = −∞, which no coordinate is in
      for (rs_f16* lo : {&g.lo_x, &g.lo_y, &g.lo_z}) lo->s[j] = none;
      for (rs_f16* hi : {&g.hi_x, &g.hi_y, &g.hi_z}) hi->s[j] = -none;
    }
  // A cell's bounds (lo, hi) as rs_region_of's walk narrows them: the first child keeps o[axis] < at
  // (hi = min), the second o[axis] ≥ at (lo = max).
  using Bounds = std::pair<std::array<float, 3>, std::array<float, 3>>;
  auto narrow = [](const Bounds& cell, RsRegionSplit s) {
    Bounds below = cell, above = cell;
    below.second[s.axis] = std::min(cell.second[s.axis], s.at);
    above.first[s.axis] = std::max(cell.first[s.axis], s.at);
    return std::pair{below, above};
  };
  walk_split_tree(splits, r, Bounds{{-none, -none, -none}, {none, none, none}}, narrow,
                  [&](std::size_t region, const Bounds& cell) {
                    auto [lo, hi] = cell;
                    // No upper bound: NaN, which no coordinate is ≥ (cl/keys_cut.h, RsRegionCells).
                    for (float& h : hi) h = h == none ? std::numeric_limits<float>::quiet_NaN() : h;
                    RsRegionCells& g = groups[region / 16];
                    const std::size_t j = region % 16;
                    g.lo_x.s[j] = lo[0], g.hi_x.s[j] = hi[0];
                    g.lo_y.s[j] = lo[1], g.hi_y.s[j] = hi[1];
                    g.lo_z.s[j] = lo[2], g.hi_z.s[j] = hi[2];
                  });
  return groups;
}

void set_region_statistics(EncodeScene& scene, RegionStatistics stats) {
  const std::size_t regions = std::size_t{1} << scene.params().region_bits;
  if (!stats.empty() && (stats.splits.size() != regions - 1 || stats.visits.size() != regions))
    throw Error("region statistics for " + std::to_string(stats.visits.size()) + " regions, hcc-region has " +
                std::to_string(regions) + " (" + std::to_string(scene.params().region_bits) + " region bits)");
  if (!stats.empty()) check_region_splits(stats.splits, scene.params().region_bits);
  for (const auto& region : stats.visits)
    for (const auto& [node, count] : region)
      if (node >= scene.bvh().nodes.size())
        throw Error("region statistics name node " + std::to_string(node) + ", the BVH has " +
                    std::to_string(scene.bvh().nodes.size()));
  scene.renew_state<RegionState>(Encoder::HCC_REGION).stats = std::move(stats);
}

const RegionInputs& region_inputs(const EncodeScene& scene, unsigned bits) {
  RegionState& state = scene.state<RegionState>(Encoder::HCC_REGION);
  return cached_inputs(state.by_bits, bits, [&] {
    check_key_bits(Encoder::HCC_REGION, bits, scene.params());
    const unsigned r = scene.params().region_bits, size = bits - r;
    const Bvh& bvh = scene.bvh();
    RegionInputs g;
    g.region_bits = r;
    g.row_size = size;
    const bool measured = !state.stats.empty();
    g.splits = measured ? state.stats.splits : median_region_splits(scene.box(), {}, r);
    g.cells = region_cells(g.splits, r);
    g.boxes = region_boxes(scene.box(), g.splits, r);
    for (std::size_t region = 0; region < g.boxes.size(); ++region) {
      if (!measured) {
        g.cuts.push_back(region_cut(bvh, scene.had(), size, g.boxes[region]));
        continue;
      }
      // Where this region's rays went: HAD blended with their traffic (a region no ray started in
      // has none, and gets HCC's cut).
      std::vector<std::uint64_t> traffic;
      if (!state.stats.visits[region].empty()) {
        traffic.assign(bvh.nodes.size(), 0);
        for (const auto& [node, count] : state.stats.visits[region]) traffic[node] = count;
      }
      const std::vector<double> priority = traffic_priority(scene.had(), traffic, scene.params().traffic_blend);
      g.cuts.push_back(priority_cut(bvh, priority, size, 0, &scene.had()));
    }
    CutRows rows = cut_rows(bvh, g.cuts, size);
    g.groups = std::move(rows.groups);
    g.counts = std::move(rows.counts);
    return g;
  });
}

RegionStatistics region_statistics(const Bvh& bvh, const Aabb& box, const std::vector<RsRay>& rays, bool any_hit,
                                   unsigned r) {
  return region_statistics(bvh, median_region_splits(box, rays, r), r, rays, any_hit);
}

RegionStatistics region_statistics(const Bvh& bvh, std::vector<RsRegionSplit> splits, unsigned r,
                                   const std::vector<RsRay>& rays, bool any_hit) {
  RegionStatistics stats;
  stats.splits = std::move(splits);
  std::vector<std::vector<RsRay>> starting_in(std::size_t{1} << r);
  for (const RsRay& ray : rays) starting_in[rs_region_of(stats.splits.data(), r, ray)].push_back(ray);
  for (const std::vector<RsRay>& group : starting_in) {
    std::vector<std::pair<std::uint32_t, std::uint64_t>> visited;
    const std::vector<std::uint64_t> visits = group.empty() ? std::vector<std::uint64_t>{} : node_traffic(bvh, group, any_hit);
    for (std::size_t n = 0; n < visits.size(); ++n)
      if (visits[n] > 0) visited.emplace_back(static_cast<std::uint32_t>(n), visits[n]);
    stats.visits.push_back(std::move(visited));
  }
  return stats;
}

}  // namespace raysort
