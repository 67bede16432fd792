#include "bench/record.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "embree/embree_reference.h"  // kEmbreePaths only (a table, no Embree call): every build has it
#include "trace/trace_class.h"

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

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A count (key bits, rays, rounds): a non-negative integer in JSON, never a float cast into one.
template <class T>
void count_from(const nlohmann::json& j, const char* key, T& out) {
  const nlohmann::json& v = j.at(key);
  if (!v.is_number_unsigned() || v.get<std::uint64_t>() > std::numeric_limits<T>::max())
    throw std::runtime_error(fmt::format("\"{}\" is {}, not a count", key, v.dump()));
  out = v.get<T>();
}
// A number that may be NaN (no interval): JSON null.
nlohmann::json number(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr); }
double number_from(const nlohmann::json& j) { return j.is_null() ? kNaN : j.get<double>(); }

nlohmann::json estimate_json(const Estimate& e) {
  return {{"value", number(e.value)}, {"lo", number(e.lo)}, {"hi", number(e.hi)}, {"n", e.n}};
}
Estimate estimate_from(const nlohmann::json& j) {
  // Format version 1 stored a point figure.
  if (j.is_number()) return {j.get<double>(), kNaN, kNaN, 0};
  Estimate e{number_from(j.at("value")), number_from(j.at("lo")), number_from(j.at("hi")), 0};
  count_from(j, "n", e.n);
  return e;
}

void timing_to_json(nlohmann::json& j, const char* name, const Timing& t) {
  j[std::string(name) + "_ms"] = {{"median", t.median_ms}, {"lo", number(t.lo_ms)}, {"hi", number(t.hi_ms)},
                                  {"min", t.min_ms},       {"max", t.max_ms},       {"n", t.n}};
}
void timing_from_json(const nlohmann::json& j, const char* name, Timing& t) {
  const std::string key = std::string(name) + "_ms";
  if (!j.contains(key)) return;  // version 1 has no permute or nosort_trace timing
  const auto& o = j.at(key);
  t.median_ms = o.at("median").get<double>();
  t.min_ms = o.at("min").get<double>();
  t.max_ms = o.at("max").get<double>();
  t.lo_ms = o.contains("lo") ? number_from(o.at("lo")) : kNaN;
  t.hi_ms = o.contains("hi") ? number_from(o.at("hi")) : kNaN;
  if (o.contains("n")) count_from(o, "n", t.n);
}

// The GPU model's figures: one object, present only when the model ran.
nlohmann::json gpu_model_json(const CellRecord::GpuModelFigures& g) {
  return {{"profile", g.profile},       {"time_us", number(g.time_us)},   {"speedup", number(g.speedup)},
          {"warp_steps", g.warp_steps}, {"idle_lanes", g.idle_lanes},     {"l1_hits", g.l1_hits},
          {"l1_misses", g.l1_misses},   {"l2_hits", g.l2_hits},           {"l2_misses", g.l2_misses},
          {"dram_bytes", g.dram_bytes}, {"warps", g.warps},               {"replayed_warps", g.replayed_warps},
          {"steps_l2", g.steps_l2},     {"steps_dram", g.steps_dram},     {"ww_steps", g.ww_steps}};
}
void gpu_model_from_json(const nlohmann::json& j, CellRecord::GpuModelFigures& g) {
  j.at("profile").get_to(g.profile);
  g.time_us = number_from(j.at("time_us"));
  g.speedup = number_from(j.at("speedup"));
  for (auto [key, field] : {std::pair<const char*, std::uint64_t*>{"warp_steps", &g.warp_steps},
                            {"idle_lanes", &g.idle_lanes}, {"l1_hits", &g.l1_hits}, {"l1_misses", &g.l1_misses},
                            {"l2_hits", &g.l2_hits}, {"l2_misses", &g.l2_misses}, {"dram_bytes", &g.dram_bytes},
                            {"warps", &g.warps}, {"replayed_warps", &g.replayed_warps}})
    count_from(j, key, *field);
  // Added later within format version 3: absent in older records.
  if (j.contains("steps_l2")) count_from(j, "steps_l2", g.steps_l2);
  if (j.contains("steps_dram")) count_from(j, "steps_dram", g.steps_dram);
  if (j.contains("ww_steps")) count_from(j, "ww_steps", g.ww_steps);
}

// MRays/s of `rays` at a median time (NaN without one).
double mrays_at(std::uint64_t rays, const Timing& t) {
  return t.n > 0 && t.median_ms > 0 ? static_cast<double>(rays) / (t.median_ms * 1e3) : kNaN;
}

// One Embree path's figures. The MRays/s are written for a reader of the file and computed again
// from rays and the median when read (one truth); the sorted arm's figures only in a sorted cell.
nlohmann::json embree_json(const CellRecord::EmbreeFigures& e, std::uint64_t rays) {
  nlohmann::json j = {{"path", e.path}, {"call", e.call}, {"threads", e.threads}};
  timing_to_json(j, "nosort", e.nosort);
  j["nosort_mrays"] = number(mrays_at(rays, e.nosort));
  if (e.trace.n > 0) {
    timing_to_json(j, "trace", e.trace);
    j["trace_mrays"] = number(mrays_at(rays, e.trace));
    j["speedup"] = estimate_json(e.speedup);
    j["ties"] = e.ties;
    j["differ"] = e.differ;
  }
  j["agreement_with_ours"] = number(e.agreement_with_ours);
  return j;
}
CellRecord::EmbreeFigures embree_from_json(const nlohmann::json& j) {
  CellRecord::EmbreeFigures e;
  j.at("path").get_to(e.path);
  j.at("call").get_to(e.call);
  count_from(j, "threads", e.threads);
  if (!j.contains("nosort_ms")) throw std::runtime_error(fmt::format("Embree path {} has no \"nosort_ms\"", e.path));
  timing_from_json(j, "nosort", e.nosort);
  if (j.contains("trace_ms")) {
    timing_from_json(j, "trace", e.trace);
    e.speedup = estimate_from(j.at("speedup"));
    count_from(j, "ties", e.ties);
    count_from(j, "differ", e.differ);
  }
  e.agreement_with_ours = number_from(j.at("agreement_with_ours"));
  return e;
}

}  // namespace

void to_json(nlohmann::json& j, const CellRecord& r) {
  j = nlohmann::json{{"format_version", kResultFormatVersion},
                     {"id", r.id()},
                     {"scene", r.scene},
                     {"batch", r.batch},
                     {"encoder", r.encoder},
                     {"bits", r.bits},
                     {"top_bits", r.top_bits},
                     {"variant", r.variant},
                     {"access", r.access},
                     {"baseline", r.baseline},
                     {"layout", r.layout},
                     {"rays", r.rays},
                     {"status", r.status},
                     {"error", r.error},
                     {"trace_mrays", r.trace_mrays},
                     {"speedup", estimate_json(r.speedup)},
                     {"net_speedup", estimate_json(r.net_speedup)},
                     {"overhead_pct", estimate_json(r.overhead_pct)},
                     {"aa", estimate_json(r.aa)},
                     {"same_order_as_nosort", r.same_order_as_nosort},
                     {"rounds", r.rounds},
                     {"stopped_by", r.stopped_by},
                     {"noise", number(r.noise)},
                     {"samples", r.samples},
                     {"anc", number(r.anc)},
                     {"simt_lane_efficiency", r.simt_lane_efficiency},
                     {"simt_distinct_per_visit", r.simt_distinct_per_visit},
                     {"simt_lane_efficiency_ratio", r.simt_lane_efficiency_ratio},
                     {"simt_distinct_per_visit_ratio", r.simt_distinct_per_visit_ratio},
                     {"hits_match_nosort", r.hits_match_nosort},
                     {"order_is_permutation", r.order_is_permutation},
                     {"keys_hash", r.keys_hash},
                     {"order_hash", r.order_hash},
                     {"leaks_per_million", r.leaks_per_million}};
  if (!r.gpu.profile.empty()) j["gpu_model"] = gpu_model_json(r.gpu);
  if (r.cut_ms >= 0) j["cut_ms"] = r.cut_ms;  // the encoders with per-batch input (added within format version 3)
  if (!r.embree.empty()) {  // run --embree-paths (added within format version 3)
    nlohmann::json& paths = j["embree"] = nlohmann::json::array();
    for (const auto& e : r.embree) paths.push_back(embree_json(e, r.rays));
  }
  timing_to_json(j, "encode", r.encode);
  timing_to_json(j, "sort", r.sort);
  timing_to_json(j, "permute", r.permute);
  timing_to_json(j, "trace", r.trace);
  timing_to_json(j, "nosort_trace", r.nosort_trace);
}

void from_json(const nlohmann::json& j, CellRecord& r) {
  // Read as a count, never as a float cast to int (fuzz/result_set_fuzzer: 7.8e50 was undefined).
  std::uint64_t version = 0;
  if (j.contains("format_version")) count_from(j, "format_version", version);
  if (version < kOldestReadableFormatVersion || version > kResultFormatVersion)
    throw std::runtime_error(fmt::format("cell record has format version {}, this raysort reads versions {} to {}",
                                         version, kOldestReadableFormatVersion, kResultFormatVersion));
  j.at("scene").get_to(r.scene);
  j.at("batch").get_to(r.batch);
  j.at("encoder").get_to(r.encoder);
  count_from(j, "bits", r.bits);
  count_from(j, "top_bits", r.top_bits);
  j.at("variant").get_to(r.variant);
  j.at("access").get_to(r.access);
  if (version >= 3) {
    j.at("baseline").get_to(r.baseline);
    j.at("layout").get_to(r.layout);
  }
  count_from(j, "rays", r.rays);
  j.at("status").get_to(r.status);
  j.at("error").get_to(r.error);
  j.at("trace_mrays").get_to(r.trace_mrays);
  r.speedup = estimate_from(j.at("speedup"));
  r.net_speedup = estimate_from(j.at("net_speedup"));
  r.overhead_pct = estimate_from(j.at("overhead_pct"));
  if (version >= 2) {
    r.aa = estimate_from(j.at("aa"));
    j.at("same_order_as_nosort").get_to(r.same_order_as_nosort);
    count_from(j, "rounds", r.rounds);
    j.at("stopped_by").get_to(r.stopped_by);
    r.noise = number_from(j.at("noise"));
    j.at("samples").get_to(r.samples);
  }
  r.anc = number_from(j.at("anc"));
  if (r.encoder == kBaselineEncoder && r.anc == 0.0) r.anc = kNaN;  // older sets stored 0: NoSort has no keys
  j.at("simt_lane_efficiency").get_to(r.simt_lane_efficiency);
  j.at("simt_distinct_per_visit").get_to(r.simt_distinct_per_visit);
  j.at("simt_lane_efficiency_ratio").get_to(r.simt_lane_efficiency_ratio);
  j.at("simt_distinct_per_visit_ratio").get_to(r.simt_distinct_per_visit_ratio);
  j.at("hits_match_nosort").get_to(r.hits_match_nosort);
  j.at("order_is_permutation").get_to(r.order_is_permutation);
  j.at("keys_hash").get_to(r.keys_hash);
  j.at("order_hash").get_to(r.order_hash);
  r.leaks_per_million = j.value("leaks_per_million", -1.0);  // added within format version 1
  if (j.contains("gpu_model")) gpu_model_from_json(j.at("gpu_model"), r.gpu);  // added within format version 3
  if (j.contains("cut_ms")) r.cut_ms = number_from(j.at("cut_ms"));
  if (j.contains("embree")) {  // run --embree-paths (added within format version 3); absent: none
    if (!j.at("embree").is_array()) throw std::runtime_error("\"embree\" is not a list of Embree paths");
    for (const auto& e : j.at("embree")) r.embree.push_back(embree_from_json(e));
  }
  timing_from_json(j, "encode", r.encode);
  timing_from_json(j, "sort", r.sort);
  timing_from_json(j, "permute", r.permute);
  timing_from_json(j, "trace", r.trace);
  timing_from_json(j, "nosort_trace", r.nosort_trace);
}

namespace {

// An empty CSV field for a missing figure (no interval).
std::string csv_number(double x, int decimals) { return std::isfinite(x) ? fmt::format("{:.{}f}", x, decimals) : ""; }

using Col = CellColumn;
using Text = std::function<std::string(const CellRecord&)>;
using Value = std::function<double(const CellRecord&)>;

Col text(std::string name, Text f, std::vector<std::string> vocabulary = {}) {
  return {std::move(name), Col::Text, std::move(f), nullptr, std::move(vocabulary)};
}
Col flag(std::string name, bool CellRecord::*member) {
  return text(std::move(name), [member](const CellRecord& r) { return std::string(r.*member ? "true" : "false"); },
              {"true", "false"});
}
// A number printed with `decimals` (fixed) or, with decimals < 0, as an integer.
Col numeric(std::string name, Value f, int decimals) {
  Text csv = [f, decimals](const CellRecord& r) {
    const double x = f(r);
    return decimals < 0 ? fmt::format("{}", static_cast<std::uint64_t>(x)) : csv_number(x, decimals);
  };
  return {std::move(name), Col::Number, std::move(csv), std::move(f), {}};
}

void add_timing(std::vector<Col>& cols, const std::string& stage, Timing CellRecord::*t) {
  cols.push_back(numeric(stage + "_ms", [t](const CellRecord& r) { return (r.*t).median_ms; }, 4));
  cols.push_back(numeric(stage + "_lo_ms", [t](const CellRecord& r) { return (r.*t).lo_ms; }, 4));
  cols.push_back(numeric(stage + "_hi_ms", [t](const CellRecord& r) { return (r.*t).hi_ms; }, 4));
  cols.push_back(numeric(stage + "_min_ms", [t](const CellRecord& r) { return (r.*t).min_ms; }, 4));
  cols.push_back(numeric(stage + "_max_ms", [t](const CellRecord& r) { return (r.*t).max_ms; }, 4));
}
void add_estimate(std::vector<Col>& cols, const std::string& name, Estimate CellRecord::*e, int decimals) {
  cols.push_back(numeric(name, [e](const CellRecord& r) { return (r.*e).value; }, decimals));
  cols.push_back(numeric(name + "_lo", [e](const CellRecord& r) { return (r.*e).lo; }, decimals));
  cols.push_back(numeric(name + "_hi", [e](const CellRecord& r) { return (r.*e).hi; }, decimals));
}

// The GPU model's columns (empty fields when the model was off).
void add_gpu_model_columns(std::vector<Col>& c) {
  c.push_back(text("gpu_model", [](const CellRecord& r) { return r.gpu.profile; }));
  c.push_back(numeric("gpu_model_speedup", [](const CellRecord& r) { return r.gpu.speedup; }, 4));
  c.push_back(numeric("gpu_model_time_us", [](const CellRecord& r) { return r.gpu.time_us; }, 3));
  using Count = std::uint64_t CellRecord::GpuModelFigures::*;
  // A plain pair, not a structured binding: clang 14 (make fuzz) cannot capture a binding in a lambda.
  for (const std::pair<const char*, Count>& column :
       {std::pair<const char*, Count>{"gpu_warp_steps", &CellRecord::GpuModelFigures::warp_steps},
        {"gpu_idle_lanes", &CellRecord::GpuModelFigures::idle_lanes},
        {"gpu_l1_hits", &CellRecord::GpuModelFigures::l1_hits},
        {"gpu_l1_misses", &CellRecord::GpuModelFigures::l1_misses},
        {"gpu_l2_hits", &CellRecord::GpuModelFigures::l2_hits},
        {"gpu_l2_misses", &CellRecord::GpuModelFigures::l2_misses},
        {"gpu_dram_bytes", &CellRecord::GpuModelFigures::dram_bytes},
        {"gpu_replayed_warps", &CellRecord::GpuModelFigures::replayed_warps},
        {"gpu_steps_l2", &CellRecord::GpuModelFigures::steps_l2},
        {"gpu_steps_dram", &CellRecord::GpuModelFigures::steps_dram},
        {"gpu_ww_steps", &CellRecord::GpuModelFigures::ww_steps}}) {
    const Count field = column.second;
    c.push_back(numeric(
        column.first,
        [field](const CellRecord& r) {
          return r.gpu.profile.empty() ? std::numeric_limits<double>::quiet_NaN() : static_cast<double>(r.gpu.*field);
        },
        0));
  }
}

// An Embree path's figure of a cell, NaN when the cell lacks the path (or the figure).
using EmbreeValue = std::function<double(const CellRecord&, const CellRecord::EmbreeFigures&)>;
Col embree_numeric(const std::string& path, const std::string& name, EmbreeValue f, int decimals) {
  return numeric(
      "embree_" + path + "_" + name,
      [path, f](const CellRecord& r) {
        const CellRecord::EmbreeFigures* e = r.embree_path(path);
        return e ? f(r, *e) : kNaN;
      },
      decimals);
}

std::vector<Col> make_columns() {
  std::vector<Col> c;
  c.push_back(text("id", [](const CellRecord& r) { return r.id(); }));
  c.push_back(text("scene", [](const CellRecord& r) { return r.scene; }));
  c.push_back(text("batch", [](const CellRecord& r) { return r.batch; }));
  c.push_back(text("encoder", [](const CellRecord& r) { return r.encoder; }));
  c.push_back(numeric("bits", [](const CellRecord& r) { return r.bits; }, -1));
  c.push_back(numeric("top_bits", [](const CellRecord& r) { return r.top_bits; }, -1));
  c.push_back(text("variant", [](const CellRecord& r) { return r.variant; }, {"robust", "fast"}));
  c.push_back(text("access", [](const CellRecord& r) { return r.access; }, {"gather", "permute"}));
  c.push_back(text("baseline", [](const CellRecord& r) { return r.baseline; }, {"pixel", "shuffled"}));
  c.push_back(text("layout", [](const CellRecord& r) { return r.layout; }, trace_layout_names()));
  c.push_back(numeric("rays", [](const CellRecord& r) { return static_cast<double>(r.rays); }, -1));
  c.push_back(text("status", [](const CellRecord& r) { return r.status; }, cell_statuses()));
  add_timing(c, "encode", &CellRecord::encode);
  add_timing(c, "sort", &CellRecord::sort);
  add_timing(c, "permute", &CellRecord::permute);
  add_timing(c, "trace", &CellRecord::trace);
  add_timing(c, "nosort_trace", &CellRecord::nosort_trace);
  // hcc-traffic's per-batch cut (host ms); empty for other cells.
  c.push_back(numeric("cut_ms", [](const CellRecord& r) { return r.cut_ms >= 0 ? r.cut_ms : kNaN; }, 3));
  c.push_back(numeric("trace_mrays", [](const CellRecord& r) { return r.trace_mrays; }, 4));
  add_estimate(c, "speedup", &CellRecord::speedup, 4);
  add_estimate(c, "net_speedup", &CellRecord::net_speedup, 4);
  add_estimate(c, "overhead_pct", &CellRecord::overhead_pct, 3);
  add_estimate(c, "aa", &CellRecord::aa, 4);
  c.push_back(flag("same_order_as_nosort", &CellRecord::same_order_as_nosort));
  c.push_back(numeric("rounds", [](const CellRecord& r) { return r.rounds; }, -1));
  c.push_back(text("stopped_by", [](const CellRecord& r) { return r.stopped_by; }, {"noise", "time", "rounds", ""}));
  c.push_back(numeric("noise", [](const CellRecord& r) { return r.noise; }, 5));
  c.push_back(numeric("anc", [](const CellRecord& r) { return r.anc; }, 4));
  c.push_back(numeric("simt_lane_efficiency", [](const CellRecord& r) { return r.simt_lane_efficiency; }, 6));
  c.push_back(numeric("simt_distinct_per_visit", [](const CellRecord& r) { return r.simt_distinct_per_visit; }, 6));
  c.push_back(numeric("simt_lane_efficiency_ratio", [](const CellRecord& r) { return r.simt_lane_efficiency_ratio; }, 6));
  c.push_back(
      numeric("simt_distinct_per_visit_ratio", [](const CellRecord& r) { return r.simt_distinct_per_visit_ratio; }, 6));
  add_gpu_model_columns(c);
  c.push_back(flag("hits_match_nosort", &CellRecord::hits_match_nosort));
  c.push_back(flag("order_is_permutation", &CellRecord::order_is_permutation));
  c.push_back(text("keys_hash", [](const CellRecord& r) { return r.keys_hash; }));
  c.push_back(text("order_hash", [](const CellRecord& r) { return r.order_hash; }));
  c.push_back(text("error", [](const CellRecord& r) {  // quoted, without quotes or line breaks inside
    std::string err = r.error;
    std::replace(err.begin(), err.end(), '"', '\'');
    std::replace(err.begin(), err.end(), '\n', ' ');
    return "\"" + err + "\"";
  }));
  return c;
}

}  // namespace

const std::vector<CellColumn>& cell_columns() {
  static const std::vector<CellColumn> columns = make_columns();
  return columns;
}

std::vector<CellColumn> embree_columns(const std::string& path) {
  using E = CellRecord::EmbreeFigures;
  auto sorted = [](const E& e) { return e.trace.n > 0; };
  std::vector<Col> c;
  c.push_back(embree_numeric(path, "speedup", [](const CellRecord&, const E& e) { return e.speedup.value; }, 4));
  c.push_back(embree_numeric(path, "speedup_lo", [](const CellRecord&, const E& e) { return e.speedup.lo; }, 4));
  c.push_back(embree_numeric(path, "speedup_hi", [](const CellRecord&, const E& e) { return e.speedup.hi; }, 4));
  c.push_back(embree_numeric(
      path, "ms", [sorted](const CellRecord&, const E& e) { return sorted(e) ? e.trace.median_ms : kNaN; }, 4));
  c.push_back(embree_numeric(path, "nosort_ms", [](const CellRecord&, const E& e) { return e.nosort.median_ms; }, 4));
  c.push_back(embree_numeric(path, "mrays", [](const CellRecord& r, const E& e) { return mrays_at(r.rays, e.trace); }, 4));
  c.push_back(
      embree_numeric(path, "nosort_mrays", [](const CellRecord& r, const E& e) { return mrays_at(r.rays, e.nosort); }, 4));
  return c;
}

std::vector<CellColumn> cell_columns_for(const std::vector<CellRecord>& cells) {
  std::vector<CellColumn> columns = cell_columns();
  std::vector<std::string> paths;
  for (const CellRecord& r : cells)
    for (const auto& e : r.embree)
      if (std::find(paths.begin(), paths.end(), e.path) == paths.end()) paths.push_back(e.path);
  for (const std::string& path : paths)
    for (CellColumn& c : embree_columns(path)) columns.push_back(std::move(c));
  return columns;
}

const CellColumn* find_cell_column(const std::string& name) {
  for (const auto& c : cell_columns())
    if (c.name == name) return &c;
  // Every path's columns, made once: a rule may name a path whichever set it is checked on.
  static const std::vector<CellColumn> embree = [] {
    std::vector<CellColumn> all;
    for (const EmbreePathInfo& info : kEmbreePaths)
      for (CellColumn& c : embree_columns(info.key)) all.push_back(std::move(c));
    return all;
  }();
  for (const auto& c : embree)
    if (c.name == name) return &c;
  return nullptr;
}

std::string csv_header() { return csv_header(cell_columns()); }

std::string csv_row(const CellRecord& r) { return csv_row(r, cell_columns()); }

std::string csv_header(const std::vector<CellColumn>& columns) {
  std::string s;
  for (const auto& c : columns) s += (s.empty() ? "" : ",") + c.name;
  return s;
}

std::string csv_row(const CellRecord& r, const std::vector<CellColumn>& columns) {
  std::string s;
  for (std::size_t i = 0; i < columns.size(); ++i) {
    if (i > 0) s += ',';
    s += columns[i].csv(r);
  }
  return s;
}

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
