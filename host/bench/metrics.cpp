#include "bench/metrics.h"

#include <algorithm>
#include <thread>

#include "traverse_binary.h"
#include "traverse_wide.h"

namespace raysort {

double average_number_of_codes(std::span<const std::uint64_t> keys) {
  if (keys.empty()) return 0.0;
  std::uint64_t distinct_total = 0, groups = 0;
  std::uint64_t buf[kWarpSize];
  for (std::size_t g = 0; g < keys.size(); g += kWarpSize) {
    std::size_t n = std::min(kWarpSize, keys.size() - g);
    std::copy_n(keys.begin() + static_cast<std::ptrdiff_t>(g), n, buf);
    std::sort(buf, buf + n);
    distinct_total += static_cast<std::uint64_t>(std::unique(buf, buf + n) - buf);
    ++groups;
  }
  return static_cast<double>(distinct_total) / static_cast<double>(groups);
}

namespace {

struct WarpTally {
  std::uint64_t steps = 0, issued = 0, distinct = 0, warps = 0;
  void add(const WarpTally& o) {
    steps += o.steps;
    issued += o.issued;
    distinct += o.distinct;
    warps += o.warps;
  }
};

// One warp's contribution, from its lanes' trails.
void tally_warp(const std::vector<const std::vector<std::uint32_t>*>& lanes, std::vector<std::uint32_t>& scratch,
                WarpTally& t) {
  std::uint64_t max_steps = 0;
  scratch.clear();
  for (auto* trail : lanes) {
    t.steps += trail->size();
    max_steps = std::max<std::uint64_t>(max_steps, trail->size());
    scratch.insert(scratch.end(), trail->begin(), trail->end());
  }
  t.issued += max_steps * lanes.size();
  std::sort(scratch.begin(), scratch.end());
  t.distinct += static_cast<std::uint64_t>(std::unique(scratch.begin(), scratch.end()) - scratch.begin());
  ++t.warps;
}

SimtModel finish(const WarpTally& t) {
  SimtModel m;
  m.total_steps = t.steps;
  m.warps = t.warps;
  m.lane_efficiency = t.issued ? static_cast<double>(t.steps) / static_cast<double>(t.issued) : 1.0;
  m.distinct_nodes_per_visit = t.steps ? static_cast<double>(t.distinct) / static_cast<double>(t.steps) : 0.0;
  return m;
}

}  // namespace

SimtModel simt_model_from_trails(const std::vector<std::vector<std::uint32_t>>& trails) {
  WarpTally t;
  std::vector<std::uint32_t> scratch;
  std::vector<const std::vector<std::uint32_t>*> lanes;
  for (std::size_t g = 0; g < trails.size(); g += kWarpSize) {
    lanes.clear();
    for (std::size_t i = g; i < std::min(trails.size(), g + kWarpSize); ++i) lanes.push_back(&trails[i]);
    tally_warp(lanes, scratch, t);
  }
  return finish(t);
}

SimtModel simt_model(const Bvh& bvh, const std::vector<RsRay>& rays, const std::uint32_t* order, bool any_hit,
                     TraceVariant variant, TraceLayout layout) {
  const int robust = variant == TraceVariant::Robust ? 1 : 0;
  const int any = any_hit ? 1 : 0;
  WideBvh scratch;
  const bool wide_layout = layout == TraceLayout::Wide;
  const WideBvh& wide = wide_layout ? wide_of(bvh, scratch) : scratch;
  const std::size_t n = rays.size();
  const std::size_t warps = (n + kWarpSize - 1) / kWarpSize;
  const unsigned threads = std::max(1u, std::min(16u, std::thread::hardware_concurrency()));
  // Trails are recorded into a fixed buffer per lane. A step visits a node or a leaf at most once,
  // so a trail is shorter than the node count plus the leaf count (a wide node has at most four
  // leaf children); longer trails could only be truncated in the union, never in the step count.
  const std::size_t most_steps = wide_layout ? wide.nodes.size() * 5 : bvh.nodes.size();
  const rs_u32 cap = static_cast<rs_u32>(std::min<std::size_t>(most_steps, 1u << 16));
  std::vector<WarpTally> partial(threads);
  auto work = [&](unsigned tid) {
    std::vector<std::vector<std::uint32_t>> lane_trails(kWarpSize, std::vector<std::uint32_t>(cap));
    std::vector<const std::vector<std::uint32_t>*> lanes;
    std::vector<std::uint32_t> scratch_ids;
    std::vector<std::vector<std::uint32_t>> trimmed(kWarpSize);
    for (std::size_t w = tid; w < warps; w += threads) {
      lanes.clear();
      for (std::size_t l = 0; l < kWarpSize && w * kWarpSize + l < n; ++l) {
        const std::size_t i = w * kWarpSize + l;
        const RsRay& ray = rays[order ? order[i] : i];
        rs_u32 len = 0;
        if (wide_layout)
          rs_traverse_wide_recorded(wide.nodes.data(), wide.packets.data(), ray, robust, any, nullptr,
                                    lane_trails[l].data(), cap, &len);
        else
          rs_traverse_variant_recorded(bvh.nodes.data(), bvh.triangles.data(), ray, robust, any, nullptr,
                                       lane_trails[l].data(), cap, &len);
        trimmed[l].assign(lane_trails[l].begin(), lane_trails[l].begin() + std::min(len, cap));
        lanes.push_back(&trimmed[l]);
      }
      tally_warp(lanes, scratch_ids, partial[tid]);
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 0; t < threads; ++t) pool.emplace_back(work, t);
  for (auto& th : pool) th.join();
  WarpTally total;
  for (auto& p : partial) total.add(p);
  return finish(total);
}

}  // namespace raysort
