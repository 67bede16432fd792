// The paper's tables laid out as in the paper, from cell records only (DESIGN.md section 3):
//   trace speed with the ratio to NoSort in parentheses, best per column in bold (Tables 2-4);
//   overhead: encode/sort ms, share of trace time and net speedup (Table 5);
//   key length: speed and ANC against key bits (Tables 6-7); the SIMT model; failed cells.
#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <set>

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

// The variant the main tables show (the first one the matrix lists); a robust-vs-fast section
// compares the variants when a run has both.
std::string g_main_variant;

const CellRecord* find(const std::vector<CellRecord>& cells, const std::string& scene, const std::string& batch,
                       const std::string& encoder, unsigned bits, const std::string& variant = g_main_variant) {
  for (auto& c : cells)
    if (c.scene == scene && c.batch == batch && c.encoder == encoder && c.top_bits == 0 && c.variant == variant &&
        (c.encoder == kBaselineEncoder || c.bits == bits))
      return &c;
  return nullptr;
}

std::string bold_if(bool b, const std::string& s) { return b ? fmt::format("**{}**", s) : s; }

std::string header(const std::string& first, const std::vector<std::string>& cols) {
  std::string h = fmt::format("| {} |", first), sep = "|---|";
  for (auto& c : cols) {
    h += fmt::format(" {} |", c);
    sep += "---:|";
  }
  return h + "\n" + sep + "\n";
}

}  // namespace

std::string render_tables(const std::vector<CellRecord>& cells, const nlohmann::json& meta) {
  std::string md = "# raysort results\n\n";
  if (meta.contains("device"))
    md += fmt::format("Device: {} ({}, driver {}). ", meta["device"].value("name", "?"), meta["device"].value("platform", "?"),
                      meta["device"].value("driver", "?"));
  if (meta.contains("matrix"))
    md += fmt::format("Resolution {}, {} spp, {} repetitions after {} warm-up; trace variant {}.\n\n",
                      meta["matrix"].value("resolution", "?"), meta["matrix"].value("spp", 0),
                      meta["matrix"].value("reps", 0), meta["matrix"].value("warmup", 0),
                      meta["matrix"].value("variant", "robust"));
  md += "Times are medians of OpenCL profiling events. Speedup = NoSort trace time / trace time on the same batch; "
        "net = NoSort trace / (encode + sort + trace). A cell whose sorted trace does not reproduce the NoSort hits "
        "exactly is listed under failed cells and has no speed.\n\n";

  g_main_variant = cells.empty() ? std::string("robust") : cells.front().variant;
  if (meta.contains("matrix") && meta["matrix"].contains("variant")) {
    std::string v = meta["matrix"]["variant"].get<std::string>();
    g_main_variant = v.substr(0, v.find(','));
  }
  auto scenes = ordered(cells, meta, "scenes", &CellRecord::scene);
  auto batches = ordered(cells, meta, "batches", &CellRecord::batch);
  auto encoders = ordered(cells, meta, "encoders", &CellRecord::encoder);
  std::set<unsigned> bit_set;
  for (auto& c : cells)
    if (c.encoder != kBaselineEncoder && c.top_bits == 0) bit_set.insert(c.bits);
  std::vector<unsigned> bits(bit_set.begin(), bit_set.end());
  const unsigned overview_bits = bit_set.count(32) ? 32 : (bits.empty() ? 0 : bits.back());

  // Trace speed per batch (Tables 2-4).
  for (auto& batch : batches) {
    md += fmt::format("## Trace speed, {} rays, {}-bit keys: MRays/s (speedup vs NoSort)\n\n", batch, overview_bits);
    md += header("encoder", scenes);
    std::map<std::string, double> best;
    for (auto& s : scenes)
      for (auto& e : encoders)
        if (auto* c = find(cells, s, batch, e, overview_bits); c && c->ok()) best[s] = std::max(best[s], c->trace_mrays);
    for (auto& e : encoders) {
      md += fmt::format("| {} |", e);
      for (auto& s : scenes) {
        auto* c = find(cells, s, batch, e, overview_bits);
        if (!c) md += " – |";
        else if (!c->ok()) md += " failed |";
        else
          md += fmt::format(" {} |", bold_if(c->trace_mrays == best[s], fmt::format("{:.2f} ({:.2f})", c->trace_mrays, c->speedup)));
      }
      md += "\n";
    }
    md += "\n";
  }

  // Overhead (Table 5).
  for (auto& batch : batches) {
    md += fmt::format("## Overhead, {} rays, {}-bit keys: encode + sort ms (% of trace) → net speedup\n\n", batch,
                      overview_bits);
    md += header("encoder", scenes);
    for (auto& e : encoders) {
      if (e == kBaselineEncoder) continue;
      md += fmt::format("| {} |", e);
      for (auto& s : scenes) {
        auto* c = find(cells, s, batch, e, overview_bits);
        if (!c) md += " – |";
        else if (!c->ok()) md += " failed |";
        else
          md += fmt::format(" {:.2f} + {:.2f} ({:.0f}%) → {:.2f} |", c->encode.median_ms, c->sort.median_ms, c->overhead_pct,
                            c->net_speedup);
      }
      md += "\n";
    }
    md += "\n";
  }

  // Key length (Tables 6 and 7): per scene and batch, when several key lengths ran.
  if (bits.size() > 1) {
    std::vector<std::string> bit_cols;
    for (auto b : bits) bit_cols.push_back(fmt::format("{} bits", b));
    for (auto& s : scenes)
      for (auto& batch : batches) {
        bool any = false;
        for (auto& e : encoders)
          for (auto b : bits) any |= find(cells, s, batch, e, b) && e != kBaselineEncoder;
        if (!any) continue;
        md += fmt::format("## Key length, {} {}: MRays/s (speedup) | ANC\n\n", s, batch);
        md += header("encoder", bit_cols);
        for (auto& e : encoders) {
          if (e == kBaselineEncoder) continue;
          md += fmt::format("| {} |", e);
          for (auto b : bits) {
            auto* c = find(cells, s, batch, e, b);
            if (!c) md += " – |";
            else if (!c->ok()) md += " failed |";
            else md += fmt::format(" {:.2f} ({:.2f}) \\| {:.2f} |", c->trace_mrays, c->speedup, c->anc);
          }
          md += "\n";
        }
        md += "\n";
      }
  }

  // ANC table (Table 7) at every key length, all scenes.
  md += "## ANC: average number of distinct keys per 32 consecutive sorted rays\n\n";
  {
    std::vector<std::string> cols;
    for (auto& s : scenes)
      for (auto& batch : batches)
        for (auto b : bits) cols.push_back(fmt::format("{} {} {}b", s, batch, b));
    md += header("encoder", cols);
    for (auto& e : encoders) {
      if (e == kBaselineEncoder) continue;
      md += fmt::format("| {} |", e);
      for (auto& s : scenes)
        for (auto& batch : batches)
          for (auto b : bits) {
            auto* c = find(cells, s, batch, e, b);
            md += c && c->ok() ? fmt::format(" {:.2f} |", c->anc) : " – |";
          }
      md += "\n";
    }
    md += "\n";
  }

  // SIMT model.
  md += fmt::format(
      "## SIMT model, {}-bit keys: lane efficiency (ratio vs NoSort) / distinct nodes per visit (ratio vs NoSort)\n\n"
      "Device-independent: what a 32-wide GPU warp would see in this trace order (DESIGN.md §3).\n\n",
      overview_bits);
  {
    std::vector<std::string> cols;
    for (auto& s : scenes)
      for (auto& batch : batches) cols.push_back(s + " " + batch);
    md += header("encoder", cols);
    for (auto& e : encoders) {
      md += fmt::format("| {} |", e);
      for (auto& s : scenes)
        for (auto& batch : batches) {
          auto* c = find(cells, s, batch, e, overview_bits);
          md += c && c->ok() ? fmt::format(" {:.3f} ({:.2f}) / {:.3f} ({:.2f}) |", c->simt_lane_efficiency,
                                           c->simt_lane_efficiency_ratio, c->simt_distinct_per_visit,
                                           c->simt_distinct_per_visit_ratio)
                             : " – |";
        }
      md += "\n";
    }
    md += "\n";
  }

  // Top-k sorting, when run.
  bool any_topk = std::any_of(cells.begin(), cells.end(), [](const CellRecord& c) { return c.top_bits > 0; });
  if (any_topk) {
    md += "## Top-k sorting: sort by the highest k key bits only\n\n";
    md += "| cell | sort ms | trace MRays/s (speedup) | net | ANC |\n|---|---:|---:|---:|---:|\n";
    for (auto& c : cells)
      if (c.top_bits > 0 && c.ok())
        md += fmt::format("| {} | {:.2f} | {:.2f} ({:.2f}) | {:.2f} | {:.2f} |\n", c.id(), c.sort.median_ms, c.trace_mrays,
                          c.speedup, c.net_speedup, c.anc);
    md += "\n";
  }

  // Robust vs fast (issue 7): what watertightness costs, and what the fast variant leaks.
  std::set<std::string> variants;
  for (auto& c : cells) variants.insert(c.variant);
  if (variants.count("robust") && variants.count("fast")) {
    md += "## Robust vs fast trace: what watertight intersection costs\n\n"
          "NoSort trace MRays/s of each variant on the same rays, their ratio, and leaks per million rays "
          "(rays the variant misses that the other one hits: the fast variant's leaks through shared edges and "
          "vertices). Best = the best encoder's speedup at the overview key length in that variant.\n\n"
          "| scene | batch | fast MRays/s | robust MRays/s | robust/fast | fast leaks/M | robust leaks/M | best fast | best robust |\n"
          "|---|---|---:|---:|---:|---:|---:|---|---|\n";
    for (auto& s : scenes)
      for (auto& batch : batches) {
        auto* f = find(cells, s, batch, kBaselineEncoder, 0, "fast");
        auto* r = find(cells, s, batch, kBaselineEncoder, 0, "robust");
        if (!f || !r || !f->ok() || !r->ok()) continue;
        auto best = [&](const std::string& v) {
          const CellRecord* b = nullptr;
          for (auto& e : encoders)
            if (auto* c = find(cells, s, batch, e, overview_bits, v); c && c->ok() && e != kBaselineEncoder)
              if (!b || c->speedup > b->speedup) b = c;
          return b ? fmt::format("{} {:.2f}", b->encoder, b->speedup) : std::string("–");
        };
        md += fmt::format("| {} | {} | {:.2f} | {:.2f} | {:.3f} | {:.1f} | {:.1f} | {} | {} |\n", s, batch, f->trace_mrays,
                          r->trace_mrays, f->trace_mrays > 0 ? r->trace_mrays / f->trace_mrays : 0.0, f->leaks_per_million,
                          r->leaks_per_million, best("fast"), best("robust"));
      }
    md += "\n";
  }

  std::vector<const CellRecord*> failed;
  for (auto& c : cells)
    if (!c.ok()) failed.push_back(&c);
  md += fmt::format("## Failed cells: {}\n\n", failed.size());
  for (auto* c : failed) md += fmt::format("- `{}`: {} — {}\n", c->id(), c->status, c->error);
  if (!failed.empty()) md += "\n";
  return md;
}

}  // namespace raysort
