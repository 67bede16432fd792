#include "bench/compare.h"

#include <fmt/format.h>

#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <set>

#include "bench/encoder_files.h"
#include "scene/provenance.h"
#include "util/error.h"

namespace raysort {

namespace {

using Getter = std::function<std::string(const CellRecord&)>;
using Number = std::function<Estimate(const CellRecord&)>;

// A metric is a column of cells.csv (bench/record_columns.h): a number with the interval it has
// (an estimate, a timing, a rate of a timing; exact otherwise), or text (status, flags, hashes...)
// as is.
struct Metric {
  bool numeric = true;
  Number number;
  Getter text;
  const std::vector<std::string>* vocabulary = nullptr;
};

std::optional<Metric> find_metric(const std::string& name) {
  const CellColumn* col = find_cell_column(name);
  if (!col) return std::nullopt;
  if (col->kind == CellColumn::Number) return Metric{true, col->estimate, {}, nullptr};
  return Metric{false, {}, col->csv, &col->vocabulary};
}

std::string metric_names() {
  std::string names;
  for (auto& n : comparable_metrics()) names += (names.empty() ? "" : ", ") + n;
  // Embree's columns, one set per path (run --embree-paths), by pattern rather than every path's.
  const std::string stem = "embree_<path>";
  std::string embree;
  for (const CellColumn& c : embree_columns("<path>")) {
    if (!embree.empty()) embree += ',';
    // Appended in place: GCC 12 warns (-Wrestrict, a false positive) on `"," + name.substr(...)`.
    if (c.name != stem) embree.append(c.name, stem.size() + 1, std::string::npos);
  }
  return names + fmt::format(", and per Embree path {}_{{{}}} (e.g. embree_16-coherent_speedup)", stem, embree);
}

// A number as a rule writes it: digits with at most one point ("5", "0.5", ".5", "5."), nothing else.
std::optional<double> rule_number(const std::string& text) {
  // Scanned by hand, not with std::regex: libstdc++'s matcher recurses per character and overflows
  // the stack on long input (found by fuzz/result_set_fuzzer).
  std::size_t digits = 0, points = 0;
  for (char c : text) {
    if (c == '.') ++points;
    else if (c >= '0' && c <= '9') ++digits;
    else return std::nullopt;
  }
  if (digits == 0 || points > 1) return std::nullopt;
  return std::strtod(text.c_str(), nullptr);
}

// The matrix entries that are the measurement protocol's (how precisely, not what, was measured):
// two sets that differ only in these compare cell for cell.
const std::set<std::string>& protocol_keys() {
  static const std::set<std::string> k{"preset", "reps", "warmup", "max_noise", "max_time_s"};
  return k;
}

std::string side_name(const ResultSet& s) {
  const nlohmann::json& m = s.meta();
  const nlohmann::json d = m.value("device", nlohmann::json::object());
  std::string kernels;  // what the kernels were built from (not recorded before issue 44)
  if (const nlohmann::json k = m.value("kernels", nlohmann::json()); k.is_object()) {
    kernels = fmt::format(", kernels {} {}", k.value("source", "?"), k.value("hash", "?"));
    if (const std::string o = k.value("cl_options", ""); !o.empty()) kernels += ", RAYSORT_CL_OPTIONS=" + o;
  }
  return fmt::format("device '{}', driver {}, raysort commit {}{}", d.is_object() ? d.value("name", "?") : "?",
                     d.is_object() ? d.value("driver", "?") : "?", m.value("git_commit", "?"), kernels);
}

std::string shown(const Estimate& e) {
  if (!e.has_value()) return "–";
  if (!e.has_interval()) return fmt::format("{:.4g}", e.value);
  return fmt::format("{:.4g} [{:.4g}, {:.4g}]", e.value, e.lo, e.hi);
}

}  // namespace

std::vector<std::string> comparable_metrics() {
  std::vector<std::string> out;
  for (const auto& c : cell_columns()) out.push_back(c.name);
  return out;
}

FailRule FailRule::parse(const std::string& text) {
  FailRule r;
  r.text = text;
  if (text == "missing") {
    r.kind = Missing;
    return r;
  }
  const std::string grammar =
      "expected METRIC<-X% (relative drop), METRIC>+X% (relative rise), METRIC!= (any change), METRIC!=X (a number: "
      "absolute change; text: B's value is not X), METRIC==X (text: B's value is X) or 'missing'";
  // METRIC, blanks, one of <- >+ != ==, blanks, the rest (trimmed). Scanned by hand (see rule_number).
  auto blank = [](char c) { return c == ' ' || c == '\t'; };
  std::size_t i = 0;
  // Digits after the first character: the GPU model's columns (gpu_l1_hits, gpu_l2_misses); '-' and
  // capitals inside too: Embree's columns name their path as written (embree_1M-coherent_ms). No
  // operator starts with '-' or a capital, so the name still ends where the operator begins.
  auto name_char = [&](std::size_t k) {
    const char c = text[k];
    return (c >= 'a' && c <= 'z') || c == '_' || (k > 0 && ((c >= '0' && c <= '9') || (c >= 'A' && c <= 'Z') || c == '-'));
  };
  while (i < text.size() && name_char(i)) ++i;
  r.metric = text.substr(0, i);
  while (i < text.size() && blank(text[i])) ++i;
  const std::string op = text.substr(i, 2);
  if (r.metric.empty() || (op != "<-" && op != ">+" && op != "!=" && op != "=="))
    throw Error(fmt::format("--fail-if '{}': {}", text, grammar));
  std::size_t b = i + 2, e = text.size();
  while (b < e && blank(text[b])) ++b;
  while (e > b && blank(text[e - 1])) --e;
  const std::string rest = text.substr(b, e - b);
  const std::optional<Metric> metric = find_metric(r.metric);
  if (!metric)
    throw Error(fmt::format("--fail-if '{}': unknown metric '{}'; metrics (the columns of cells.csv) are: {}", text,
                            r.metric, metric_names()));
  if (op == "<-" || op == ">+") {
    if (!metric->numeric)
      throw Error(fmt::format("--fail-if '{}': {} is text; use {}!= (any change), {}!=X or {}==X", text, r.metric,
                              r.metric, r.metric, r.metric));
    const std::optional<double> x =
        rest.size() > 1 && rest.back() == '%' ? rule_number(rest.substr(0, rest.size() - 1)) : std::nullopt;
    if (!x)
      throw Error(fmt::format("--fail-if '{}': a relative rule needs a percentage, e.g. {}{}5%", text, r.metric, op));
    r.kind = op == "<-" ? RelativeDrop : RelativeRise;
    r.threshold = *x / 100.0;
    return r;
  }
  if (op == "!=" && rest.empty()) {
    r.kind = AnyChange;
    return r;
  }
  if (metric->numeric) {
    const std::optional<double> x = op == "!=" ? rule_number(rest) : std::nullopt;
    if (!x)
      throw Error(fmt::format("--fail-if '{}': {} is a number: {}!=X takes a non-negative number X (e.g. {}!=0.01), "
                              "and == is for text columns",
                              text, r.metric, r.metric, r.metric));
    r.kind = AbsoluteChange;
    r.threshold = *x;
    return r;
  }
  if (rest.empty()) throw Error(fmt::format("--fail-if '{}': {}", text, grammar));
  const auto& vocab = *metric->vocabulary;
  if (!vocab.empty() && std::find(vocab.begin(), vocab.end(), rest) == vocab.end()) {
    std::string known;
    for (const auto& v : vocab)
      if (!v.empty()) known += (known.empty() ? "" : ", ") + v;
    throw Error(fmt::format("--fail-if '{}': {} is one of {}, not '{}'", text, r.metric, known, rest));
  }
  r.kind = op == "==" ? ValueIs : ValueIsNot;
  r.value = rest;
  return r;
}

namespace {

using CellsById = std::map<std::string, const CellRecord*>;

// The --fail-if rules, cell by cell: violations, and relative changes that stayed within the noise.
void check_rules(const std::vector<FailRule>& rules, const CellsById& ma, CellsById& mb,
                 const std::vector<std::string>& only_a, CompareResult& out) {
  for (const FailRule& rule : rules) {
    if (rule.kind == FailRule::Missing) {
      for (auto& id : only_a) out.violations.push_back(fmt::format("missing: cell {} is in A but not in B", id));
      for (auto& [id, x] : ma)
        if (mb.count(id) && x->ok() && !mb[id]->ok())
          out.violations.push_back(fmt::format("missing: cell {} failed in B: {}", id, mb[id]->error));
      continue;
    }
    const Metric metric = *find_metric(rule.metric);
    if (rule.kind == FailRule::ValueIs || rule.kind == FailRule::ValueIsNot) {
      for (auto& [id, y] : mb) {
        const std::string vb = metric.text(*y);
        if ((vb == rule.value) == (rule.kind == FailRule::ValueIs))
          out.violations.push_back(fmt::format("{}: {} is {} in B (rule {})", id, rule.metric, vb, rule.text));
      }
      continue;
    }
    for (auto& [id, x] : ma) {
      auto it = mb.find(id);
      if (it == mb.end()) continue;
      const CellRecord* y = it->second;
      if (metric.numeric) {
        const Estimate ea = metric.number(*x), eb = metric.number(*y);
        const double va = ea.value, vb = eb.value;
        const bool relative = rule.kind == FailRule::RelativeDrop || rule.kind == FailRule::RelativeRise;
        const bool intervals = relative && ea.has_interval() && eb.has_interval();
        bool bad = false;   // the rule, on the intervals where both have one
        bool point = false;  // the same rule on the points alone
        switch (rule.kind) {
          // A figure that is null in both sets (NoSort's ANC: no keys) has not changed; null in one
          // set only has.
          case FailRule::AnyChange: bad = std::isnan(va) != std::isnan(vb) || (!std::isnan(va) && va != vb); break;
          case FailRule::AbsoluteChange:
            bad = std::isnan(va) != std::isnan(vb) || std::abs(vb - va) > rule.threshold;
            break;
          case FailRule::RelativeDrop:
            point = va > 0 && (vb - va) / va < -rule.threshold;
            // Even B's highest plausible value is more than the threshold below A's lowest.
            bad = intervals ? va > 0 && eb.hi < ea.lo * (1.0 - rule.threshold) : point;
            break;
          case FailRule::RelativeRise:
            point = va > 0 && (vb - va) / va > rule.threshold;
            bad = intervals ? va > 0 && eb.lo > ea.hi * (1.0 + rule.threshold) : point;
            break;
          case FailRule::Missing:
          case FailRule::ValueIs:
          case FailRule::ValueIsNot: break;
        }
        if (!bad && point) {
          out.within_noise.push_back(fmt::format("{}: {} {} -> {} (rule {}; not beyond the threshold between the "
                                                 "intervals' nearest ends)",
                                                 id, rule.metric, shown(ea), shown(eb), rule.text));
          continue;
        }
        if (bad)
          out.violations.push_back(fmt::format("{}: {} {} -> {} (rule {}{})", id, rule.metric, shown(ea), shown(eb),
                                               rule.text,
                                               !relative    ? ""
                                               : intervals  ? "; beyond the threshold between the intervals' nearest ends"
                                                            : "; point rule: no interval in both sets"));
      } else {
        std::string va = metric.text(*x), vb = metric.text(*y);
        if (va != vb) out.violations.push_back(fmt::format("{}: {} {} -> {} (rule {})", id, rule.metric, va, vb, rule.text));
      }
    }
  }
}

}  // namespace

std::string matrix_mismatch(const ResultSet& a, const ResultSet& b) {
  const nlohmann::json ma = canonical_matrix(a.meta().value("matrix", nlohmann::json::object())),
                       mb = canonical_matrix(b.meta().value("matrix", nlohmann::json::object()));
  std::vector<std::string> keys;
  for (const auto* m : {&ma, &mb})
    if (m->is_object())
      for (auto& [k, v] : m->items())
        if (!protocol_keys().count(k) && std::find(keys.begin(), keys.end(), k) == keys.end()) keys.push_back(k);
  return keys.empty() && ma != mb ? "matrix entry of another shape" : json_differences(ma, mb, keys);
}

namespace {

// The files the two sets' figures came from, where their checksums differ: scene files (meta.json
// "scene_files"), encoders from files ("encoder_files") and ray batches from files ("ray_files").
// Such figures are not comparable, whatever the rules say.
void add_provenance_notes(const nlohmann::json& meta_a, const nlohmann::json& meta_b, CompareResult& out) {
  out.scene_files = scene_file_differences(meta_a, meta_b);
  out.encoder_files = encoder_file_differences(meta_a, meta_b);
  out.ray_files = ray_file_differences(meta_a, meta_b);
  auto note = [&](const std::vector<std::string>& lines, const char* what) {
    if (lines.empty()) return;
    out.report += what;
    for (const auto& line : lines) out.report += "- " + line + "\n";
    out.report += "\n";
  };
  note(out.scene_files, "**The sets traced different scene files** (meta.json \"scene_files\", SHA-256): their "
                        "figures on these scenes are not comparable.\n\n");
  note(out.encoder_files, "**The sets ran different encoder files** (meta.json \"encoder_files\", SHA-256): their "
                          "figures for these encoders are not comparable.\n\n");
  note(out.ray_files, "**The sets traced different ray files** (meta.json \"ray_files\", SHA-256): their figures on "
                      "these batches are not comparable.\n\n");
}

}  // namespace

CompareResult compare_result_sets(const ResultSet& a, const ResultSet& b, const std::vector<std::string>& metrics,
                                  const std::vector<FailRule>& rules, bool allow_different_matrix) {
  CompareResult out;
  const std::string mismatch = matrix_mismatch(a, b);
  if (!mismatch.empty() && !allow_different_matrix)
    throw Error(fmt::format("{} and {} ran different matrices ({}); their cells would be compared as if alike. "
                            "Compare sets of one matrix (the device may differ), or pass --allow-different-matrix",
                            a.dir(), b.dir(), mismatch));
  auto ca = a.cells(), cb = b.cells();
  std::map<std::string, const CellRecord*> ma, mb;
  for (auto& c : ca) ma[c.id()] = &c;
  for (auto& c : cb) mb[c.id()] = &c;
  std::string& md = out.report;
  md += fmt::format("# raysort compare\n\nA: {} ({})\nB: {} ({})\n\n", a.dir(), side_name(a), b.dir(), side_name(b));
  if (!mismatch.empty()) md += fmt::format("**The matrices differ** (--allow-different-matrix): {}\n\n", mismatch);
  if (std::string p = json_differences(a.meta().value("matrix", nlohmann::json::object()),
                                       b.meta().value("matrix", nlohmann::json::object()),
                                       {protocol_keys().begin(), protocol_keys().end()});
      !p.empty())
    md += fmt::format("Measurement settings differ (the intervals' widths may too): {}\n\n", p);
  add_provenance_notes(a.meta(), b.meta(), out);

  for (auto& metric : metrics) {
    const std::optional<Metric> found = find_metric(metric);
    if (!found) throw Error(fmt::format("--metrics: unknown metric '{}'; metrics are: {}", metric, metric_names()));
    const bool numeric = found->numeric;
    md += fmt::format("## {}\n\n| cell | A | B | B/A | intervals |\n|---|---:|---:|---:|---|\n", metric);
    for (auto& [id, x] : ma) {
      auto it = mb.find(id);
      if (it == mb.end()) continue;
      const CellRecord* y = it->second;
      if (numeric) {
        const Estimate ea = found->number(*x), eb = found->number(*y);
        const double va = ea.value, vb = eb.value;
        const std::string overlap = !ea.has_interval() || !eb.has_interval() ? "–"
                                    : ea.overlaps(eb)                        ? "overlap"
                                                                             : "**apart**";
        md += fmt::format("| {} | {} | {} | {} | {} |\n", id, shown(ea), shown(eb),
                          va != 0 && std::isfinite(va) && std::isfinite(vb) ? fmt::format("{:.3f}", vb / va) : "–",
                          overlap);
      } else {
        std::string va = found->text(*x), vb = found->text(*y);
        md += fmt::format("| {} | {} | {} | {} | |\n", id, va, vb, va == vb ? "same" : "**differs**");
      }
    }
    md += "\n";
  }

  std::vector<std::string> only_a, only_b;
  for (auto& [id, x] : ma)
    if (!mb.count(id)) only_a.push_back(id);
  for (auto& [id, y] : mb)
    if (!ma.count(id)) only_b.push_back(id);
  md += fmt::format("## Cells in one set only\n\nOnly in A: {}\n\nOnly in B: {}\n\n", only_a.size(), only_b.size());
  for (auto& id : only_a) md += "- A only: `" + id + "`\n";
  for (auto& id : only_b) md += "- B only: `" + id + "`\n";

  check_rules(rules, ma, mb, only_a, out);
  if (!out.violations.empty()) {
    md += fmt::format("\n## Regressions: {}\n\n", out.violations.size());
    for (auto& v : out.violations) md += "- " + v + "\n";
  }
  if (!out.within_noise.empty()) {
    md += fmt::format("\n## Past a threshold but within the noise (not fired): {}\n\n", out.within_noise.size());
    for (auto& v : out.within_noise) md += "- " + v + "\n";
  }
  return out;
}

}  // namespace raysort
