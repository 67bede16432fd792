#include "bench/metrics.h"

#include <algorithm>
#include <optional>
#include <thread>

#include "traverse_binary.h"
#include "traverse_cwbvh.h"
#include "traverse_wide.h"
#include "traverse_wide8.h"
#include "util/parallel.h"

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

using Lanes = std::vector<const std::vector<std::uint32_t>*>;

// One warp's steps and issued lane-steps, from its lanes' trails.
void tally_steps(const Lanes& lanes, WarpTally& t) {
  std::uint64_t max_steps = 0;
  for (auto* trail : lanes) {
    t.steps += trail->size();
    max_steps = std::max<std::uint64_t>(max_steps, trail->size());
  }
  t.issued += max_steps * lanes.size();
  ++t.warps;
}

// One warp's contribution, for trails of any ids: the union's size by sorting.
void tally_warp(const Lanes& lanes, std::vector<std::uint32_t>& scratch, WarpTally& t) {
  tally_steps(lanes, t);
  scratch.clear();
  for (auto* trail : lanes) scratch.insert(scratch.end(), trail->begin(), trail->end());
  std::sort(scratch.begin(), scratch.end());
  t.distinct += static_cast<std::uint64_t>(std::unique(scratch.begin(), scratch.end()) - scratch.begin());
}

// The size of a warp's union of visited nodes, for trails on a tree of known size: each node's slot
// holds the number of the last warp that visited it, so the count is linear in the trail length.
// Sorting the union (tally_warp) was 2.6 % of a quick preset's samples (issue 42, item 5); the
// count is the same. Slots: a binary node or a wide inner node by its index, a wide leaf after the
// inner nodes: a 4-wide one (RS_WIDE_LEAF | first packet << 2 | count - 1, cl/bvh_layout.h) by its
// first packet (no two share it), an 8-wide one by its first lane (RS_WIDE8_LEAF_SLOT: its small
// leaves share packets).
class DistinctNodes {
 public:
  DistinctNodes(std::size_t inner, std::size_t packets, bool wide8 = false)
      : inner_(inner), wide8_(wide8), last_(inner + (wide8 ? 8 : 1) * packets, 0) {}
  std::uint64_t count(const Lanes& lanes) {
    ++warp_;
    std::uint64_t distinct = 0;
    for (auto* trail : lanes)
      for (std::uint32_t ref : *trail) {
        std::uint32_t& last = last_[slot(ref)];
        distinct += last != warp_;
        last = warp_;
      }
    return distinct;
  }

 private:
  std::size_t slot(std::uint32_t ref) const {
    if (!(ref & RS_WIDE_LEAF)) return ref;
    return inner_ + (wide8_ ? RS_WIDE8_LEAF_SLOT(ref) : RS_WIDE_LEAF_FIRST(ref));
  }
  std::size_t inner_;
  bool wide8_;
  std::vector<std::uint32_t> last_;
  std::uint32_t warp_ = 0;
};

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
  Lanes lanes;
  for (std::size_t g = 0; g < trails.size(); g += kWarpSize) {
    lanes.clear();
    for (std::size_t i = g; i < std::min(trails.size(), g + kWarpSize); ++i) lanes.push_back(&trails[i]);
    tally_warp(lanes, scratch, t);
  }
  return finish(t);
}

namespace {

// Records the trails of warps [first, first + slots.size()) (rays in trace order) into `slots`,
// warp by warp on host threads, and adds their SIMT tallies to `partial` (one per thread).
struct TrailRecorder {
  const Bvh& bvh;
  const WideBvh& wide;
  const Wide8Bvh& wide8;
  const CwBvh& cw;
  const std::vector<RsRay>& rays;
  const std::uint32_t* order;
  int robust, any;
  bool wide_layout, wide8_layout, cw_layout;
  rs_u32 cap;
  const RayTrails* cached;  // filled: each lane's trail is read, not walked

  // An any-hit traversal stops in the leaf it hits, right after the packet (wide) or triangle
  // (binary) holding the hit triangle: how many of the leaf's it read (the GPU model's reads of
  // that last step). The leaf's triangles are distinct, so the first one holding the id is it.
  std::uint32_t leaf_reads_until(std::uint32_t tri, std::uint32_t leaf_ref) const {
    if (cw_layout) return 0;  // a cwbvh step reads one triangle: all of it
    if (wide_layout || wide8_layout) {
      const WideLeaf leaf = wide_leaf(leaf_ref, wide8_layout);
      const std::uint32_t first = leaf.first, count = leaf.count();
      for (std::uint32_t k = 0; k < count; ++k)
        for (std::uint32_t id : wide8_layout ? std::span<const std::uint32_t>(wide8.packets[first + k].id)
                                             : std::span<const std::uint32_t>(wide.packets[first + k].id))
          if (id == tri) return k + 1;
      return 0;
    }
    const RsBvhNode& n = bvh.nodes[leaf_ref];
    for (std::uint32_t k = 0; k < n.count; ++k)
      if (bvh.triangles[n.first + k].id == tri) return k + 1;
    return 0;
  }

  void record(std::size_t first_warp, std::span<WarpTrails> slots, std::vector<WarpTally>& partial) const {
    const auto threads = static_cast<unsigned>(partial.size());
    auto work = [&](unsigned tid) {
      std::vector<std::uint32_t> buffer(cap);
      DistinctNodes distinct = wide_layout    ? DistinctNodes(wide.nodes.size(), wide.packets.size())
                               : wide8_layout ? DistinctNodes(wide8.nodes.size(), wide8.packets.size(), true)
                               : cw_layout    ? DistinctNodes(cw.nodes.size(), cw.triangles.size())
                                              : DistinctNodes(bvh.nodes.size(), 0);
      Lanes lanes;
      for (std::size_t k = tid; k < slots.size(); k += threads) {
        WarpTrails& w = slots[k];
        const std::size_t first_ray = (first_warp + k) * kWarpSize;
        // Resized, not cleared: the lanes keep their capacity from wave to wave.
        w.lanes.resize(std::min(kWarpSize, rays.size() - first_ray));
        w.rays.clear();
        w.last_reads.clear();
        lanes.clear();
        for (std::size_t l = 0; l < w.lanes.size(); ++l) {
          const std::size_t i = first_ray + l;
          const std::uint32_t ray_index = order ? order[i] : static_cast<std::uint32_t>(i);
          w.rays.push_back(ray_index);
          if (cached) {
            w.lanes[l].assign(cached->steps.begin() + static_cast<std::ptrdiff_t>(cached->begin[ray_index]),
                              cached->steps.begin() + static_cast<std::ptrdiff_t>(cached->begin[ray_index + 1]));
            w.last_reads.push_back(cached->last_reads[ray_index]);
            continue;
          }
          rs_u32 len = 0;
          const RsHit hit =
              wide_layout    ? rs_traverse_wide_recorded(wide.nodes.data(), wide.packets.data(), rays[ray_index],
                                                         robust, any, nullptr, buffer.data(), cap, &len)
              : wide8_layout ? rs_traverse_wide8_recorded(wide8.nodes.data(), wide8.packets.data(), rays[ray_index],
                                                          robust, any, nullptr, buffer.data(), cap, &len)
              : cw_layout    ? rs_traverse_cwbvh_recorded(cw.nodes.data(), cw.triangles.data(), rays[ray_index], robust,
                                                          any, nullptr, buffer.data(), cap, &len)
                             : rs_traverse_variant_recorded(bvh.nodes.data(), bvh.triangles.data(), rays[ray_index],
                                                            robust, any, nullptr, buffer.data(), cap, &len);
          w.lanes[l].assign(buffer.begin(), buffer.begin() + std::min(len, cap));
          w.last_reads.push_back(any && hit.tri != RS_NO_HIT && len > 0 && len <= cap
                                     ? leaf_reads_until(hit.tri, buffer[len - 1])
                                     : 0);
        }
        for (const auto& lane : w.lanes) lanes.push_back(&lane);
        tally_steps(lanes, partial[tid]);
        partial[tid].distinct += distinct.count(lanes);
      }
    };
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < threads; ++t) pool.emplace_back(work, t);
    for (auto& th : pool) th.join();
  }
};

}  // namespace

SimtModel simt_model(const Bvh& bvh, const std::vector<RsRay>& rays, const std::uint32_t* order, bool any_hit,
                     TraceVariant variant, TraceLayout layout, const GpuProfile* gpu, GpuCounts* gpu_counts,
                     RayTrails* trails) {
  WideBvh scratch;
  // Each class's model walks the tree its kernels walk, one ray per lane: the binary tree (binary,
  // binary-ww), the 8-wide one (wide8, stream, coherent: split_tree), the compressed one (cwbvh), else the 4-wide one (the
  // packet classes too: the model's warp of 32 lanes is their packet, at a GPU's width).
  const bool wide_layout = walks_wide_tree(layout), wide8_layout = tree_kind(layout) == TreeKind::Wide8;
  const bool cw_layout = tree_kind(layout) == TreeKind::Compressed8;
  const WideBvh& wide = wide_layout ? wide_of(bvh, scratch) : scratch;
  const Wide8Bvh no_wide8;
  const Wide8Bvh& wide8 = wide8_layout ? split_tree(bvh).wide8 : no_wide8;
  const CwBvh cw = cw_layout ? collapse_to_cwbvh(bvh) : CwBvh{};
  const std::size_t n = rays.size();
  const std::size_t warps = (n + kWarpSize - 1) / kWarpSize;
  const unsigned threads = host_threads();
  // Trails are recorded into a fixed buffer per lane. A step visits a node or a leaf at most once,
  // so a trail is shorter than the node count plus the leaf count (a wide node has at most four, or
  // eight, leaf children); longer trails could only be truncated in the union, never in the step count.
  // (cwbvh: a node or one triangle per step.)
  const std::size_t most_steps = wide_layout    ? wide.nodes.size() * 5
                                 : wide8_layout ? wide8.nodes.size() * 9
                                 : cw_layout    ? cw.nodes.size() + cw.triangles.size()
                                                : bvh.nodes.size();
  const rs_u32 cap = static_cast<rs_u32>(std::min<std::size_t>(most_steps, 1u << 16));
  const bool read_trails = trails && trails->filled() && trails->begin.size() == rays.size() + 1;
  // Filled in ray order, wave after wave, while it fits its budget (paper-1spp on sibenik: 94 orders of
  // 2 M rays, each of which walked the whole batch again on the host).
  RayTrails* fill = trails && !trails->filled() && !trails->over_budget && !order ? trails : nullptr;
  if (fill) fill->begin.assign(1, 0);
  const TrailRecorder recorder{bvh, wide, wide8, cw, rays, order, variant == TraceVariant::Robust ? 1 : 0,
                               any_hit ? 1 : 0, wide_layout, wide8_layout, cw_layout, cap,
                               read_trails ? trails : nullptr};
  std::optional<GpuAddressMap> map;
  std::optional<GpuReplay> replay;
  if (gpu) {
    map = wide_layout    ? GpuAddressMap(wide, n)
          : wide8_layout ? GpuAddressMap(wide8, n)
          : cw_layout    ? GpuAddressMap(cw, n)
                         : GpuAddressMap(bvh, n);
    replay.emplace(*gpu, *map);
  }
  // Warps are recorded a wave at a time (the GPU model's resident set), so the trails of only one
  // wave are held; the SIMT tallies are integer sums, the same in any grouping.
  const std::size_t wave = replay ? replay->wave_warps() : std::size_t{4096};
  std::vector<WarpTrails> slots(std::min(wave, warps));
  std::vector<WarpTally> partial(threads);
  for (std::size_t w0 = 0; w0 < warps; w0 += wave) {
    std::span<WarpTrails> now(slots.data(), std::min(wave, warps - w0));
    recorder.record(w0, now, partial);
    if (fill) {
      for (const WarpTrails& w : now)
        for (std::size_t l = 0; l < w.lanes.size(); ++l) {
          fill->steps.insert(fill->steps.end(), w.lanes[l].begin(), w.lanes[l].end());
          fill->begin.push_back(fill->steps.size());
          fill->last_reads.push_back(w.last_reads[l]);
        }
      if (fill->bytes() > fill->budget_bytes) {
        *fill = RayTrails{fill->budget_bytes, {}, {}, {}, true};
        fill = nullptr;
      }
    }
    if (!replay) continue;
    if (replay->dynamic_fetch())
      replay->replay_stream(now, w0 + now.size() == warps);
    else
      replay->replay_wave(now);
  }
  WarpTally total;
  for (auto& p : partial) total.add(p);
  if (replay && gpu_counts) {
    *gpu_counts = replay->counts();
    gpu_counts->warps = warps;
    // A while-while kernel issues its while-while steps (the same trails, lanes waiting for the other
    // kind of step): the count the model's time reads.
    if (loops_while_while(layout) && !replay->dynamic_fetch()) gpu_counts->warp_steps = gpu_counts->ww_steps;
  }
  return finish(total);
}

}  // namespace raysort
