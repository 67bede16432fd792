#include "bench/shard.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <map>
#include <regex>
#include <set>

#include "bench/batch_file.h"
#include "bench/record.h"
#include "render/batches.h"
#include "scene/load.h"
#include "util/error.h"

namespace raysort {

ShardSpec ShardSpec::parse(const std::string& text) {
  static const std::regex re(R"(^\s*([0-9]{1,6})\s*/\s*([0-9]{1,6})\s*$)");
  std::smatch m;
  if (!std::regex_match(text, m, re))
    throw Error(fmt::format("--shard '{}': expected i/N (shard i of N, numbered from 1), e.g. --shard 2/4", text));
  ShardSpec s;
  s.index = static_cast<unsigned>(std::stoul(m[1]));
  s.count = static_cast<unsigned>(std::stoul(m[2]));
  if (s.count == 0) throw Error(fmt::format("--shard '{}': the number of shards must be at least 1", text));
  if (s.index < 1 || s.index > s.count)
    throw Error(fmt::format("--shard '{}': shards are numbered from 1, so the shards of {} are 1/{} ... {}/{}", text,
                            s.count, s.count, s.count, s.count));
  return s;
}

std::string ShardSpec::str() const { return fmt::format("{}/{}", index, count); }

SceneFacts scene_facts_of(const Scene& s, const FrameSize& frame) {
  SceneFacts f;
  f.triangles = s.triangle_count();
  f.rays_per_batch = std::uint64_t{frame.width} * frame.height * frame.spp;
  f.shadow_rays_per_bounce = next_event_estimation(s) ? s.effects.shadow_rays_per_bounce : 0;
  f.max_bounces = s.effects.max_bounces;
  return f;
}

SceneFacts load_scene_facts(const std::string& scene, const MatrixSpec& spec, const std::string& scene_root) {
  SceneOptions opts;
  opts.scene_root = scene_root;
  // The camera's resolution does not change the geometry or effects; the sampling overrides do.
  opts.frame = {1, 1, 1, spec.frame.shadow_rays, spec.frame.bounces};
  return scene_facts_of(load_scene(scene, opts), spec.frame);
}

namespace {

// Encode + sort on top of the trace, in percent of one trace (see matrix_cells in shard.h).
std::uint64_t encoder_weight_pct(Encoder e) { return encoder_info(e).cost_weight_pct; }

}  // namespace

std::vector<PlannedCell> matrix_cells(const MatrixSpec& spec,
                                      const std::function<SceneFacts(const std::string&)>& facts) {
  // The encoders the runner visits: the spec's order, NoSort apart (it is every batch's baseline).
  std::vector<Encoder> encoders;
  for (Encoder e : spec.encoders)
    if (e != Encoder::NoSort && std::find(encoders.begin(), encoders.end(), e) == encoders.end()) encoders.push_back(e);
  std::vector<PlannedCell> out;
  std::set<std::string> seen;
  for (const auto& scene : spec.scenes) {
    const SceneFacts f = facts(scene);
    std::vector<std::string> possible;
    for (const PossibleBatch& b : possible_batches(f.shadow_rays_per_bounce > 0, f.max_bounces))
      possible.push_back(b.name);
    if (!spec.ray_file.empty()) possible = {ray_file_batch_name(spec.ray_file)};  // the file's batch alone
    std::vector<std::string> batches;
    for (const auto& b : spec.batches.empty() ? possible : spec.batches)
      if (std::find(possible.begin(), possible.end(), b) != possible.end()) batches.push_back(b);
    const std::uint64_t depth = std::max<std::uint64_t>(1, std::bit_width(f.triangles));
    for (const auto& batch : batches) {
      const std::uint64_t rays = batch.rfind("shadow", 0) == 0 ? f.rays_per_batch * f.shadow_rays_per_bounce
                                                               : f.rays_per_batch;
      for (const TraceVariant variant : spec.variants) {
        for (const TraceLayout layout : spec.layouts) {
          for (const BaselineOrder baseline : spec.baselines) {
            auto add = [&](Encoder encoder, unsigned bits, unsigned top, RayAccess access) {
              CellRecord c;
              c.scene = scene, c.batch = batch, c.encoder = encoder_name(encoder), c.bits = bits, c.top_bits = top;
              c.variant = trace_variant_name(variant), c.access = ray_access_name(access);
              c.baseline = baseline_order_name(baseline), c.layout = trace_layout_name(layout);
              if (!seen.insert(c.id()).second) return;  // a scene named twice runs once
              out.push_back({c.id(), scene, batch, c.variant, rays * depth * encoder_weight_pct(encoder), 0, c.encoder,
                             c.access, bits, top, c.baseline, c.layout});
            };
            add(Encoder::NoSort, 0, 0, RayAccess::Gather);  // the baseline order itself: no access mode to choose
            const std::vector<unsigned> bits = spec.bits_for(scene);
            for (Encoder e : encoders) {
              for (unsigned b : bits)
                for (RayAccess a : spec.accesses) add(e, b, 0, a);
              for (unsigned k : spec.top_bits)
                for (RayAccess a : spec.accesses) add(e, bits.back(), k, a);
            }
          }
        }
      }
    }
  }
  return out;
}

std::string round_group(const PlannedCell& c) {
  return fmt::format("{}/{}/{}/{}/{}", c.scene, c.batch, c.variant, c.layout, c.baseline);
}

std::string sort_group(const PlannedCell& c) {
  return fmt::format("{}/{}/{}/{}", round_group(c), c.encoder, c.bits, c.top_bits);
}

std::vector<PlannedCell> plan_shards(std::vector<PlannedCell> cells, unsigned count) {
  if (count == 0) throw Error("plan_shards: the number of shards must be at least 1");
  // Round groups as consecutive runs (the visiting order keeps a group's cells together).
  struct Group {
    std::size_t begin = 0, end = 0;
    std::uint64_t cost = 0;
  };
  std::vector<Group> groups;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (groups.empty() || round_group(cells[groups.back().begin]) != round_group(cells[i])) groups.push_back({i, i, 0});
    groups.back().end = i + 1;
    groups.back().cost += cells[i].cost;
  }
  unsigned __int128 total = 0;
  for (const Group& g : groups) total += g.cost;
  unsigned __int128 before = 0;  // cost of the groups before this one
  for (const Group& g : groups) {
    // 128-bit: 2 · total · N exceeds 64 bits for a full-HD matrix split in hundreds.
    const unsigned __int128 mid2 = 2 * before + g.cost;  // twice the group's midpoint
    const unsigned shard =
        total == 0 ? 0u : static_cast<unsigned>(std::min<unsigned __int128>(mid2 * count / (2 * total), count - 1));
    for (std::size_t i = g.begin; i < g.end; ++i) cells[i].shard = shard + 1;
    before += g.cost;
  }
  return cells;
}

std::vector<ShardLoad> shard_loads(const std::vector<PlannedCell>& planned, unsigned count) {
  std::vector<ShardLoad> loads(count);
  for (const auto& c : planned) {
    if (c.shard < 1 || c.shard > count) continue;
    ++loads[c.shard - 1].cells;
    loads[c.shard - 1].cost += c.cost;
  }
  return loads;
}

nlohmann::json shard_meta(const MatrixSpec& spec, const ShardSpec& shard, const std::vector<PlannedCell>& planned) {
  nlohmann::json plan = nlohmann::json::object();
  std::string text = spec.to_json().dump() + "\n";
  for (const auto& c : planned) {
    plan[c.id] = c.shard;
    text += fmt::format("{}={}\n", c.id, c.shard);
  }
  return {{"index", shard.index},
          {"count", shard.count},
          {"cells", planned.size()},
          {"plan_hash", fnv1a_hex(text.data(), text.size())},
          {"plan", plan}};
}

std::string format_plan(const std::vector<PlannedCell>& planned, unsigned count) {
  const auto loads = shard_loads(planned, count);
  std::uint64_t total = 0, largest = 0;
  std::map<std::string, std::uint64_t> group_cost;
  for (const auto& c : planned) total += c.cost, group_cost[round_group(c)] += c.cost;
  for (const auto& [group, cost] : group_cost) largest = std::max(largest, cost);
  const double mean = count ? static_cast<double>(total) / count : 0.0;
  std::string s = fmt::format("{} cells in {} shards; estimated cost (rays x tree depth x encoder weight):\n",
                              planned.size(), count);
  s += fmt::format("{:>7} {:>6} {:>16} {:>8}\n", "shard", "cells", "est. cost", "vs mean");
  std::uint64_t most = 0;
  for (unsigned i = 0; i < count; ++i) {
    most = std::max(most, loads[i].cost);
    s += fmt::format("{:>7} {:>6} {:>16} {:>7.3f}x\n", fmt::format("{}/{}", i + 1, count), loads[i].cells,
                     loads[i].cost, mean > 0 ? static_cast<double>(loads[i].cost) / mean : 0.0);
  }
  s += fmt::format("most loaded shard: {:.3f}x the mean (bound: mean + largest round group = {:.3f}x)\n\n",
                   mean > 0 ? static_cast<double>(most) / mean : 0.0,
                   mean > 0 ? (mean + static_cast<double>(largest)) / mean : 0.0);
  s += fmt::format("{:>7} {:>16}  {}\n", "shard", "est. cost", "cell");
  for (const auto& c : planned) s += fmt::format("{:>7} {:>16}  {}\n", c.shard, c.cost, c.id);
  return s;
}

}  // namespace raysort
