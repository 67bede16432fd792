#include "bench/shard.h"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <map>
#include <numeric>
#include <regex>
#include <set>

#include "bench/record.h"
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

SceneFacts load_scene_facts(const std::string& scene, const MatrixSpec& spec, const std::string& scene_root) {
  SceneOptions opts;
  opts.scene_root = scene_root;
  opts.width = opts.height = 1;  // the camera's resolution does not change the geometry or effects
  Scene s = load_scene(scene, opts);
  std::uint32_t w = 0, h = 0;
  parse_resolution(spec.resolution, w, h);
  SceneFacts f;
  f.triangles = s.triangle_count();
  f.rays_per_batch = std::uint64_t{w} * h * spec.spp;
  f.shadow_rays_per_bounce = s.sphere_lights.empty() ? 0 : s.effects.shadow_rays_per_bounce;
  f.max_bounces = s.effects.max_bounces;
  return f;
}

namespace {

// Encode + sort on top of the trace, in percent of one trace (see matrix_cells in shard.h).
std::uint64_t encoder_weight_pct(const std::string& encoder) {
  const auto e = parse_encoder(encoder);
  return e ? encoder_info(*e).cost_weight_pct : 130;
}

// The batches render/batches.cpp generate_batches can produce for these effects, in its order:
// primary, then per bounce depth k its shadow rays and bounce k+1.
std::vector<std::string> possible_batches(const SceneFacts& f) {
  std::vector<std::string> out{"primary"};
  for (std::uint32_t k = 0;; ++k) {
    if (f.shadow_rays_per_bounce > 0) out.push_back(fmt::format("shadow{}", k));
    if (k >= f.max_bounces) break;
    out.push_back(fmt::format("bounce{}", k + 1));
  }
  return out;
}

}  // namespace

std::vector<PlannedCell> matrix_cells(const MatrixSpec& spec,
                                      const std::function<SceneFacts(const std::string&)>& facts) {
  // The encoders the runner visits: the spec's order, NoSort apart (it is every batch's baseline).
  std::vector<std::string> encoders;
  for (const auto& n : spec.encoders)
    if (auto e = parse_encoder(n); e && *e != Encoder::NoSort) {
      std::string name(encoder_name(*e));
      if (std::find(encoders.begin(), encoders.end(), name) == encoders.end()) encoders.push_back(name);
    }
  std::vector<PlannedCell> out;
  std::set<std::string> seen;
  for (const auto& scene : spec.scenes) {
    const SceneFacts f = facts(scene);
    const std::vector<std::string> possible = possible_batches(f);
    std::vector<std::string> batches;
    for (const auto& b : spec.batches.empty() ? possible : spec.batches)
      if (std::find(possible.begin(), possible.end(), b) != possible.end()) batches.push_back(b);
    const std::uint64_t depth = std::max<std::uint64_t>(1, std::bit_width(f.triangles));
    for (const auto& batch : batches) {
      const std::uint64_t rays = batch.rfind("shadow", 0) == 0 ? f.rays_per_batch * f.shadow_rays_per_bounce
                                                               : f.rays_per_batch;
      for (const auto& variant : spec.variant_list()) {
        auto add = [&](const std::string& encoder, unsigned bits, unsigned top, const std::string& access) {
          CellRecord c;
          c.scene = scene, c.batch = batch, c.encoder = encoder, c.bits = bits, c.top_bits = top, c.variant = variant;
          c.access = access;
          if (!seen.insert(c.id()).second) return;  // a scene named twice runs once
          out.push_back({c.id(), scene, batch, variant, rays * depth * encoder_weight_pct(encoder), 0, encoder, access,
                         bits, top});
        };
        add(kBaselineEncoder, 0, 0, "gather");  // the identity order: no access mode to choose
        const std::vector<unsigned> bits = spec.bits_for(scene);
        for (const auto& e : encoders) {
          for (unsigned b : bits)
            for (const auto& a : spec.access_list()) add(e, b, 0, a);
          for (unsigned k : spec.top_bits)
            for (const auto& a : spec.access_list()) add(e, bits.back(), k, a);
        }
      }
    }
  }
  return out;
}

std::vector<PlannedCell> plan_shards(std::vector<PlannedCell> cells, unsigned count) {
  if (count == 0) throw Error("plan_shards: the number of shards must be at least 1");
  std::vector<std::size_t> order(cells.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (cells[a].cost != cells[b].cost) return cells[a].cost > cells[b].cost;
    return cells[a].id < cells[b].id;
  });
  std::vector<std::uint64_t> load(count, 0);
  for (std::size_t i : order) {
    std::size_t least = std::min_element(load.begin(), load.end()) - load.begin();  // first minimum
    load[least] += cells[i].cost;
    cells[i].shard = static_cast<unsigned>(least + 1);
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
  for (const auto& c : planned) total += c.cost, largest = std::max(largest, c.cost);
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
  s += fmt::format("most loaded shard: {:.3f}x the mean (bound: mean + largest cell = {:.3f}x)\n\n",
                   mean > 0 ? static_cast<double>(most) / mean : 0.0,
                   mean > 0 ? (mean + static_cast<double>(largest)) / mean : 0.0);
  s += fmt::format("{:>7} {:>16}  {}\n", "shard", "est. cost", "cell");
  for (const auto& c : planned) s += fmt::format("{:>7} {:>16}  {}\n", c.shard, c.cost, c.id);
  return s;
}

}  // namespace raysort
