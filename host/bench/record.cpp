#include "bench/record.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "bench/record_columns.h"
#include "embree/embree_reference.h"  // kEmbreePaths only (a table, no Embree call): every build has it

namespace raysort {

namespace {

std::string cell_id(const CellRecord& c, bool with_class) {
  std::string s = fmt::format("{}/{}/{}/{}", c.scene, c.batch, c.encoder, c.bits);
  if (c.top_bits) s += fmt::format("/top{}", c.top_bits);
  if (c.variant != "robust") s += "/" + c.variant;
  if (with_class && c.layout != "wide") s += "/" + c.layout;
  if (c.access != "gather") s += "/" + c.access;
  if (c.baseline != "pixel") s += "/" + c.baseline;
  return s;
}

}  // namespace

std::string CellRecord::id() const { return cell_id(*this, true); }

const CellRecord::EmbreeFigures* CellRecord::embree_path(const std::string& key) const {
  for (const EmbreeFigures& e : embree)
    if (e.path == key) return &e;
  return nullptr;
}

std::string CellRecord::id_before_class_axis() const { return cell_id(*this, false); }

namespace {

// What an "ok" cell must be to be reported: its hits checked, its intervals around their values,
// its ratios above 0, and its estimates the ones its own samples give (an edited figure shows).
std::string ok_cell_problem(const CellRecord& r) {
  if (!r.order_is_permutation) return "it is \"ok\" but its order is not a permutation (order_is_permutation false)";
  if (!r.hits_match_nosort) return "it is \"ok\" but its hits differ from NoSort's (hits_match_nosort false)";
  const std::pair<const char*, const Estimate*> estimates[] = {
      {"speedup", &r.speedup}, {"net_speedup", &r.net_speedup}, {"aa", &r.aa}, {"overhead_pct", &r.overhead_pct}};
  for (const auto& [name, e] : estimates) {
    if (std::isnan(e->value)) continue;  // not measured (a version 1 record)
    if (std::string(name) != "overhead_pct" && !(e->value > 0))
      return fmt::format("{} is {}; a ratio of two times is more than 0", name, e->value);
    if (e->has_interval() && !(e->lo <= e->value && e->value <= e->hi))
      return fmt::format("{} {} lies outside its interval [{}, {}]", name, e->value, e->lo, e->hi);
  }
  // The paired estimates again from the samples (bench/protocol.h), as the run computed them.
  auto agrees = [](const Estimate& recorded, const Estimate& again) {
    auto same = [](double a, double b) {
      return (std::isnan(a) && std::isnan(b)) || std::abs(a - b) <= 1e-9 * std::max(std::abs(a), std::abs(b));
    };
    return same(recorded.value, again.value) && same(recorded.lo, again.lo) && same(recorded.hi, again.hi);
  };
  const auto nosort = r.samples.find("nosort"), aa = r.samples.find("aa"), trace = r.samples.find("trace");
  if (nosort == r.samples.end()) return "";  // a record without samples (version 1)
  for (const auto& [stage, series] : r.samples)
    if (series.size() != nosort->second.size())
      return fmt::format("its samples hold {} \"{}\" rounds but {} \"nosort\" ones", series.size(), stage,
                         nosort->second.size());
  if (aa != r.samples.end() && !agrees(r.aa, ratio_interval(nosort->second, aa->second)))
    return "its aa figure is not the one its nosort and aa samples give (an edited record)";
  if (trace != r.samples.end() && !r.same_order_as_nosort && r.encoder != kBaselineEncoder &&
      !agrees(r.speedup, ratio_interval(nosort->second, trace->second)))
    return "its speedup is not the one its nosort and trace samples give (an edited record)";
  for (const auto& e : r.embree) {
    const std::string what = "Embree path " + e.path;
    if (e.trace.n == 0) continue;  // a NoSort cell: no sorted arm
    if (e.differ > 0)
      return fmt::format("it is \"ok\" but {} rays of {}'s sorted-order trace differ from its NoSort-order trace "
                         "beyond ties", e.differ, what);
    if (!(e.speedup.value > 0)) return fmt::format("{}'s speedup is {}; a ratio of two times is more than 0", what, e.speedup.value);
    if (e.speedup.has_interval() && !(e.speedup.lo <= e.speedup.value && e.speedup.value <= e.speedup.hi))
      return fmt::format("{}'s speedup {} lies outside its interval [{}, {}]", what, e.speedup.value, e.speedup.lo,
                         e.speedup.hi);
    const auto en = r.samples.find("embree:" + e.path + ":nosort"), et = r.samples.find("embree:" + e.path + ":trace");
    if (en == r.samples.end() || et == r.samples.end())
      return fmt::format("its samples lack {}'s arms (\"embree:{}:nosort\", \"embree:{}:trace\")", what, e.path, e.path);
    if (!r.same_order_as_nosort && !agrees(e.speedup, ratio_interval(en->second, et->second)))
      return fmt::format("{}'s speedup is not the one its samples give (an edited record)", what);
  }
  return "";
}

}  // namespace

std::string cell_record_problem(const CellRecord& r) {
  std::vector<std::string> paths;
  for (const auto& e : r.embree) {
    if (std::none_of(std::begin(kEmbreePaths), std::end(kEmbreePaths), [&](const EmbreePathInfo& info) { return e.path == info.key; }))
      return fmt::format("Embree path \"{}\" is not one raysort knows (--embree-paths)", e.path);
    if (std::find(paths.begin(), paths.end(), e.path) != paths.end())
      return fmt::format("Embree path {} is recorded twice", e.path);
    paths.push_back(e.path);
  }
  for (const auto& c : cell_columns_for({r})) {
    if (c.kind == CellColumn::Text && !c.vocabulary.empty() &&
        std::find(c.vocabulary.begin(), c.vocabulary.end(), c.csv(r)) == c.vocabulary.end()) {
      std::string known;
      for (const auto& v : c.vocabulary) known += (known.empty() ? "" : ", ") + (v.empty() ? "\"\"" : v);
      return fmt::format("{} \"{}\" is not one of {}", c.name, c.csv(r), known);
    }
    if (c.kind == CellColumn::Number) {
      const double x = c.value(r);
      // No interval (NaN) is a valid state of the _lo/_hi columns, of noise and of a v1 speedup.
      if (std::isinf(x) || x < 0) return fmt::format("{} is {}; it must be a finite number, 0 or more", c.name, x);
    }
  }
  return r.ok() ? ok_cell_problem(r) : "";
}

}  // namespace raysort
