#include "bench/compare.h"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <functional>
#include <map>
#include <regex>

#include "util/error.h"

namespace raysort {

namespace {

using Getter = std::function<std::string(const CellRecord&)>;
using Number = std::function<Estimate(const CellRecord&)>;

// rays / time: the interval of a rate is the rate at the time interval's ends.
Estimate mrays(const CellRecord& c) {
  const Estimate t = c.trace.estimate();
  const double r = static_cast<double>(c.rays) * 1e-3;
  Estimate e{c.trace_mrays, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN(), t.n};
  if (t.has_interval() && t.lo > 0) e.lo = r / t.hi, e.hi = r / t.lo;
  return e;
}
Estimate exact(double v) { return {v, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN(), 0}; }

const std::map<std::string, Number>& numeric_metrics() {
  static const std::map<std::string, Number> m = {
      {"trace_mrays", mrays},
      {"speedup", [](const CellRecord& c) { return c.speedup; }},
      {"net_speedup", [](const CellRecord& c) { return c.net_speedup; }},
      {"overhead_pct", [](const CellRecord& c) { return c.overhead_pct; }},
      {"aa", [](const CellRecord& c) { return c.aa; }},
      {"encode_ms", [](const CellRecord& c) { return c.encode.estimate(); }},
      {"sort_ms", [](const CellRecord& c) { return c.sort.estimate(); }},
      {"permute_ms", [](const CellRecord& c) { return c.permute.estimate(); }},
      {"trace_ms", [](const CellRecord& c) { return c.trace.estimate(); }},
      {"anc", [](const CellRecord& c) { return exact(c.anc); }},
      {"simt_lane_efficiency", [](const CellRecord& c) { return exact(c.simt_lane_efficiency); }},
      {"simt_distinct_per_visit", [](const CellRecord& c) { return exact(c.simt_distinct_per_visit); }},
      {"simt_lane_efficiency_ratio", [](const CellRecord& c) { return exact(c.simt_lane_efficiency_ratio); }},
      {"simt_distinct_per_visit_ratio", [](const CellRecord& c) { return exact(c.simt_distinct_per_visit_ratio); }},
      {"rays", [](const CellRecord& c) { return exact(static_cast<double>(c.rays)); }},
  };
  return m;
}

std::string shown(const Estimate& e) {
  if (!e.has_value()) return "–";
  if (!e.has_interval()) return fmt::format("{:.4g}", e.value);
  return fmt::format("{:.4g} [{:.4g}, {:.4g}]", e.value, e.lo, e.hi);
}

const std::map<std::string, Getter>& text_metrics() {
  static const std::map<std::string, Getter> m = {
      {"keys_hash", [](const CellRecord& c) { return c.keys_hash; }},
      {"order_hash", [](const CellRecord& c) { return c.order_hash; }},
      {"status", [](const CellRecord& c) { return c.status; }},
  };
  return m;
}

}  // namespace

std::vector<std::string> comparable_metrics() {
  std::vector<std::string> out;
  for (auto& [k, v] : numeric_metrics()) out.push_back(k);
  for (auto& [k, v] : text_metrics()) out.push_back(k);
  return out;
}

FailRule FailRule::parse(const std::string& text) {
  FailRule r;
  r.text = text;
  if (text == "missing") {
    r.kind = Missing;
    return r;
  }
  std::smatch m;
  static const std::regex re(R"(^([a-z_]+)\s*(<-|>\+|!=)\s*([0-9]*\.?[0-9]*)\s*(%?)$)");
  if (!std::regex_match(text, m, re))
    throw Error(fmt::format("--fail-if '{}': expected METRIC<-X% (relative drop), METRIC>+X% (relative rise), "
                            "METRIC!= (any change), METRIC!=X (absolute change) or 'missing'",
                            text));
  r.metric = m[1];
  std::string op = m[2], num = m[3], pct = m[4];
  if (!numeric_metrics().count(r.metric) && !text_metrics().count(r.metric)) {
    std::string names;
    for (auto& n : comparable_metrics()) names += (names.empty() ? "" : ", ") + n;
    throw Error(fmt::format("--fail-if '{}': unknown metric '{}'; metrics are: {}", text, r.metric, names));
  }
  if (op == "!=") {
    r.kind = num.empty() ? AnyChange : AbsoluteChange;
    r.threshold = num.empty() ? 0.0 : std::stod(num);
  } else {
    if (num.empty() || pct.empty())
      throw Error(fmt::format("--fail-if '{}': a relative rule needs a percentage, e.g. {}{}5%", text, r.metric, op));
    if (!numeric_metrics().count(r.metric))
      throw Error(fmt::format("--fail-if '{}': {} is not numeric; use {}!=", text, r.metric, r.metric));
    r.kind = op == "<-" ? RelativeDrop : RelativeRise;
    r.threshold = std::stod(num) / 100.0;
  }
  return r;
}

CompareResult compare_result_sets(const ResultSet& a, const ResultSet& b, const std::vector<std::string>& metrics,
                                  const std::vector<FailRule>& rules) {
  CompareResult out;
  auto ca = a.cells(), cb = b.cells();
  std::map<std::string, const CellRecord*> ma, mb;
  for (auto& c : ca) ma[c.id()] = &c;
  for (auto& c : cb) mb[c.id()] = &c;
  auto name_of = [](const ResultSet& s) {
    return s.meta().contains("device") ? s.meta()["device"].value("name", s.dir()) + " @ " + s.meta().value("git_commit", "?")
                                       : s.dir();
  };
  std::string& md = out.report;
  md += fmt::format("# raysort compare\n\nA: {} ({})\nB: {} ({})\n\n", a.dir(), name_of(a), b.dir(), name_of(b));

  for (auto& metric : metrics) {
    bool numeric = numeric_metrics().count(metric) > 0;
    if (!numeric && !text_metrics().count(metric)) {
      std::string names;
      for (auto& n : comparable_metrics()) names += (names.empty() ? "" : ", ") + n;
      throw Error(fmt::format("unknown metric '{}'; metrics are: {}", metric, names));
    }
    md += fmt::format("## {}\n\n| cell | A | B | B/A | intervals |\n|---|---:|---:|---:|---|\n", metric);
    for (auto& [id, x] : ma) {
      auto it = mb.find(id);
      if (it == mb.end()) continue;
      const CellRecord* y = it->second;
      if (numeric) {
        const Estimate ea = numeric_metrics().at(metric)(*x), eb = numeric_metrics().at(metric)(*y);
        const double va = ea.value, vb = eb.value;
        const std::string overlap = !ea.has_interval() || !eb.has_interval() ? "–"
                                    : ea.overlaps(eb)                        ? "overlap"
                                                                             : "**apart**";
        md += fmt::format("| {} | {} | {} | {} | {} |\n", id, shown(ea), shown(eb),
                          va != 0 && std::isfinite(va) && std::isfinite(vb) ? fmt::format("{:.3f}", vb / va) : "–",
                          overlap);
      } else {
        std::string va = text_metrics().at(metric)(*x), vb = text_metrics().at(metric)(*y);
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

  for (const FailRule& rule : rules) {
    if (rule.kind == FailRule::Missing) {
      for (auto& id : only_a) out.violations.push_back(fmt::format("missing: cell {} is in A but not in B", id));
      for (auto& [id, x] : ma)
        if (mb.count(id) && x->ok() && !mb[id]->ok())
          out.violations.push_back(fmt::format("missing: cell {} failed in B: {}", id, mb[id]->error));
      continue;
    }
    for (auto& [id, x] : ma) {
      auto it = mb.find(id);
      if (it == mb.end()) continue;
      const CellRecord* y = it->second;
      if (numeric_metrics().count(rule.metric)) {
        const Estimate ea = numeric_metrics().at(rule.metric)(*x), eb = numeric_metrics().at(rule.metric)(*y);
        const double va = ea.value, vb = eb.value;
        const bool relative = rule.kind == FailRule::RelativeDrop || rule.kind == FailRule::RelativeRise;
        const bool intervals = relative && ea.has_interval() && eb.has_interval();
        bool bad = false;   // the rule, on the intervals where both have one
        bool point = false;  // the same rule on the points alone
        switch (rule.kind) {
          case FailRule::AnyChange: bad = va != vb; break;
          case FailRule::AbsoluteChange: bad = std::abs(vb - va) > rule.threshold; break;
          case FailRule::RelativeDrop:
            point = va > 0 && (vb - va) / va < -rule.threshold;
            // Even B's highest plausible value is more than the threshold below A's lowest.
            bad = intervals ? va > 0 && eb.hi < ea.lo * (1.0 - rule.threshold) : point;
            break;
          case FailRule::RelativeRise:
            point = va > 0 && (vb - va) / va > rule.threshold;
            bad = intervals ? va > 0 && eb.lo > ea.hi * (1.0 + rule.threshold) : point;
            break;
          case FailRule::Missing: break;
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
        std::string va = text_metrics().at(rule.metric)(*x), vb = text_metrics().at(rule.metric)(*y);
        if (va != vb) out.violations.push_back(fmt::format("{}: {} {} -> {} (rule {})", id, rule.metric, va, vb, rule.text));
      }
    }
  }
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
