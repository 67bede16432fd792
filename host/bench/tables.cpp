// The paper's tables laid out as in the paper, from cell records only:
//   the noise floor of the set (A/A calibration, interval widths, what stopped the cells);
//   trace speed with the speedup and its 95 % interval (Tables 2-4), per access mode;
//   overhead: encode/sort[/permute] ms, share of trace time and net speedup (Table 5);
//   gather against permute; key length: speed and ANC against key bits (Tables 6-7); the SIMT
//   model (a column's best lane-efficiency ratio in bold); HCC with direction bits (appendix Table
//   8); subsequent bounces (appendix); robust against fast; trace classes; Embree's paths on the
//   cells' orders (run --embree-paths); pixel against shuffled baseline; failed cells.
// Marks: **bold** is a column's best speedup only when its interval does not overlap the second
// best's; *italic* is a speedup whose interval contains 1; "= NoSort" is an order equal to the
// generation order (no speedup is reported for it).
#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <set>

#include "bench/encoder_files.h"
#include "bench/result_set.h"

namespace raysort {

namespace {

std::vector<std::string> ordered(const std::vector<CellRecord>& cells, const nlohmann::json& meta, const char* axis,
                                 std::string CellRecord::*field) {
  std::vector<std::string> out;
  if (meta.contains("matrix") && meta["matrix"].contains(axis))
    for (auto& v : meta["matrix"][axis]) out.push_back(v.get<std::string>());
  for (auto& c : cells)
    if (std::find(out.begin(), out.end(), c.*field) == out.end()) out.push_back(c.*field);
  // Keep only values that have cells.
  std::vector<std::string> present;
  for (auto& v : out)
    if (std::any_of(cells.begin(), cells.end(), [&](const CellRecord& c) { return c.*field == v; })) present.push_back(v);
  return present;
}

// The first item of a comma-separated matrix entry ("robust,fast" -> "robust").
std::string first_of(const nlohmann::json& meta, const char* key, const std::string& fallback) {
  if (!meta.contains("matrix") || !meta["matrix"].contains(key) || !meta["matrix"][key].is_string()) return fallback;
  const std::string v = meta["matrix"][key].get<std::string>();
  return v.substr(0, v.find(','));
}

// Which cells a table shows: the main trace variant, trace class, access mode and baseline order
// unless it says otherwise.
struct View {
  std::string variant = "robust", access = "gather", baseline = "pixel", layout = "wide";
  View with_variant(const std::string& x) const { View v = *this; v.variant = x; return v; }
  View with_access(const std::string& a) const { View v = *this; v.access = a; return v; }
  View with_baseline(const std::string& b) const { View v = *this; v.baseline = b; return v; }
  View with_layout(const std::string& l) const { View v = *this; v.layout = l; return v; }
};

const CellRecord* find(const std::vector<CellRecord>& cells, const View& view, const std::string& scene,
                       const std::string& batch, const std::string& encoder, unsigned bits) {
  for (auto& c : cells)
    if (c.scene == scene && c.batch == batch && c.encoder == encoder && c.top_bits == 0 && c.variant == view.variant &&
        c.baseline == view.baseline && c.layout == view.layout &&
        (c.encoder == kBaselineEncoder || (c.bits == bits && c.access == view.access)))
      return &c;
  return nullptr;
}

std::string header(const std::string& first, const std::vector<std::string>& cols) {
  std::string h = fmt::format("| {} |", first), sep = "|---|";
  for (auto& c : cols) {
    h += fmt::format(" {} |", c);
    sep += "---:|";
  }
  return h + "\n" + sep + "\n";
}

// A speedup as the tables print it: "= NoSort" for an unchanged order, italic when its interval
// contains 1, bold when `best`.
std::string speedup_text(const CellRecord& c, bool best) {
  if (c.same_order_as_nosort) return "= NoSort";
  std::string s = interval_text(c.speedup);
  if (c.speedup.contains(1.0)) s = "*" + s + "*";
  return best ? "**" + s + "**" : s;
}

// The cell whose speedup is a column's significant best: the highest speedup among cells with an
// interval, provided its interval does not overlap the runner-up's. nullptr when none qualifies.
const CellRecord* significant_best(const std::vector<const CellRecord*>& column) {
  std::vector<const CellRecord*> ranked;
  for (const CellRecord* c : column)
    if (c && c->ok() && c->encoder != kBaselineEncoder && !c->same_order_as_nosort && c->speedup.has_interval())
      ranked.push_back(c);
  if (ranked.empty()) return nullptr;
  std::sort(ranked.begin(), ranked.end(),
            [](const CellRecord* a, const CellRecord* b) { return a->speedup.value > b->speedup.value; });
  if (ranked.size() > 1 && ranked[0]->speedup.overlaps(ranked[1]->speedup)) return nullptr;
  return ranked[0];
}

// The encoder cell with the highest SIMT lane-efficiency ratio (deterministic: no interval to
// overlap), or nullptr when no encoder cell has one.
const CellRecord* best_lane_efficiency(const std::vector<const CellRecord*>& column) {
  const CellRecord* best = nullptr;
  for (const CellRecord* c : column)
    if (c && c->ok() && c->encoder != kBaselineEncoder &&
        (!best || c->simt_lane_efficiency_ratio > best->simt_lane_efficiency_ratio))
      best = c;
  return best;
}

// "1.230 · 1.152": the speedup (as speedup_text prints it, without marks) and the SIMT
// lane-efficiency ratio (three decimals: these tables compare close variants), bold when `best`.
std::string speed_and_lanes(const CellRecord& c, bool best) {
  const std::string lanes = fmt::format("{:.3f}", c.simt_lane_efficiency_ratio);
  return fmt::format("{} · {}", speedup_text(c, false), best ? "**" + lanes + "**" : lanes);
}

std::string noise_section(const std::vector<CellRecord>& cells) {
  const NoiseSummary n = summarize_noise(cells);
  std::string md = "## Noise floor\n\n";
  if (n.aa_intervals == 0) return md + "No cell has an A/A interval (too few rounds, or a version 1 result set).\n\n";
  md += fmt::format(
      "- **A/A calibration**: {} of {} A/A intervals contain 1.00 ({:.1f} %; about 95 % means the intervals are "
      "honest). Each A/A interval compares the NoSort trace with a second NoSort trace of the same rounds.\n",
      n.aa_containing_one, n.aa_intervals, 100.0 * n.aa_coverage());
  md += fmt::format("- Speedup intervals: {} cells; relative half-width median {:.1f} %, 90th percentile {:.1f} %, "
                    "largest {:.1f} %.\n",
                    n.cells_with_interval, 100.0 * n.median_half_width, 100.0 * n.p90_half_width,
                    100.0 * n.max_half_width);
  md += fmt::format("- Rounds per cell: median {}, range {}–{}; stopped by the noise target: {}, by the time budget: "
                    "{}, by the round limit: {}.\n",
                    n.median_rounds, n.min_rounds, n.max_rounds, n.stopped_by_noise, n.stopped_by_time,
                    n.stopped_by_rounds);
  md += fmt::format("- Cells whose sorted order equals NoSort's (no speedup reported): {}; speedups whose interval "
                    "contains 1 (no measurable effect): {}.\n\n",
                    n.same_order_cells, n.speedups_containing_one);
  return md;
}

// What every section of the tables reads: the cells, the axes in the matrix's order, and the view
// the main tables show.
struct TableContext {
  const std::vector<CellRecord>& cells;
  View main_view;
  std::vector<std::string> scenes, batches, encoders, accesses;
  std::vector<unsigned> bits;
  unsigned overview_bits = 0;

  TableContext(const std::vector<CellRecord>& all, const nlohmann::json& meta) : cells(all) {
    main_view = {first_of(meta, "variant", cells.empty() ? "robust" : cells.front().variant),
                 first_of(meta, "access", "gather"), first_of(meta, "baseline", "pixel"),
                 first_of(meta, "layout", cells.empty() ? "wide" : cells.front().layout)};
    scenes = ordered(cells, meta, "scenes", &CellRecord::scene);
    batches = ordered(cells, meta, "batches", &CellRecord::batch);
    encoders = ordered(cells, meta, "encoders", &CellRecord::encoder);
    std::set<std::string> access_set;
    std::set<unsigned> bit_set;
    for (auto& c : cells)
      if (c.encoder != kBaselineEncoder) {
        if (c.top_bits == 0) bit_set.insert(c.bits);
        access_set.insert(c.access);
      }
    for (const std::string a : {"gather", "permute"})
      if (access_set.count(a)) accesses.push_back(a);
    if (accesses.empty()) accesses.push_back(main_view.access);
    bits.assign(bit_set.begin(), bit_set.end());
    overview_bits = bit_set.count(32) ? 32 : (bits.empty() ? 0 : bits.back());
  }
  const CellRecord* at(const View& v, const std::string& scene, const std::string& batch, const std::string& encoder,
                       unsigned b) const {
    return find(cells, v, scene, batch, encoder, b);
  }
};

std::string introduction(const nlohmann::json& meta) {
  std::string md = "# raysort results\n\n";
  if (meta.contains("device"))
    md += fmt::format("Device: {} ({}, driver {}). ", meta["device"].value("name", "?"), meta["device"].value("platform", "?"),
                      meta["device"].value("driver", "?"));
  if (meta.contains("matrix")) {
    const auto& m = meta["matrix"];
    std::string sampling;
    if (m.contains("shadow_rays")) sampling += fmt::format(", {} shadow rays per bounce", m["shadow_rays"].get<unsigned>());
    if (m.contains("bounces")) sampling += fmt::format(", {} bounces", m["bounces"].get<unsigned>());
    md += fmt::format("Resolution {}, {} spp{}; trace variant {}, access {}, baseline order {}, trace class {}. Protocol: {} warm-up round(s), at least {} "
                      "timed rounds per cell, then until the speedup interval is within ±{:.1f} % or {} s of "
                      "sampling.\n\n",
                      m.value("resolution", "?"), m.value("spp", 0), sampling, m.value("variant", "robust"),
                      m.value("access", "gather"), m.value("baseline", "pixel"), m.value("layout", "wide"),
                      m.value("warmup", 0), m.value("reps", 0),
                      100.0 * m.value("max_noise", 0.0), m.value("max_time_s", 0.0));
  }
  md += "Times are medians of OpenCL profiling events over the rounds of the measurement protocol "
        "(docs/measurement.md): each round runs encode + sort, then, in a random order, the NoSort trace, a second "
        "NoSort trace (the A/A check) and the cell's own trace(s). Speedup = the typical per-round NoSort trace / "
        "trace (Hodges–Lehmann estimate of the log ratios) with its exact 95 % signed-rank interval in brackets; net = "
        "NoSort trace / (encode + sort + permute + trace), per round likewise. **Bold**: a column's best speedup whose "
        "interval does not overlap the second best's. *Italic*: the interval contains 1. \"= NoSort\": the sorted "
        "order is the generation order, so no speedup is reported. A cell whose sorted trace does not reproduce the "
        "NoSort hits exactly is listed under failed cells and has no speed.\n\n";
  return md;
}

// Free text (a device's message, a path) in a list item or a table cell: one line, its '|' escaped,
// so it cannot end the item or the cell, or be read as a table by a markdown viewer.
std::string one_line(const std::string& text) {
  std::string out;
  for (char ch : text) out += ch == '|' ? std::string("\\|") : ch == '\n' || ch == '\r' ? std::string(" ") : std::string(1, ch);
  return out;
}

// Where the encoders from files came from, and that they have no host twin (meta.json
// "encoder_files"): nothing when the set has none.
std::string encoder_files_section(const nlohmann::json& meta) {
  const std::vector<RecordedEncoderFile> files = recorded_encoder_files(meta);
  if (files.empty()) return "";
  std::string md =
      "## Encoders from files\n\nEach written as one OpenCL C function in a file (docs/encoders.md, \"An encoder from "
      "a file\"), named here by its file and SHA-256. **No host twin**: unlike a built-in encoder, whose kernel the "
      "tests compare bit for bit with a host copy, its keys are checked only against themselves: in every cell a second "
      "launch over the batch gave the same keys, or the cell failed.\n\n| encoder | file | SHA-256 | host twin |\n|---|---|---|---|\n";
  for (const RecordedEncoderFile& f : files)
    md += fmt::format("| {} | `{}` | `{}` | no host twin |\n", one_line(f.name), one_line(f.path), one_line(f.sha256));
  return md + "\n";
}

// Trace speed per batch and access mode (Tables 2-4).
std::string trace_speed_sections(const TableContext& t) {
  std::string md;
  for (auto& access : t.accesses) {
    const View view = t.main_view.with_access(access);
    for (auto& batch : t.batches) {
      md += fmt::format("## Trace speed, {} rays, {}-bit keys, access {}: MRays/s (speedup [95 % interval])\n\n", batch,
                        t.overview_bits, access);
      md += header("encoder", t.scenes);
      std::map<std::string, const CellRecord*> best;
      for (auto& s : t.scenes) {
        std::vector<const CellRecord*> column;
        for (auto& e : t.encoders) column.push_back(t.at(view, s, batch, e, t.overview_bits));
        best[s] = significant_best(column);
      }
      for (auto& e : t.encoders) {
        md += fmt::format("| {} |", e);
        for (auto& s : t.scenes) {
          auto* c = t.at(view, s, batch, e, t.overview_bits);
          if (!c) md += " – |";
          else if (!c->ok()) md += " failed |";
          else if (c->encoder == kBaselineEncoder)
            md += fmt::format(" {:.2f} (A/A {}) |", c->trace_mrays, interval_text(c->aa));
          else
            md += fmt::format(" {:.2f} ({}) |", c->trace_mrays, speedup_text(*c, c == best[s]));
        }
        md += "\n";
      }
      md += "\n";
    }
  }
  return md;
}

// Overhead (Table 5).
std::string overhead_sections(const TableContext& t) {
  std::string md;
  for (auto& access : t.accesses) {
    const View view = t.main_view.with_access(access);
    for (auto& batch : t.batches) {
      md += fmt::format("## Overhead, {} rays, {}-bit keys, access {}: encode + sort{} ms (% of trace) → net speedup "
                        "[95 % interval]\n\n",
                        batch, t.overview_bits, access, access == "permute" ? " + permute" : "");
      md += header("encoder", t.scenes);
      for (auto& e : t.encoders) {
        if (e == kBaselineEncoder) continue;
        md += fmt::format("| {} |", e);
        for (auto& s : t.scenes) {
          auto* c = t.at(view, s, batch, e, t.overview_bits);
          if (!c) md += " – |";
          else if (!c->ok()) md += " failed |";
          else
            md += fmt::format(" {:.2f} + {:.2f}{} ({:.0f}%) → {} |", c->encode.median_ms, c->sort.median_ms,
                              access == "permute" ? fmt::format(" + {:.2f}", c->permute.median_ms) : "",
                              c->overhead_pct.value, interval_text(c->net_speedup));
        }
        md += "\n";
      }
      md += "\n";
    }
  }
  return md;
}

// Gather against permute, when both ran: the same order read two ways.
std::string gather_permute_section(const TableContext& t) {
  if (t.accesses.size() < 2) return "";
  std::string md = fmt::format(
      "## Gather against permute, {}-bit keys: trace speedup, permute ms, net speedup\n\n"
      "Each cell's speedups are paired with the NoSort traces of its own rounds; the gather and permute cells of one "
      "encoder share their rounds.\n\n"
      "| scene | batch | encoder | speedup gather | speedup permute | permute ms (% of trace) | net gather | net "
      "permute |\n|---|---|---|---:|---:|---:|---:|---:|\n",
      t.overview_bits);
  const View g = t.main_view.with_access("gather"), p = t.main_view.with_access("permute");
  for (auto& s : t.scenes)
    for (auto& batch : t.batches)
      for (auto& e : t.encoders) {
        if (e == kBaselineEncoder) continue;
        auto* cg = t.at(g, s, batch, e, t.overview_bits);
        auto* cp = t.at(p, s, batch, e, t.overview_bits);
        if (!cg || !cp || !cg->ok() || !cp->ok()) continue;
        md += fmt::format("| {} | {} | {} | {} | {} | {:.2f} ({:.1f}%) | {} | {} |\n", s, batch, e,
                          speedup_text(*cg, false), speedup_text(*cp, false), cp->permute.median_ms,
                          cp->trace.median_ms > 0 ? 100.0 * cp->permute.median_ms / cp->trace.median_ms : 0.0,
                          interval_text(cg->net_speedup), interval_text(cp->net_speedup));
      }
  return md + "\n";
}

// Key length (Tables 6 and 7): per scene and batch, when several key lengths ran.
std::string key_length_sections(const TableContext& t) {
  if (t.bits.size() < 2) return "";
  std::string md;
  std::vector<std::string> bit_cols;
  for (auto b : t.bits) bit_cols.push_back(fmt::format("{} bits", b));
  for (auto& s : t.scenes)
    for (auto& batch : t.batches) {
      bool any = false;
      for (auto& e : t.encoders)
        for (auto b : t.bits) any |= t.at(t.main_view, s, batch, e, b) && e != kBaselineEncoder;
      if (!any) continue;
      md += fmt::format("## Key length, {} {}, access {}: MRays/s (speedup [95 % interval]) | ANC\n\n", s, batch,
                        t.main_view.access);
      md += header("encoder", bit_cols);
      for (auto& e : t.encoders) {
        if (e == kBaselineEncoder) continue;
        md += fmt::format("| {} |", e);
        for (auto b : t.bits) {
          auto* c = t.at(t.main_view, s, batch, e, b);
          if (!c) md += " – |";
          else if (!c->ok()) md += " failed |";
          else md += fmt::format(" {:.2f} ({}) \\| {:.2f} |", c->trace_mrays, speedup_text(*c, false), c->anc);
        }
        md += "\n";
      }
      md += "\n";
    }
  return md;
}

// The deterministic figures: ANC at every key length (Table 7) and the SIMT model.
std::string deterministic_sections(const TableContext& t) {
  std::string md = "## ANC: average number of distinct keys per 32 consecutive sorted rays\n\n";
  std::vector<std::string> cols;
  for (auto& s : t.scenes)
    for (auto& batch : t.batches)
      for (auto b : t.bits) cols.push_back(fmt::format("{} {} {}b", s, batch, b));
  md += header("encoder", cols);
  for (auto& e : t.encoders) {
    if (e == kBaselineEncoder) continue;
    md += fmt::format("| {} |", e);
    for (auto& s : t.scenes)
      for (auto& batch : t.batches)
        for (auto b : t.bits) {
          auto* c = t.at(t.main_view, s, batch, e, b);
          md += c && c->ok() ? fmt::format(" {:.2f} |", c->anc) : " – |";
        }
    md += "\n";
  }
  md += fmt::format(
      "\n## SIMT model, {}-bit keys: lane efficiency (ratio vs NoSort) / distinct nodes per visit (ratio vs NoSort)\n\n"
      "Device-independent: what a 32-wide GPU warp would see in this trace order (docs/design.md, \"Metrics\").\n\n",
      t.overview_bits);
  cols.clear();
  for (auto& s : t.scenes)
    for (auto& batch : t.batches) cols.push_back(s + " " + batch);
  md += header("encoder", cols);
  // Deterministic, so a column's best needs no interval: the highest lane-efficiency ratio is bold.
  std::map<std::pair<std::string, std::string>, const CellRecord*> best;
  for (auto& s : t.scenes)
    for (auto& batch : t.batches) {
      std::vector<const CellRecord*> column;
      for (auto& e : t.encoders) column.push_back(t.at(t.main_view, s, batch, e, t.overview_bits));
      best[{s, batch}] = best_lane_efficiency(column);
    }
  for (auto& e : t.encoders) {
    md += fmt::format("| {} |", e);
    for (auto& s : t.scenes)
      for (auto& batch : t.batches) {
        auto* c = t.at(t.main_view, s, batch, e, t.overview_bits);
        if (!c || !c->ok()) {
          md += " – |";
          continue;
        }
        const std::string ratio = fmt::format("{:.2f}", c->simt_lane_efficiency_ratio);
        md += fmt::format(" {:.3f} ({}) / {:.3f} ({:.2f}) |", c->simt_lane_efficiency,
                          c == best[{s, batch}] ? "**" + ratio + "**" : ratio, c->simt_distinct_per_visit,
                          c->simt_distinct_per_visit_ratio);
      }
    md += "\n";
  }
  return md + "\n";
}

// Top-k sorting, when run.
std::string top_k_section(const TableContext& t) {
  if (std::none_of(t.cells.begin(), t.cells.end(), [](const CellRecord& c) { return c.top_bits > 0; })) return "";
  std::string md = "## Top-k sorting: sort by the highest k key bits only\n\n"
                   "| cell | sort ms | trace MRays/s (speedup [95 % interval]) | net | ANC |\n|---|---:|---:|---:|---:|\n";
  for (auto& c : t.cells)
    if (c.top_bits > 0 && c.ok())
      md += fmt::format("| {} | {:.2f} | {:.2f} ({}) | {} | {:.2f} |\n", c.id(), c.sort.median_ms, c.trace_mrays,
                        speedup_text(c, false), interval_text(c.net_speedup), c.anc);
  return md + "\n";
}

// Robust vs fast (issue 7): what watertightness costs, and what the fast variant leaks.
std::string variants_section(const TableContext& t) {
  std::set<std::string> variants;
  for (auto& c : t.cells) variants.insert(c.variant);
  if (!variants.count("robust") || !variants.count("fast")) return "";
  std::string md =
      "## Robust vs fast trace: what watertight intersection costs\n\n"
      "NoSort trace MRays/s of each variant on the same rays, their ratio, and leaks per million rays "
      "(rays the variant misses that the other one hits: the fast variant's leaks through shared edges and "
      "vertices). Best = the encoder with the highest speedup at the overview key length in that variant. The "
      "two variants' NoSort cells ran at different times, so their ratio carries no interval; `raysort trace "
      "--variant both` times both variants in the same rounds.\n\n"
      "| scene | batch | fast MRays/s | robust MRays/s | robust/fast | fast leaks/M | robust leaks/M | best fast | best robust |\n"
      "|---|---|---:|---:|---:|---:|---:|---|---|\n";
  for (auto& s : t.scenes)
    for (auto& batch : t.batches) {
      auto* f = t.at(t.main_view.with_variant("fast"), s, batch, kBaselineEncoder, 0);
      auto* r = t.at(t.main_view.with_variant("robust"), s, batch, kBaselineEncoder, 0);
      if (!f || !r || !f->ok() || !r->ok()) continue;
      auto best = [&](const std::string& v) {
        const CellRecord* b = nullptr;
        for (auto& e : t.encoders)
          if (auto* c = t.at(t.main_view.with_variant(v), s, batch, e, t.overview_bits);
              c && c->ok() && e != kBaselineEncoder && !c->same_order_as_nosort)
            if (!b || c->speedup.value > b->speedup.value) b = c;
        return b ? fmt::format("{} {}", b->encoder, speedup_text(*b, false)) : std::string("–");
      };
      md += fmt::format("| {} | {} | {:.2f} | {:.2f} | {:.3f} | {:.1f} | {:.1f} | {} | {} |\n", s, batch, f->trace_mrays,
                        r->trace_mrays, f->trace_mrays > 0 ? r->trace_mrays / f->trace_mrays : 0.0, f->leaks_per_million,
                        r->leaks_per_million, best("fast"), best("robust"));
    }
  return md + "\n";
}

// The trace classes side by side (docs/trace.md, "Trace classes"): what each makes of the same
// rays, and how much of the ordering effect it can see. A class's speedups are against its own
// NoSort in its own rounds; two classes' NoSort traces ran at different times, so their ratio has no
// interval (`raysort trace --layout a,b` times classes in the same rounds).
std::string classes_section(const TableContext& t) {
  std::vector<std::string> classes;
  for (auto& c : t.cells)
    if (std::find(classes.begin(), classes.end(), c.layout) == classes.end()) classes.push_back(c.layout);
  if (classes.size() < 2) return "";
  // The main class first, the others in the order the cells name them.
  std::stable_partition(classes.begin(), classes.end(), [&](const std::string& l) { return l == t.main_view.layout; });
  std::string md = fmt::format(
      "## Trace classes, {}-bit keys, access {}\n\n"
      "Per scene and batch and class: NoSort MRays/s, its speed over the {} class's NoSort (ran in other rounds: no "
      "interval), the best encoder's speedup over the class's own NoSort [95 % interval], and how many of the "
      "class's speedup intervals contain 1 (no measurable effect of the order).\n\n"
      "| scene | batch | class | NoSort MRays/s | × {} | best encoder | intervals containing 1 |\n"
      "|---|---|---|---:|---:|---|---:|\n",
      t.overview_bits, t.main_view.access, t.main_view.layout, t.main_view.layout);
  // Per class and batch over every scene: speedup intervals, and those that contain 1.
  std::map<std::pair<std::string, std::string>, std::pair<unsigned, unsigned>> totals;
  for (auto& s : t.scenes)
    for (auto& batch : t.batches) {
      const CellRecord* main = t.at(t.main_view, s, batch, kBaselineEncoder, 0);
      for (auto& layout : classes) {
        const View view = t.main_view.with_layout(layout);
        const CellRecord* nosort = t.at(view, s, batch, kBaselineEncoder, 0);
        if (!nosort || !nosort->ok()) continue;
        const CellRecord* best = nullptr;
        unsigned intervals = 0, with_one = 0;
        for (auto& e : t.encoders) {
          const CellRecord* c = t.at(view, s, batch, e, t.overview_bits);
          if (!c || !c->ok() || e == kBaselineEncoder || c->same_order_as_nosort) continue;
          if (!best || c->speedup.value > best->speedup.value) best = c;
          if (c->speedup.has_interval()) ++intervals, with_one += c->speedup.contains(1.0);
        }
        auto& total = totals[{layout, batch}];
        total.first += intervals, total.second += with_one;
        md += fmt::format("| {} | {} | {} | {:.2f} | {} | {} | {} of {} |\n", s, batch, layout, nosort->trace_mrays,
                          main && main->ok() && main->trace_mrays > 0
                              ? fmt::format("{:.2f}", nosort->trace_mrays / main->trace_mrays)
                              : "–",
                          best ? fmt::format("{} {}", best->encoder, speedup_text(*best, false)) : "–", with_one,
                          intervals);
      }
    }
  md += "\nSpeedup intervals containing 1, per class and batch over every scene:\n\n";
  for (auto& layout : classes)
    for (auto& batch : t.batches)
      if (auto it = totals.find({layout, batch}); it != totals.end() && it->second.first > 0)
        md += fmt::format("- {} {}: {} of {} ({:.0f} %)\n", layout, batch, it->second.second, it->second.first,
                          100.0 * it->second.second / it->second.first);
  return md + "\n";
}

// Embree's paths on the cells' orders (run --embree-paths; docs/measurement.md, "Embree on sorted
// orders"): per scene, batch and path, Embree's NoSort speed and what each encoder's order buys
// that path (paired, in the cell's own rounds), beside what it buys our trace class on the same
// cell. Shown when the cells hold Embree figures.
std::string embree_section(const TableContext& t, const nlohmann::json& meta) {
  std::vector<std::string> paths;
  for (auto& c : t.cells)
    for (auto& e : c.embree)
      if (std::find(paths.begin(), paths.end(), e.path) == paths.end()) paths.push_back(e.path);
  if (paths.empty()) return "";
  // What each arm ran: the calls, flags and threads meta.json records (the cells record them too).
  std::string how;
  const nlohmann::json em = meta.value("embree", nlohmann::json());
  if (em.is_object() && em.contains("paths") && em["paths"].is_array()) {
    for (const auto& p : em["paths"])
      if (p.is_object())
        how += fmt::format("{}`{}` {} / {} (context flag {})", how.empty() ? "" : "; ", p.value("path", "?"),
                           p.value("closest_hit", "?"), p.value("any_hit", "?"), p.value("context_flag", "?"));
    how = fmt::format("Embree {} on {} threads: {}.", em.value("version", "?"), em.value("threads", 0u), how);
  } else {
    for (auto& c : t.cells)
      for (auto& e : c.embree)
        if (how.find("`" + e.path + "`") == std::string::npos)
          how += fmt::format("{}`{}` {} ({} threads)", how.empty() ? "" : "; ", e.path, e.call, e.threads);
    how += ".";
  }
  std::string md;
  for (auto& access : t.accesses) {
    const View view = t.main_view.with_access(access);
    md += fmt::format(
        "## Embree on sorted orders, {}-bit keys, access {}\n\n"
        "Every cell's rounds also held, per Embree path, Embree tracing the batch in NoSort order and in the cell's "
        "sorted order ({}), each timed by its wall clock. Per encoder: the path's speedup on that order (NoSort / "
        "sorted, paired, [95 % interval]) · our trace class's ({}, {}) speedup on the same cell. *Italic*: the interval "
        "contains 1; \"= NoSort\": the sorted order is the NoSort order. {}\n\n",
        t.overview_bits, access,
        access == "permute" ? "the rays moved into sorted order on the host before the timed arm, then traced in "
                              "order"
                            : "traced through the order, so a packet or stream holds consecutive rays of it",
        view.layout, view.variant, how);
    std::vector<std::string> cols{"path", "Embree NoSort MRays/s"};
    for (auto& e : t.encoders)
      if (e != kBaselineEncoder) cols.push_back(e);
    md += header("scene / batch", cols);
    for (auto& s : t.scenes)
      for (auto& batch : t.batches)
        for (auto& path : paths) {
          // Embree's NoSort speed: the NoSort cell's arm, else the first sorted cell's.
          const CellRecord::EmbreeFigures* base = nullptr;
          std::uint64_t rays = 0;
          if (const CellRecord* n = t.at(view, s, batch, kBaselineEncoder, 0); n && n->ok())
            if ((base = n->embree_path(path))) rays = n->rays;
          std::string row;
          bool any = false;
          for (auto& e : t.encoders) {
            if (e == kBaselineEncoder) continue;
            const CellRecord* c = t.at(view, s, batch, e, t.overview_bits);
            const CellRecord::EmbreeFigures* f = c && c->ok() ? c->embree_path(path) : nullptr;
            if (!f) {
              row += c && !c->ok() ? " failed |" : " – |";
              continue;
            }
            any = true;
            if (!base) base = f, rays = c->rays;
            std::string speed = c->same_order_as_nosort ? "= NoSort" : interval_text(f->speedup);
            if (!c->same_order_as_nosort && f->speedup.contains(1.0)) speed = "*" + speed + "*";
            row += fmt::format(" {} · {} |", speed, speedup_text(*c, false));
          }
          if (!any && !base) continue;
          const double mrays = base && base->nosort.median_ms > 0 ? static_cast<double>(rays) / (base->nosort.median_ms * 1e3) : 0.0;
          md += fmt::format("| {} {} | {} | {} |{}\n", s, batch, path, base ? fmt::format("{:.2f}", mrays) : "–", row);
        }
    md += "\n";
  }
  return md;
}

// Pixel against shuffled baseline order (render/batches.h): the same rays, NoSort in generation
// order or in a fixed-seed shuffle (as atomic compaction leaves them). The baseline decides how much
// coherence an ordering can recover: every ratio here is against its own baseline.
std::string baselines_section(const TableContext& t) {
  std::set<std::string> baselines;
  for (auto& c : t.cells) baselines.insert(c.baseline);
  if (!baselines.count("pixel") || !baselines.count("shuffled")) return "";
  const View pv = t.main_view.with_baseline("pixel"), sv = t.main_view.with_baseline("shuffled");
  std::string md = fmt::format(
      "## Baseline order: pixel against shuffled, {}-bit keys, access {}\n\n"
      "Each cell against its own NoSort: the rays in generation (pixel) order, or shuffled by a fixed-seed "
      "permutation as a path tracer that compacts with atomics leaves them. Per encoder: speedup [95 % interval] "
      "and the SIMT model's lane-efficiency ratio (higher is better) · distinct-nodes-per-visit ratio (lower is "
      "better), against pixel | against shuffled. The NoSort row gives each baseline's MRays/s and its absolute "
      "lane efficiency · distinct nodes per visit; the two NoSort traces ran in different rounds.\n\n",
      t.overview_bits, t.main_view.access);
  auto model = [](const CellRecord* c, bool ratios) {
    if (!c || !c->ok()) return std::string("–");
    return ratios ? fmt::format("{:.2f} · {:.2f}", c->simt_lane_efficiency_ratio, c->simt_distinct_per_visit_ratio)
                  : fmt::format("{:.3f} · {:.3f}", c->simt_lane_efficiency, c->simt_distinct_per_visit);
  };
  for (auto& s : t.scenes)
    for (auto& batch : t.batches) {
      const CellRecord* pn = t.at(pv, s, batch, kBaselineEncoder, 0);
      const CellRecord* sn = t.at(sv, s, batch, kBaselineEncoder, 0);
      if (!pn || !sn) continue;
      md += fmt::format("### {} {}\n\n| encoder | speedup vs pixel | model vs pixel | speedup vs shuffled | model vs "
                        "shuffled |\n|---|---:|---:|---:|---:|\n",
                        s, batch);
      md += fmt::format("| nosort | {:.2f} MRays/s | {} | {:.2f} MRays/s | {} |\n", pn->trace_mrays, model(pn, false),
                        sn->trace_mrays, model(sn, false));
      for (auto& e : t.encoders) {
        if (e == kBaselineEncoder) continue;
        const CellRecord* pc = t.at(pv, s, batch, e, t.overview_bits);
        const CellRecord* sc = t.at(sv, s, batch, e, t.overview_bits);
        auto speed = [](const CellRecord* c) { return c && c->ok() ? speedup_text(*c, false) : std::string("–"); };
        md += fmt::format("| {} | {} | {} | {} | {} |\n", e, speed(pc), model(pc, true), speed(sc), model(sc, true));
      }
      md += "\n";
    }
  return md;
}

// HCC with direction information (paper appendix, Table 8): per scene, HCC at the overview key
// length, HCC_DIR at the same length (its cut has one bit per direction bit fewer), and HCC with
// one bit fewer. Shown when the set has HCC_DIR and HCC at both lengths.
std::string hcc_dir_section(const TableContext& t) {
  const unsigned b = t.overview_bits;
  if (b < 2 || std::find(t.bits.begin(), t.bits.end(), b - 1) == t.bits.end()) return "";
  if (std::find(t.encoders.begin(), t.encoders.end(), "hcc-dir") == t.encoders.end()) return "";
  std::string md;
  for (auto& access : t.accesses) {
    const View view = t.main_view.with_access(access);
    for (auto& batch : t.batches) {
      std::string rows;
      for (auto& s : t.scenes) {
        const std::vector<const CellRecord*> row{t.at(view, s, batch, "hcc", b), t.at(view, s, batch, "hcc-dir", b),
                                                 t.at(view, s, batch, "hcc", b - 1)};
        if (std::any_of(row.begin(), row.end(), [](const CellRecord* c) { return !c || !c->ok(); })) continue;
        const CellRecord* best = best_lane_efficiency(row);
        rows += fmt::format("| {} |", s);
        for (const CellRecord* c : row) rows += fmt::format(" {:.2f} ({}) |", c->trace_mrays, speed_and_lanes(*c, c == best));
        rows += "\n";
      }
      if (rows.empty()) continue;
      md += fmt::format("## HCC with direction information (paper appendix Table 8), {} rays, access {}: MRays/s "
                        "(speedup · SIMT lane-efficiency ratio)\n\n",
                        batch, access);
      md += header("scene", {fmt::format("HCC {}b", b), fmt::format("HCC_DIR {}b", b), fmt::format("HCC {}b", b - 1)});
      md += rows + "\nBold: the row's highest lane-efficiency ratio.\n\n";
    }
  }
  return md;
}

// Subsequent bounces (paper appendix, "Reflection ray trace performance"): per scene, each
// encoder's speedup and SIMT lane-efficiency ratio at bounce 1, 2, 3 ..., under the ray count of
// each bounce. Shown when the set has two or more bounce batches.
std::string bounces_section(const TableContext& t) {
  std::vector<std::string> bounces;
  for (auto& batch : t.batches)
    if (batch.rfind("bounce", 0) == 0) bounces.push_back(batch);
  if (bounces.size() < 2) return "";
  std::string md;
  for (auto& access : t.accesses) {
    const View view = t.main_view.with_access(access);
    for (auto& s : t.scenes) {
      md += fmt::format("## Subsequent bounces, {}, {}-bit keys, access {}: speedup · SIMT lane-efficiency ratio "
                        "(paper appendix)\n\n",
                        s, t.overview_bits, access);
      md += header("encoder", bounces);
      md += "| rays |";
      for (auto& batch : bounces) {
        auto* n = t.at(view, s, batch, kBaselineEncoder, 0);
        md += n ? fmt::format(" {} |", n->rays) : " – |";
      }
      md += "\n";
      std::map<std::string, const CellRecord*> best;
      for (auto& batch : bounces) {
        std::vector<const CellRecord*> column;
        for (auto& e : t.encoders) column.push_back(t.at(view, s, batch, e, t.overview_bits));
        best[batch] = best_lane_efficiency(column);
      }
      for (auto& e : t.encoders) {
        if (e == kBaselineEncoder) continue;
        md += fmt::format("| {} |", e);
        for (auto& batch : bounces) {
          auto* c = t.at(view, s, batch, e, t.overview_bits);
          md += !c ? " – |" : !c->ok() ? " failed |" : fmt::format(" {} |", speed_and_lanes(*c, c == best[batch]));
        }
        md += "\n";
      }
      md += "\nBold: the column's highest lane-efficiency ratio.\n\n";
    }
  }
  return md;
}

std::string failed_section(const std::vector<CellRecord>& cells) {
  std::vector<const CellRecord*> failed;
  for (auto& c : cells)
    if (!c.ok()) failed.push_back(&c);
  std::string md = fmt::format("## Failed cells: {}\n\n", failed.size());
  for (auto* c : failed) md += fmt::format("- `{}`: {} — {}\n", c->id(), c->status, one_line(c->error));
  if (!failed.empty()) md += "\n";
  return md;
}

}  // namespace

std::string render_tables(const std::vector<CellRecord>& cells, const nlohmann::json& meta) {
  const TableContext t(cells, meta);
  return introduction(meta) + encoder_files_section(meta) + noise_section(cells) + trace_speed_sections(t) + overhead_sections(t) +
         gather_permute_section(t) + key_length_sections(t) + deterministic_sections(t) + hcc_dir_section(t) +
         bounces_section(t) + top_k_section(t) + variants_section(t) + classes_section(t) + embree_section(t, meta) +
         baselines_section(t) + failed_section(cells);
}

}  // namespace raysort
