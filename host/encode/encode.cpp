// Host side of the encoders: names, key-length rules, the per-scene inputs (frame, HAD, cuts,
// grid cells) and the host twin. The key arithmetic is cl/keys*.h, the same source the kernels run.
#include "encode/encode.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cctype>
#include <cmath>
#include <limits>
#include <thread>

#include "bvh/had.h"
#include "util/error.h"

namespace raysort {

static_assert(sizeof(RsBox) == 24 && sizeof(RsEncodeFrame) == 48 && sizeof(RsCutGroup) == 384 &&
                  sizeof(RsRegionSplit) == 8,
              "device struct layouts (cl/keys.h, cl/keys_cut.h)");

const std::vector<EncoderInfo>& encoder_table() {
  // Cost weights: encode + sort as a share of one trace, measured on PoCL in the quick preset
  // (bench/shard.h, matrix_cells).
  using F = EncoderFamily;
  static const std::vector<EncoderInfo> table = {
      {Encoder::NoSort, "nosort", {"none", "nosorting"}, F::None, "encode_nosort", 100, false},
      {Encoder::Origin, "origin", {}, F::Spatial, "encode_origin", 115, false},
      {Encoder::Reis, "reis", {}, F::Spatial, "encode_reis", 128, false},
      {Encoder::Costa, "costa", {}, F::Spatial, "encode_costa", 128, false},
      {Encoder::Aila, "aila", {"aila_compact"}, F::Spatial, "encode_aila", 125, false},
      {Encoder::TwoPoint, "twopoint", {}, F::Spatial, "encode_twopoint", 122, false},
      {Encoder::RegularGrid, "grid", {"regular-grid"}, F::BoxSet, "encode_box_set", 128, true},
      {Encoder::HCC, "hcc", {"hierarchy-cut", "hierarchy-cut-code"}, F::BoxSet, "encode_box_set", 128, true},
      {Encoder::MLHCC, "mlhcc", {}, F::TwoLevel, "encode_two_level", 142, true},
      {Encoder::PPC, "ppc", {"prefix-path", "prefix-path-code"}, F::PrefixPath, "encode_prefix_path", 165, false},
      {Encoder::HCC_DIR, "hcc-dir", {}, F::BoxSet, "encode_box_set", 150, false},
      // Beyond the paper (issue 21). Cost weights estimated from HCC's (not yet measured): the
      // region code tests its region cells, then reads its row from global memory; the cut inputs
      // of hcc-region and hcc-traffic are host traversals, outside the weight.
      {Encoder::HCC_REGION, "hcc-region", {"region"}, F::RegionCut, "encode_region_cut", 135, false},
      {Encoder::HCC_TRAFFIC, "hcc-traffic", {"traffic"}, F::BoxSet, "encode_box_set", 135, false},
      // MLHCC's tables plus an origin cell and an octahedral direction cell per ray and one table
      // read; its cost statistics are a host traversal of a previous frame's batch, outside the weight.
      {Encoder::MLHCC_COST, "mlhcc-cost", {"cost"}, F::CostCut, "encode_cost_cut", 150, false},
  };
  return table;
}

const EncoderInfo& encoder_info(Encoder e) {
  const auto& table = encoder_table();
  const auto i = static_cast<std::size_t>(e);
  if (i >= table.size() || table[i].id != e) throw Error("encoder_info: an encoder outside the table");
  return table[i];
}

std::string_view encoder_name(Encoder e) { return encoder_info(e).name; }

std::optional<Encoder> parse_encoder(std::string_view name) {
  auto folded = [](std::string_view text) {
    std::string s;
    for (char c : text)
      if (c != '-' && c != '_' && c != ' ') s += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
  };
  const std::string wanted = folded(name);
  for (const EncoderInfo& info : encoder_table()) {
    if (folded(info.name) == wanted) return info.id;
    for (std::string_view alias : info.aliases)
      if (folded(alias) == wanted) return info.id;
  }
  return std::nullopt;
}

const std::vector<Encoder>& all_encoders() {
  static const std::vector<Encoder> all = [] {
    std::vector<Encoder> ids;
    for (const EncoderInfo& info : encoder_table()) ids.push_back(info.id);
    return ids;
  }();
  return all;
}

std::vector<Encoder> parse_encoders(const std::vector<std::string>& names) {
  if (names.size() == 1 && names[0] == "all") return all_encoders();
  std::vector<Encoder> out;
  for (const auto& name : names) {
    const auto e = parse_encoder(name);
    if (!e) {
      std::string valid;
      for (const EncoderInfo& info : encoder_table()) valid += (valid.empty() ? "" : ", ") + std::string(info.name);
      throw Error("unknown encoder '" + name + "'; encoders are: " + valid);
    }
    if (std::find(out.begin(), out.end(), *e) == out.end()) out.push_back(*e);
  }
  return out;
}

unsigned max_key_bits(Encoder) { return RS_MAX_KEY_BITS; }

std::string key_bits_problem(Encoder e, unsigned bits, const EncoderParams& params) {
  const std::string name(encoder_name(e));
  if (bits < 1 || bits > max_key_bits(e))
    return name + " keys have 1 to " + std::to_string(max_key_bits(e)) + " bits, not " + std::to_string(bits);
  if (e == Encoder::MLHCC && bits % 2 != 0)
    return "mlhcc keys need an even number of bits (half top-level, half low-level cut nodes), not " +
           std::to_string(bits);
  if (e == Encoder::HCC_DIR) {
    if (params.direction_bits > 2 * RS_DIRECTION_LEVELS)
      return "hcc-dir takes at most " + std::to_string(2 * RS_DIRECTION_LEVELS) + " direction bits, not " +
             std::to_string(params.direction_bits);
    if (params.direction_bits >= bits)
      return "hcc-dir with " + std::to_string(params.direction_bits) + " direction bits needs keys of more than " +
             std::to_string(params.direction_bits) + " bits, not " + std::to_string(bits);
  }
  if (e == Encoder::HCC_REGION) {
    if (params.region_bits > kMaxRegionBits)
      return "hcc-region takes 0 to " + std::to_string(kMaxRegionBits) + " region bits (--region-bits), not " +
             std::to_string(params.region_bits);
    if (params.region_bits >= bits)
      return "hcc-region with " + std::to_string(params.region_bits) + " region bits needs keys of more than " +
             std::to_string(params.region_bits) + " bits, not " + std::to_string(bits);
  }
  if (e == Encoder::MLHCC_COST) {
    if (bits % 2 != 0 || bits < 4)
      return "mlhcc-cost keys need an even number of bits, at least 4 (half top-level cut, then low-level cut "
             "and cost estimate), not " + std::to_string(bits);
    const CostSplit split = cost_split(bits, params);
    if (split.low_bits == 0)
      return "mlhcc-cost with " + std::to_string(split.cost_bits) + " cost bits (--cost-bits) leaves no low-level "
             "cut in a " + std::to_string(bits) + "-bit key: take fewer than " + std::to_string(bits / 2);
  }
  if (e == Encoder::HCC_TRAFFIC && !(params.traffic_blend >= 0.0 && params.traffic_blend <= 1.0))
    return "hcc-traffic's traffic blend (--traffic-blend) is a number from 0 (HAD only) to 1 (traffic only), not " +
           std::to_string(params.traffic_blend);
  return "";
}

CostSplit cost_split(unsigned bits, const EncoderParams& params) {
  CostSplit s;
  s.top_bits = bits / 2;
  // The default, an eighth of the key (4 of 32 bits): of the widths swept (4, 8, 12 of 32) the one
  // that gains lane efficiency without reading more distinct nodes than MLHCC (results/README.md).
  s.cost_bits = params.cost_bits > 0 ? params.cost_bits : std::max(1u, bits / 8);
  s.low_bits = bits - s.top_bits > s.cost_bits ? bits - s.top_bits - s.cost_bits : 0u;
  return s;
}

void check_key_bits(Encoder e, unsigned bits, const EncoderParams& params) {
  std::string why = key_bits_problem(e, bits, params);
  if (!why.empty()) throw Error(why);
}

RsBox to_rs_box(const Aabb& b) {
  RsBox r{};
  for (int a = 0; a < 3; ++a) {
    r.bmin[a] = b.min[a];
    r.bmax[a] = b.max[a];
  }
  return r;
}

std::vector<RsCutGroup> rs_cut_groups(const RsBox* boxes, std::size_t n) {
  if (n > RS_MAX_KEY_BITS) throw Error("rs_cut_groups: more boxes than key bits");
  const std::size_t lanes = RS_CUT_LANES;
  std::vector<RsCutGroup> groups(rs_cut_group_count(static_cast<rs_u32>(n)), RsCutGroup{});
  for (std::size_t i = 0; i < n; ++i) {
    const RsBox& b = boxes[i];
    for (int a = 0; a < 3; ++a)
      if (!(b.bmin[a] <= b.bmax[a]))  // also NaN: the sign-picked slab test needs lo <= hi
        throw Error("rs_cut_groups: box " + std::to_string(i) + " is empty or not a number on axis " +
                    std::to_string(a));
    RsCutGroup& g = groups[i / lanes];
    const std::size_t l = lanes - 1 - i % lanes;  // box j of a group in lane 15 − j (keys.h, RsCutGroup)
    g.lo_x.s[l] = b.bmin[0], g.hi_x.s[l] = b.bmax[0];
    g.lo_y.s[l] = b.bmin[1], g.hi_y.s[l] = b.bmax[1];
    g.lo_z.s[l] = b.bmin[2], g.hi_z.s[l] = b.bmax[2];
  }
  return groups;
}

EncodeScene::EncodeScene(const Bvh& bvh, const Aabb& scene_box, const EncoderParams& params)
    : bvh_(&bvh), params_(params), box_(scene_box.empty() ? Aabb{{0, 0, 0}, {0, 0, 0}} : scene_box) {
  for (int a = 0; a < 3; ++a) {
    frame_.box_min[a] = box_.min[a];
    frame_.box_max[a] = box_.max[a];
    const float extent = box_.max[a] - box_.min[a];
    frame_.inv_extent[a] = extent > 0.0f ? 1.0f / extent : 0.0f;  // flat axis: every t is 0
  }
  frame_.twopoint_length = params.twopoint_length_fraction * box_.largest_extent();
  had_ = hierarchically_accumulated_density(bvh, params.had_lambda);
}

const std::vector<std::uint32_t>& EncodeScene::hcc_cut(unsigned size) const {
  auto it = hcc_cuts_.find(size);
  if (it == hcc_cuts_.end()) it = hcc_cuts_.emplace(size, hierarchy_cut(*bvh_, had_, size)).first;
  return it->second;
}

const std::vector<RsBox>& EncodeScene::box_set(Encoder e, unsigned bits) const {
  const auto key = std::make_pair(static_cast<int>(e), bits);
  auto it = box_sets_.find(key);
  if (it != box_sets_.end()) return it->second;
  check_key_bits(e, bits, params_);
  std::vector<RsBox> boxes;
  if (e == Encoder::RegularGrid) {
    for (const Aabb& c : regular_grid_cells(box_, bits)) boxes.push_back(to_rs_box(c));
  } else if (e == Encoder::HCC || e == Encoder::HCC_DIR) {
    const unsigned size = e == Encoder::HCC ? bits : bits - params_.direction_bits;
    for (std::uint32_t n : hcc_cut(size)) boxes.push_back(to_rs_box(node_box(bvh_->nodes[n])));
  } else if (e == Encoder::HCC_TRAFFIC) {
    for (std::uint32_t n : traffic_cut(bits)) boxes.push_back(to_rs_box(node_box(bvh_->nodes[n])));
  } else {
    throw Error(std::string(encoder_name(e)) + " is not a box-set encoder");
  }
  return box_sets_.emplace(key, std::move(boxes)).first->second;
}

void EncodeScene::set_node_traffic(std::vector<std::uint64_t> visits) {
  if (!visits.empty() && visits.size() != bvh_->nodes.size())
    throw Error("node traffic for " + std::to_string(visits.size()) + " nodes, the BVH has " +
                std::to_string(bvh_->nodes.size()));
  traffic_ = std::move(visits);
  traffic_cuts_.clear();
  const int id = static_cast<int>(Encoder::HCC_TRAFFIC);
  std::erase_if(box_sets_, [&](const auto& kv) { return kv.first.first == id; });
  std::erase_if(cut_sets_, [&](const auto& kv) { return kv.first.first == id; });
}

const std::vector<std::uint32_t>& EncodeScene::traffic_cut(unsigned size) const {
  auto it = traffic_cuts_.find(size);
  if (it == traffic_cuts_.end()) {
    const std::vector<double> priority = traffic_priority(had_, traffic_, params_.traffic_blend);
    it = traffic_cuts_.emplace(size, priority_cut(*bvh_, priority, size, 0, &had_)).first;
  }
  return it->second;
}

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

}  // namespace

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

void EncodeScene::set_region_statistics(RegionStatistics stats) {
  const std::size_t regions = std::size_t{1} << params_.region_bits;
  if (!stats.empty() && (stats.splits.size() != regions - 1 || stats.visits.size() != regions))
    throw Error("region statistics for " + std::to_string(stats.visits.size()) + " regions, hcc-region has " +
                std::to_string(regions) + " (" + std::to_string(params_.region_bits) + " region bits)");
  if (!stats.empty()) check_region_splits(stats.splits, params_.region_bits);
  for (const auto& region : stats.visits)
    for (const auto& [node, count] : region)
      if (node >= bvh_->nodes.size())
        throw Error("region statistics name node " + std::to_string(node) + ", the BVH has " +
                    std::to_string(bvh_->nodes.size()));
  region_stats_ = std::move(stats);
  regions_.clear();
}

const EncodeScene::Regions& EncodeScene::regions(unsigned bits) const {
  auto it = regions_.find(bits);
  if (it != regions_.end()) return it->second;
  check_key_bits(Encoder::HCC_REGION, bits, params_);
  const unsigned r = params_.region_bits, size = bits - r;
  Regions g;
  g.region_bits = r;
  g.row_size = size;
  const bool measured = !region_stats_.empty();
  g.splits = measured ? region_stats_.splits : median_region_splits(box_, {}, r);
  g.cells = region_cells(g.splits, r);
  g.boxes = region_boxes(box_, g.splits, r);
  for (std::size_t region = 0; region < g.boxes.size(); ++region) {
    if (measured) {
      // Where this region's rays went: HAD blended with their traffic (a region no ray started in
      // has none, and gets HCC's cut).
      std::vector<std::uint64_t> traffic;
      if (!region_stats_.visits[region].empty()) {
        traffic.assign(bvh_->nodes.size(), 0);
        for (const auto& [node, count] : region_stats_.visits[region]) traffic[node] = count;
      }
      g.cuts.push_back(priority_cut(*bvh_, traffic_priority(had_, traffic, params_.traffic_blend), size, 0, &had_));
    } else {
      g.cuts.push_back(region_cut(*bvh_, had_, size, g.boxes[region]));
    }
  }
  CutRows rows = cut_rows(*bvh_, g.cuts, size);
  g.groups = std::move(rows.groups);
  g.counts = std::move(rows.counts);
  return regions_.emplace(bits, std::move(g)).first->second;
}

const EncodeScene::CutSet& EncodeScene::cut_set(Encoder e, unsigned bits) const {
  const auto key = std::make_pair(static_cast<int>(e), bits);
  auto it = cut_sets_.find(key);
  if (it != cut_sets_.end()) return it->second;
  const auto& boxes = box_set(e, bits);
  CutSet set{rs_cut_groups(boxes.data(), boxes.size()), static_cast<rs_u32>(boxes.size())};
  return cut_sets_.emplace(key, std::move(set)).first->second;
}

const EncodeScene::TwoLevel& EncodeScene::two_level(unsigned bits) const {
  auto it = two_levels_.find(bits);
  if (it != two_levels_.end()) return it->second;
  check_key_bits(Encoder::MLHCC, bits, params_);
  TwoLevel t;
  t.half = bits / 2;
  t.cut = two_level_cut(*bvh_, had_, t.half);
  static_cast<TwoLevelTables&>(t) = two_level_tables(*bvh_, t.cut, t.half);
  return two_levels_.emplace(bits, std::move(t)).first->second;
}

CutRows cut_rows(const Bvh& bvh, const std::vector<std::vector<std::uint32_t>>& cuts, unsigned row) {
  CutRows rows;
  rows.boxes.assign(cuts.size() * row, RsBox{});
  for (std::size_t i = 0; i < cuts.size(); ++i) {
    if (cuts[i].size() > row)
      throw Error("cut_rows: a cut of " + std::to_string(cuts[i].size()) + " nodes in a row of " + std::to_string(row));
    for (std::size_t j = 0; j < cuts[i].size(); ++j) rows.boxes[i * row + j] = to_rs_box(node_box(bvh.nodes[cuts[i][j]]));
    rows.counts.push_back(static_cast<rs_u32>(cuts[i].size()));
    // Row i: its counts[i] boxes, then zero groups up to `row`. The kernels test the whole row and
    // keep the bits of its first counts[i] boxes (cl/keys_cut.h, rs_row_kept).
    auto groups = rs_cut_groups(rows.boxes.data() + i * row, cuts[i].size());
    groups.resize(rs_cut_group_count(row), RsCutGroup{});
    rows.groups.insert(rows.groups.end(), groups.begin(), groups.end());
  }
  return rows;
}

TwoLevelTables two_level_tables(const Bvh& bvh, const TwoLevelCut& cut, unsigned row) {
  TwoLevelTables t;
  for (std::uint32_t n : cut.top) t.top.push_back(to_rs_box(node_box(bvh.nodes[n])));
  t.top_groups = rs_cut_groups(t.top.data(), t.top.size());
  CutRows low = cut_rows(bvh, cut.low, row);
  t.low = std::move(low.boxes);
  t.low_groups = std::move(low.groups);
  t.low_count = std::move(low.counts);
  if (t.low_count.empty()) {  // no top node: keys read row 0 (and keep none of its bits), so there is one
    t.low_count.push_back(0);
    t.low_groups.resize(rs_cut_group_count(row), RsCutGroup{});
  }
  return t;
}

void EncodeScene::set_cost_estimates(std::vector<std::uint64_t> mean_steps) {
  if (!mean_steps.empty() && mean_steps.size() != RS_COST_BINS)
    throw Error("cost estimates for " + std::to_string(mean_steps.size()) + " bins, mlhcc-cost has " +
                std::to_string(RS_COST_BINS));
  cost_means_ = std::move(mean_steps);
  cost_cuts_.clear();
}

const EncodeScene::CostCut& EncodeScene::cost_cut(unsigned bits) const {
  auto it = cost_cuts_.find(bits);
  if (it != cost_cuts_.end()) return it->second;
  check_key_bits(Encoder::MLHCC_COST, bits, params_);
  CostCut t;
  t.split = cost_split(bits, params_);
  t.cut = two_level_cut(*bvh_, had_, t.split.top_bits, t.split.low_bits);
  static_cast<TwoLevelTables&>(t) = two_level_tables(*bvh_, t.cut, t.split.low_bits);
  // The estimate on cost_bits bits: scaled to the largest bin mean, so the field's range covers
  // this batch's estimates; integer arithmetic, the same on every machine.
  t.cost.assign(RS_COST_BINS, 0u);
  if (!cost_means_.empty()) {
    const std::uint64_t largest = *std::max_element(cost_means_.begin(), cost_means_.end());
    for (std::size_t b = 0; b < cost_means_.size(); ++b)
      t.cost[b] = static_cast<rs_u32>((cost_means_[b] << t.split.cost_bits) / (largest + 1));
  }
  return cost_cuts_.emplace(bits, std::move(t)).first->second;
}

std::vector<std::uint64_t> cost_statistics(const RsEncodeFrame& frame, const std::vector<RsRay>& rays,
                                           const std::vector<std::uint32_t>& steps) {
  if (steps.size() != rays.size())
    throw Error("cost_statistics: " + std::to_string(steps.size()) + " step counts for " +
                std::to_string(rays.size()) + " rays");
  constexpr std::size_t kCells = std::size_t{1} << (3 * RS_COST_CELL_LEVELS);
  std::vector<std::uint64_t> bin_sum(RS_COST_BINS, 0), bin_count(RS_COST_BINS, 0);
  std::vector<std::uint64_t> cell_sum(kCells, 0), cell_count(kCells, 0);
  std::uint64_t sum = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const rs_u32 bin = rs_cost_bin(&frame, rays[i]);
    bin_sum[bin] += steps[i], ++bin_count[bin];
    cell_sum[bin >> RS_COST_DIRECTION_BITS] += steps[i], ++cell_count[bin >> RS_COST_DIRECTION_BITS];
    sum += steps[i];
  }
  const std::uint64_t batch_mean = rays.empty() ? 0 : sum * 16 / rays.size();
  std::vector<std::uint64_t> mean(RS_COST_BINS);
  for (std::size_t b = 0; b < RS_COST_BINS; ++b) {
    const std::size_t cell = b >> RS_COST_DIRECTION_BITS;
    mean[b] = bin_count[b] > 0    ? bin_sum[b] * 16 / bin_count[b]
              : cell_count[cell] > 0 ? cell_sum[cell] * 16 / cell_count[cell]
                                     : batch_mean;
  }
  return mean;
}

std::uint64_t encode_ray(Encoder e, unsigned bits, const EncodeScene& scene, const RsRay& ray) {
  switch (encoder_info(e).family) {
    case EncoderFamily::None: return 0;
    case EncoderFamily::Spatial:
      return rs_key_from_code(rs_spatial_code(static_cast<int>(e), &scene.frame(), ray), bits);
    case EncoderFamily::BoxSet: {
      const auto& set = scene.cut_set(e, bits);
      const unsigned dir = e == Encoder::HCC_DIR ? scene.params().direction_bits : 0u;
      const rs_u64 code = rs_box_set_code(ray, set.groups.data(), set.box_count, bits - dir, dir);
      return rs_key_from_code(code, bits);
    }
    case EncoderFamily::RegionCut: {
      const auto& g = scene.regions(bits);
      return rs_key_from_code(
          rs_region_cut_code(ray, g.cells.data(), g.region_bits, g.groups.data(), g.counts.data(), g.row_size), bits);
    }
    case EncoderFamily::TwoLevel: {
      const auto& t = scene.two_level(bits);
      return rs_key_from_code(rs_two_level_cut_code(ray, t.top_groups.data(), static_cast<rs_u32>(t.top.size()),
                                                    t.low_groups.data(), t.low_count.data(), t.half),
                              bits);
    }
    case EncoderFamily::CostCut: {
      const auto& t = scene.cost_cut(bits);
      return rs_key_from_code(rs_cost_cut_code(ray, &scene.frame(), t.top_groups.data(),
                                               static_cast<rs_u32>(t.top.size()), t.low_groups.data(),
                                               t.low_count.data(), t.split.top_bits, t.split.low_bits,
                                               t.cost.data(), bits),
                              bits);
    }
    case EncoderFamily::PrefixPath:
      return rs_key_from_code(rs_prefix_path_code(scene.bvh().nodes.data(), scene.bvh().triangles.data(), ray, bits),
                              bits);
  }
  return 0;
}

std::vector<std::uint64_t> encode_on_host(Encoder e, unsigned bits, const EncodeScene& scene,
                                          const std::vector<RsRay>& rays) {
  check_key_bits(e, bits, scene.params());
  // Build the cached cut data before the threads read it.
  if (encoder_info(e).family == EncoderFamily::BoxSet) scene.cut_set(e, bits);
  if (encoder_info(e).family == EncoderFamily::TwoLevel) scene.two_level(bits);
  if (encoder_info(e).family == EncoderFamily::RegionCut) scene.regions(bits);
  if (encoder_info(e).family == EncoderFamily::CostCut) scene.cost_cut(bits);
  std::vector<std::uint64_t> keys(rays.size());
  auto work = [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) keys[i] = encode_ray(e, bits, scene, rays[i]);
  };
  const unsigned threads = std::max(1u, std::min(16u, std::thread::hardware_concurrency()));
  if (rays.size() < 8192 || threads == 1) {
    work(0, rays.size());
    return keys;
  }
  std::vector<std::thread> pool;
  const std::size_t chunk = (rays.size() + threads - 1) / threads;
  for (unsigned t = 0; t < threads; ++t) {
    const std::size_t b = t * chunk, end = std::min(rays.size(), b + chunk);
    if (b < end) pool.emplace_back(work, b, end);
  }
  for (auto& th : pool) th.join();
  return keys;
}

std::vector<std::uint64_t> encode_on_host(Encoder e, unsigned bits, const Bvh& bvh, const Aabb& scene_box,
                                          const EncoderParams& params, const std::vector<RsRay>& rays) {
  EncodeScene scene(bvh, scene_box, params);
  return encode_on_host(e, bits, scene, rays);
}

}  // namespace raysort
