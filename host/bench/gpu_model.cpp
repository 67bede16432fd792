#include "bench/gpu_model.h"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <limits>
#include <sstream>

#include "bench/metrics.h"
#include "bvh_layout.h"
#include "scene/toml_reader.h"
#include "util/embedded.h"
#include "util/error.h"

namespace raysort {

namespace {

constexpr std::string_view kProfileDir = "gpu/profiles/";
constexpr std::uint64_t kEmptyLine = std::numeric_limits<std::uint64_t>::max();

std::uint64_t align_up(std::uint64_t x, std::uint64_t a) { return (x + a - 1) / a * a; }

// Appends the blocks (lines or sectors) of the byte range [addr, addr + bytes).
void range_blocks(std::uint64_t addr, std::uint64_t bytes, unsigned line, std::vector<std::uint64_t>& out) {
  for (std::uint64_t l = addr / line; l <= (addr + bytes - 1) / line; ++l) out.push_back(l);
}

}  // namespace

GpuProfile parse_gpu_profile(const std::string& text, const std::string& origin) {
  const toml::table root = parse_toml_text(text, origin);
  TomlTable t(origin, root, "",
              {"name", "description", "sms", "resident_warps_per_sm", "l1_bytes", "l1_ways", "l2_bytes", "l2_ways",
               "line_bytes", "sector_bytes", "dram_gbps", "l2_gbps", "clock_ghz", "step_cycles",
               "dynamic_fetch_threshold"});
  GpuProfile p;
  p.origin = origin;
  p.name = t.string("name");
  p.description = t.string("description", p.name);
  constexpr std::uint64_t kBig = 1ull << 40;
  p.sms = static_cast<unsigned>(t.integer("sms", 0, 1, 4096));
  p.resident_warps_per_sm = static_cast<unsigned>(t.integer("resident_warps_per_sm", 0, 1, 256));
  p.line_bytes = static_cast<unsigned>(t.integer("line_bytes", 0, 16, 4096));
  p.sector_bytes = static_cast<unsigned>(t.integer("sector_bytes", p.line_bytes, 4, p.line_bytes));
  p.l1_ways = static_cast<unsigned>(t.integer("l1_ways", 0, 1, 64));
  p.l2_ways = static_cast<unsigned>(t.integer("l2_ways", 0, 1, 64));
  p.l1_bytes = t.integer("l1_bytes", 0, p.line_bytes * p.l1_ways, kBig);
  p.l2_bytes = t.integer("l2_bytes", 0, p.line_bytes * p.l2_ways, kBig);
  p.dram_gbps = t.number("dram_gbps");
  p.l2_gbps = t.number("l2_gbps");
  p.clock_ghz = t.number("clock_ghz");
  p.step_cycles = t.number("step_cycles");
  p.dynamic_fetch_threshold = static_cast<unsigned>(t.integer("dynamic_fetch_threshold", 0, 0, kWarpSize));
  if (p.line_bytes & (p.line_bytes - 1)) t.fail("line_bytes", "must be a power of two");
  if (p.line_bytes % p.sector_bytes) t.fail("sector_bytes", "must divide line_bytes");
  for (auto [key, v] : {std::pair<const char*, double>{"dram_gbps", p.dram_gbps}, {"l2_gbps", p.l2_gbps},
                        {"clock_ghz", p.clock_ghz}, {"step_cycles", p.step_cycles}})
    if (!(v > 0)) t.fail(key, "must be a positive number");
  return p;
}

std::vector<std::string> gpu_profile_names() {
  std::vector<std::string> names;
  for (const auto& f : embedded_files())
    if (f.path.starts_with(kProfileDir) && f.path.ends_with(".toml"))
      names.emplace_back(f.path.substr(kProfileDir.size(), f.path.size() - kProfileDir.size() - 5));
  std::sort(names.begin(), names.end());
  return names;
}

GpuProfile load_gpu_profile(const std::string& name_or_path) {
  if (name_or_path.ends_with(".toml")) {
    std::ifstream in(name_or_path);
    if (!in) throw Error(fmt::format("cannot read GPU profile {}", name_or_path));
    std::stringstream ss;
    ss << in.rdbuf();
    return parse_gpu_profile(ss.str(), name_or_path);
  }
  const std::string path = std::string(kProfileDir) + name_or_path + ".toml";
  auto text = find_embedded(path);
  if (!text)
    throw Error(fmt::format("unknown GPU profile '{}'; known: {} (or a path to a .toml profile)", name_or_path,
                            fmt::join(gpu_profile_names(), ", ")));
  return parse_gpu_profile(std::string(*text), "embedded:" + path);
}

LruCache::LruCache(std::uint64_t bytes, unsigned line_bytes, unsigned ways)
    : ways_(ways), sets_(std::max<std::uint64_t>(1, bytes / line_bytes / ways)), tags_(sets_ * ways, kEmptyLine) {}

bool LruCache::access(std::uint64_t line) {
  std::uint64_t* set = &tags_[(line % sets_) * ways_];
  unsigned i = 0;
  while (i < ways_ && set[i] != line) ++i;
  const bool hit = i < ways_;
  if (!hit) i = ways_ - 1;  // evict the least recently used (or an empty way: empty ways sit last)
  std::copy_backward(set, set + i, set + i + 1);
  set[0] = line;
  return hit;
}

GpuTime gpu_model_time(const GpuCounts& c, const GpuProfile& p) {
  GpuTime t;
  if (c.replayed_warps == 0) return t;
  // A sampled replay stands for all warps in proportion (docs/gpu-model.md, "Cost").
  const double scale = static_cast<double>(c.warps) / static_cast<double>(c.replayed_warps);
  t.issue_s = static_cast<double>(c.warp_steps) * scale * p.step_cycles / (p.sms * p.clock_ghz * 1e9);
  const double l2_bytes = static_cast<double>(c.l2_hits + c.l2_misses) * p.sector_bytes;
  t.memory_s = scale * (static_cast<double>(c.dram_bytes) / (p.dram_gbps * 1e9) + l2_bytes / (p.l2_gbps * 1e9));
  // A sum, not a roofline max: traversal is latency-bound, and the resident warps hide only part of
  // the memory time behind issue. Chosen on the paper's Table 2 (docs/gpu-model.md: leave-one-scene-out
  // MAE 0.116 for the sum, 0.154 for the max).
  t.total_s = t.issue_s + t.memory_s;
  return t;
}

GpuAddressMap::GpuAddressMap(const WideBvh& wide, std::size_t rays) {
  (void)rays;
  prim_base_ = align_up(wide.nodes.size() * sizeof(RsWideNode), 4096);
  ray_base_ = prim_base_ + align_up(wide.packets.size() * sizeof(RsTriPacket), 4096);
}

GpuAddressMap::GpuAddressMap(const Wide8Bvh& wide8, std::size_t rays)
    : wide_node_bytes_(sizeof(RsWide8Node)), wide_packet_bytes_(sizeof(RsTriPacket8)), wide8_(true) {
  (void)rays;
  prim_base_ = align_up(wide8.nodes.size() * sizeof(RsWide8Node), 4096);
  ray_base_ = prim_base_ + align_up(wide8.packets.size() * sizeof(RsTriPacket8), 4096);
}

GpuAddressMap::GpuAddressMap(const CwBvh& cw, std::size_t rays)
    : wide_node_bytes_(sizeof(RsCwbvhNode)), wide_packet_bytes_(sizeof(RsTriangle)) {
  (void)rays;
  prim_base_ = align_up(cw.nodes.size() * sizeof(RsCwbvhNode), 4096);
  ray_base_ = prim_base_ + align_up(cw.triangles.size() * sizeof(RsTriangle), 4096);
}

GpuAddressMap::GpuAddressMap(const Bvh& binary, std::size_t rays) : binary_(binary.nodes.data()) {
  (void)rays;
  prim_base_ = align_up(binary.nodes.size() * sizeof(RsBvhNode), 4096);
  ray_base_ = prim_base_ + align_up(binary.triangles.size() * sizeof(RsTriangle), 4096);
}

void GpuAddressMap::step_blocks(std::uint32_t ref, unsigned line, std::vector<std::uint64_t>& out,
                                std::uint32_t leaf_reads) const {
  // An any-hit ray that stops at a hit reads its leaf's packets or triangles up to that one only.
  auto read = [&](std::uint64_t count) { return leaf_reads > 0 ? std::min<std::uint64_t>(count, leaf_reads) : count; };
  if (!binary_) {
    if (!(ref & RS_WIDE_LEAF)) return range_blocks(node_base_ + ref * wide_node_bytes_, wide_node_bytes_, line, out);
    // An 8-wide leaf that shares its packet reads the packet's rows all the same (a row's eight lanes
    // are one 32-byte sector).
    const WideLeaf leaf = wide_leaf(ref, wide8_);
    const std::uint64_t first = leaf.first, count = leaf.count();
    return range_blocks(prim_base_ + first * wide_packet_bytes_, read(count) * wide_packet_bytes_, line, out);
  }
  const RsBvhNode& n = binary_[ref];
  range_blocks(node_base_ + std::uint64_t{ref} * sizeof(RsBvhNode), sizeof(RsBvhNode), line, out);
  if (n.count == 0)
    range_blocks(node_base_ + std::uint64_t{n.first} * sizeof(RsBvhNode), 2 * sizeof(RsBvhNode), line, out);
  else
    range_blocks(prim_base_ + std::uint64_t{n.first} * sizeof(RsTriangle), read(n.count) * sizeof(RsTriangle), line,
                 out);
}

bool GpuAddressMap::is_leaf(std::uint32_t ref) const {
  return binary_ ? binary_[ref].count != 0 : (ref & RS_WIDE_LEAF) != 0;
}

std::uint64_t while_while_steps(const WarpTrails& warp, const GpuAddressMap& map) {
  std::vector<std::size_t> at(warp.lanes.size(), 0);  // each lane's next step
  // One loop of an iteration: every lane takes its run of consecutive steps of one kind (leaves or
  // inner nodes); the warp issues the longest.
  auto longest_run = [&](bool leaves) {
    std::size_t longest = 0;
    for (std::size_t l = 0; l < warp.lanes.size(); ++l) {
      const auto& trail = warp.lanes[l];
      const std::size_t start = at[l];
      while (at[l] < trail.size() && map.is_leaf(trail[at[l]]) == leaves) ++at[l];
      longest = std::max(longest, at[l] - start);
    }
    return longest;
  };
  std::uint64_t steps = 0;
  for (;;) {
    const std::size_t inner = longest_run(false);
    const std::size_t leaves = longest_run(true);
    if (inner == 0 && leaves == 0) return steps;
    steps += inner + leaves;
  }
}

void GpuAddressMap::ray_blocks(std::uint32_t ray, unsigned line, std::vector<std::uint64_t>& out) const {
  range_blocks(ray_base_ + std::uint64_t{ray} * sizeof(RsRay), sizeof(RsRay), line, out);
}

GpuReplay::GpuReplay(const GpuProfile& profile, const GpuAddressMap& map)
    : profile_(profile),
      map_(map),
      l1_(profile.sms, LruCache(profile.l1_bytes, profile.line_bytes, profile.l1_ways)),
      l2_(profile.l2_bytes, profile.sector_bytes, profile.l2_ways) {}

void GpuReplay::warp_step(unsigned sm, const WarpTrails& warp, std::size_t step) {
  sectors_.clear();
  refs_.clear();
  for (std::size_t l = 0; l < warp.lanes.size(); ++l) {
    if (step == 0 && l < warp.rays.size()) map_.ray_blocks(warp.rays[l], profile_.sector_bytes, sectors_);
    if (step >= warp.lanes[l].size()) continue;
    const bool last = step + 1 == warp.lanes[l].size();
    const std::uint64_t reads = last && l < warp.last_reads.size() ? warp.last_reads[l] : 0;
    refs_.push_back(reads << 32 | warp.lanes[l][step]);
  }
  issue(sm, warp.lanes.size());
}

void GpuReplay::issue(unsigned sm, std::uint64_t lanes) {
  const unsigned sector = profile_.sector_bytes, per_line = profile_.line_bytes / sector;
  const std::uint64_t active = refs_.size();
  // Lanes of a coherent warp share most references: expanding each distinct one once keeps the
  // sector list short (the replay's cost is mostly this list; docs/gpu-model.md, "Cost").
  std::sort(refs_.begin(), refs_.end());
  refs_.erase(std::unique(refs_.begin(), refs_.end()), refs_.end());
  for (std::uint64_t r : refs_)
    map_.step_blocks(static_cast<std::uint32_t>(r), sector, sectors_, static_cast<std::uint32_t>(r >> 32));
  // Lanes of one load instruction that read the same line are served by one request (coalescing);
  // an L1 miss fetches from L2 only the sectors of that line the lanes read (as NVIDIA's L1/L2 do).
  std::sort(sectors_.begin(), sectors_.end());
  sectors_.erase(std::unique(sectors_.begin(), sectors_.end()), sectors_.end());
  ++counts_.warp_steps;
  counts_.idle_lanes += lanes - active;
  bool to_l2 = false, to_dram = false;
  for (std::size_t i = 0; i < sectors_.size();) {
    const std::uint64_t line = sectors_[i] / per_line;
    std::size_t end = i;
    while (end < sectors_.size() && sectors_[end] / per_line == line) ++end;
    ++counts_.requests;
    if (l1_[sm].access(line)) {
      ++counts_.l1_hits;
    } else {
      ++counts_.l1_misses;
      to_l2 = true;
      for (std::size_t k = i; k < end; ++k) {
        if (l2_.access(sectors_[k])) {
          ++counts_.l2_hits;
        } else {
          ++counts_.l2_misses;
          counts_.dram_bytes += sector;
          to_dram = true;
        }
      }
    }
    i = end;
  }
  counts_.steps_dram += to_dram;
  counts_.steps_l2 += to_l2 && !to_dram;
}

void GpuReplay::replay_wave(std::span<const WarpTrails> warps) {
  std::vector<std::size_t> len(warps.size(), 0);
  for (std::size_t k = 0; k < warps.size(); ++k)
    for (const auto& lane : warps[k].lanes) len[k] = std::max(len[k], lane.size());
  const std::size_t longest = len.empty() ? 0 : *std::max_element(len.begin(), len.end());
  for (std::size_t step = 0; step < longest; ++step)
    for (unsigned sm = 0; sm < profile_.sms; ++sm)
      for (std::size_t k = sm; k < warps.size(); k += profile_.sms)
        if (step < len[k]) warp_step(sm, warps[k], step);
  for (const WarpTrails& warp : warps) counts_.ww_steps += while_while_steps(warp, map_);
  counts_.replayed_warps += warps.size();
}

bool GpuReplay::persistent_turn(std::size_t w, bool last) {
  std::vector<Lane>& warp = resident_[w];
  auto tracing = [](const Lane& lane) { return lane.step < lane.trail.size(); };
  const auto active = static_cast<std::size_t>(std::count_if(warp.begin(), warp.end(), tracing));
  // The threshold is at most kWarpSize (parse_gpu_profile), so a warp that fetches has a finished lane.
  if (active < profile_.dynamic_fetch_threshold) {
    // The finished lanes fetch together (one atomic add per warp in the kernel): wait for rays
    // rather than fetch fewer than a later chunk would give.
    if (!last && to_fetch_.size() < kWarpSize - active) return false;
    for (Lane& lane : warp) {
      if (to_fetch_.empty()) break;
      if (tracing(lane)) continue;
      lane = std::move(to_fetch_.front());
      to_fetch_.pop_front();
    }
  }
  sectors_.clear();
  refs_.clear();
  for (Lane& lane : warp) {
    if (!tracing(lane)) continue;
    if (lane.step == 0) map_.ray_blocks(lane.ray, profile_.sector_bytes, sectors_);
    const bool final_step = lane.step + 1 == lane.trail.size();
    refs_.push_back(std::uint64_t{final_step ? lane.last_reads : 0u} << 32 | lane.trail[lane.step]);
    ++lane.step;
  }
  if (!refs_.empty()) {
    issue(static_cast<unsigned>(w % profile_.sms), kWarpSize);
    any_stepped_ = true;
  }
  return true;
}

void GpuReplay::replay_stream(std::span<WarpTrails> warps, bool last) {
  if (resident_.empty()) resident_.assign(wave_warps(), std::vector<Lane>(kWarpSize));
  for (WarpTrails& warp : warps) {
    for (std::size_t l = 0; l < warp.lanes.size(); ++l) {
      Lane lane;
      lane.trail = std::move(warp.lanes[l]);
      lane.ray = l < warp.rays.size() ? warp.rays[l] : 0;
      lane.last_reads = l < warp.last_reads.size() ? warp.last_reads[l] : 0;
      to_fetch_.push_back(std::move(lane));
    }
  }
  counts_.replayed_warps += warps.size();
  // Rounds: every resident warp takes one turn, SM by SM, warp by warp (warp w runs on SM w mod sms,
  // the order replay_wave uses), until no warp steps and no ray is left to fetch.
  const std::size_t per_sm = profile_.resident_warps_per_sm;
  for (;;) {
    for (; next_warp_ < resident_.size(); ++next_warp_) {
      const std::size_t sm = next_warp_ / per_sm, k = next_warp_ % per_sm;
      if (!persistent_turn(k * profile_.sms + sm, last)) return;
    }
    next_warp_ = 0;
    const bool done = !any_stepped_ && to_fetch_.empty();
    any_stepped_ = false;
    if (done) return;
  }
}

}  // namespace raysort
