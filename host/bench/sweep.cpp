#include "bench/sweep.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "bench/matrix.h"
#include "bench/result_set.h"
#include "encode/encoder_params.h"
#include "util/error.h"

namespace raysort {

namespace {

// The encoder knobs a sweep may vary (encode/encoder_params.h), as meta.json's matrix names them.
bool sweepable(const std::string& key) {
  const auto& rows = encoder_params();
  return std::any_of(rows.begin(), rows.end(), [&](const EncoderParam& row) { return row.key == key; });
}

// "--lambda, --twopoint-length, ... or --cost-bits"; "had_lambda, twopoint_length_fraction, ...".
std::string param_list(bool flags) {
  std::string out;
  const auto& rows = encoder_params();
  for (std::size_t i = 0; i < rows.size(); ++i)
    out += fmt::format("{}{}", i == 0 ? "" : i + 1 == rows.size() && flags ? " or " : ", ",
                       flags ? rows[i].flag : rows[i].key);
  return out;
}

}  // namespace

Sweep load_sweep(const std::vector<std::string>& dirs) {
  if (dirs.size() < 2) throw Error("a sweep needs two or more result sets (one per parameter value)");
  std::vector<nlohmann::json> matrices;
  Sweep sweep;
  for (const auto& dir : dirs) {
    ResultSet rs = ResultSet::load(dir);
    if (!rs.meta().contains("matrix")) throw Error(fmt::format("{}: meta.json has no matrix", dir));
    // Its entries are read below as numbers; a null (a non-finite value written by an older raysort)
    // or a string is named here instead of ending in a JSON type error.
    check_matrix_json(rs.meta()["matrix"], dir + "/meta.json");
    matrices.push_back(rs.meta()["matrix"]);
    sweep.points.push_back({dir, 0.0, rs.cells()});
  }
  // Which matrix entries differ between the sets.
  std::set<std::string> differing;
  for (std::size_t i = 1; i < matrices.size(); ++i) {
    for (auto& [key, value] : matrices[0].items())
      if (!matrices[i].contains(key) || matrices[i][key] != value) differing.insert(key);
    for (auto& [key, value] : matrices[i].items())
      if (!matrices[0].contains(key)) differing.insert(key);
  }
  std::set<std::string> swept, other;
  for (const auto& key : differing)
    (sweepable(key) ? swept : other).insert(key);
  if (!other.empty())
    throw Error(fmt::format("{}: the sets differ in {} as well, so their columns are not comparable; run them with one "
                            "command that changes only {}",
                            fmt::join(dirs, ", "), fmt::join(other, ", "), param_list(true)));
  if (swept.size() != 1)
    throw Error(fmt::format("{}: {}; a sweep varies exactly one of {}", fmt::join(dirs, ", "),
                            swept.empty() ? "the sets ran the same matrix" : fmt::format("the sets differ in {}", fmt::join(swept, " and ")),
                            param_list(false)));
  sweep.parameter = *swept.begin();
  std::set<double> seen;
  for (std::size_t i = 0; i < matrices.size(); ++i) {
    sweep.points[i].value = matrices[i].at(sweep.parameter).get<double>();
    if (!seen.insert(sweep.points[i].value).second)
      throw Error(fmt::format("{}: {} = {} is in two sets; give each value once", sweep.points[i].dir, sweep.parameter,
                              sweep.points[i].value));
  }
  std::sort(sweep.points.begin(), sweep.points.end(), [](const SweepPoint& a, const SweepPoint& b) { return a.value < b.value; });
  return sweep;
}

std::string render_sweep(const Sweep& sweep) {
  // Rows: (batch, encoder, bits, access) groups with their scenes, in first-seen order.
  struct Key {
    std::string batch, encoder, access;
    unsigned bits;
    bool operator<(const Key& o) const {
      return std::tie(batch, encoder, bits, access) < std::tie(o.batch, o.encoder, o.bits, o.access);
    }
  };
  std::map<Key, std::vector<std::string>> groups;
  std::map<std::tuple<std::string, std::string, std::string, unsigned, std::string>, std::map<double, const CellRecord*>> at;
  for (const auto& p : sweep.points)
    for (const auto& c : p.cells) {
      if (c.encoder == kBaselineEncoder || c.top_bits != 0 || c.baseline != "pixel") continue;
      auto& scenes = groups[{c.batch, c.encoder, c.access, c.bits}];
      if (std::find(scenes.begin(), scenes.end(), c.scene) == scenes.end()) scenes.push_back(c.scene);
      at[{c.scene, c.batch, c.encoder, c.bits, c.access}][p.value] = &c;
    }
  std::string md = fmt::format("# Sweep of {}\n\nSets: {}.\n\nEach cell: SIMT lane-efficiency ratio vs NoSort "
                               "(deterministic; **bold**: the row's best) · PoCL speedup.\n\n",
                               encoder_param(sweep.parameter).label,
                               fmt::join([&] {
                                 std::vector<std::string> v;
                                 for (auto& p : sweep.points) v.push_back(fmt::format("`{}` ({:g})", p.dir, p.value));
                                 return v;
                               }(), ", "));
  for (const auto& [key, scenes] : groups) {
    md += fmt::format("## {} {}-bit, {} rays, access {}\n\n| scene |", key.encoder, key.bits, key.batch, key.access);
    std::string sep = "|---|";
    for (auto& p : sweep.points) md += fmt::format(" {:g} |", p.value), sep += "---:|";
    md += "\n" + sep + "\n";
    std::map<double, std::pair<double, int>> sums;
    for (const auto& scene : scenes) {
      const auto& row = at[{scene, key.batch, key.encoder, key.bits, key.access}];
      double best = -1;
      for (auto& [v, c] : row)
        if (c->ok()) best = std::max(best, c->simt_lane_efficiency_ratio);
      md += fmt::format("| {} |", scene);
      for (auto& p : sweep.points) {
        auto it = row.find(p.value);
        if (it == row.end() || !it->second->ok()) {
          md += " – |";
          continue;
        }
        const CellRecord& c = *it->second;
        const std::string ratio = fmt::format("{:.3f}", c.simt_lane_efficiency_ratio);
        md += fmt::format(" {} · {} |", c.simt_lane_efficiency_ratio == best ? "**" + ratio + "**" : ratio,
                          c.speedup.has_value() ? fmt::format("{:.2f}", c.speedup.value) : "–");
        sums[p.value].first += c.simt_lane_efficiency_ratio;
        sums[p.value].second += 1;
      }
      md += "\n";
    }
    md += "| mean lane ratio |";
    for (auto& p : sweep.points)
      md += sums.count(p.value) ? fmt::format(" {:.3f} |", sums[p.value].first / sums[p.value].second) : " – |";
    md += "\n\n";
  }
  return md;
}

}  // namespace raysort
