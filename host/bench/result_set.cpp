#include "bench/result_set.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>

#include "bench/plots.h"
#include "util/atomic_file.h"
#include "util/error.h"

namespace raysort {

namespace fs = std::filesystem;

namespace {

std::string cell_file_name(const std::string& id) {
  std::string s;
  for (char c : id) s += (c == '/') ? std::string("__") : std::string(1, c);
  return s + ".json";
}

// Reading accepts every version this raysort knows (older sets stay comparable); a run resumes
// only into a set of the current version (for_run).
void check_version(const nlohmann::json& meta, const std::string& path, bool for_run) {
  int v = meta.value("format_version", 0);
  if (for_run && v != kResultFormatVersion)
    throw Error(fmt::format("{}: result format version {} but this raysort writes version {}; "
                            "run into a new --out folder, or resume with the raysort that wrote it",
                            path, v, kResultFormatVersion));
  if (v < kOldestReadableFormatVersion || v > kResultFormatVersion)
    throw Error(fmt::format("{}: result format version {} but this raysort reads versions {} to {}; "
                            "rerun with this version into a new --out folder, or use the raysort that wrote it",
                            path, v, kOldestReadableFormatVersion, kResultFormatVersion));
}

void read_cells(const std::string& dir, std::map<std::string, CellRecord>& cells) {
  fs::path cdir = fs::path(dir) / "cells";
  if (!fs::exists(cdir)) return;
  for (const auto& entry : fs::directory_iterator(cdir)) {
    const auto& p = entry.path();
    if (p.extension() != ".json") continue;  // leftover *.tmp.<pid> files of a killed run are ignored
    try {
      auto j = nlohmann::json::parse(read_file(p.string()));
      CellRecord r = j.get<CellRecord>();
      cells[r.id()] = r;
    } catch (const Error&) {
      throw;
    } catch (const std::exception& e) {
      throw Error(fmt::format("{}: unreadable cell record ({}); delete the file to rerun that cell", p.string(), e.what()));
    }
  }
}

// "i/N" of a shard's meta.json, or "" for a full run.
std::string shard_name(const nlohmann::json& meta) {
  if (!meta.contains("shard")) return "";
  return fmt::format("{}/{}", meta["shard"].value("index", 0u), meta["shard"].value("count", 0u));
}

// A shard resumes only into its own folder, with the same plan (bench/shard.h).
void check_same_shard(const nlohmann::json& old, const nlohmann::json& meta, const std::string& dir) {
  const std::string was = shard_name(old), now = shard_name(meta);
  if (was == now) {
    if (!was.empty() && old["shard"].value("plan_hash", "") != meta["shard"].value("plan_hash", ""))
      throw Error(fmt::format("{} holds shard {} of another plan of this matrix (the scene files changed since it "
                              "started); choose another --out folder (or delete it to start over)",
                              dir, was));
    return;
  }
  if (was.empty())
    throw Error(fmt::format("{} holds a full (unsharded) run of this matrix, not shard {}; give each shard its own "
                            "--out folder",
                            dir, now));
  if (now.empty())
    throw Error(fmt::format("{} holds shard {} of this matrix; resume it with --shard {}, or choose another --out "
                            "folder for a full run",
                            dir, was, was));
  throw Error(fmt::format("{} holds shard {} of this matrix, not shard {}; give each shard its own --out folder", dir,
                          was, now));
}

}  // namespace

ResultSet ResultSet::open_for_run(const std::string& dir, const nlohmann::json& meta) {
  ResultSet rs;
  rs.dir_ = dir;
  rs.meta_ = meta;
  fs::path meta_path = fs::path(dir) / "meta.json";
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "cells", ec);
  if (ec) throw Error(fmt::format("cannot create result folder '{}': {}", dir, ec.message()));
  if (fs::exists(meta_path)) {
    nlohmann::json old;
    try {
      old = nlohmann::json::parse(read_file(meta_path.string()));
    } catch (const nlohmann::json::exception& e) {
      throw Error(fmt::format("{}: not valid JSON ({}); choose another --out folder", meta_path.string(), e.what()));
    }
    check_version(old, meta_path.string(), true);
    if (old.value("matrix", nlohmann::json()) != meta.value("matrix", nlohmann::json()))
      throw Error(fmt::format("{} holds results of a different matrix configuration; choose another --out folder "
                              "(or delete it to start over)",
                              dir));
    check_same_shard(old, meta, dir);
    read_cells(dir, rs.cells_);
    // Keep the original meta (first start), but record that the run was resumed.
    rs.meta_ = old;
    rs.meta_["resumed"] = rs.meta_.value("resumed", 0) + 1;
  }
  write_file_atomically(meta_path.string(), rs.meta_.dump(2) + "\n");
  return rs;
}

ResultSet ResultSet::load(const std::string& dir) {
  fs::path meta_path = fs::path(dir) / "meta.json";
  if (!fs::exists(meta_path)) throw Error(fmt::format("'{}' is not a result set (no meta.json)", dir));
  ResultSet rs;
  rs.dir_ = dir;
  try {
    rs.meta_ = nlohmann::json::parse(read_file(meta_path.string()));
  } catch (const nlohmann::json::exception& e) {
    throw Error(fmt::format("{}: not valid JSON ({})", meta_path.string(), e.what()));
  }
  check_version(rs.meta_, meta_path.string(), false);
  read_cells(dir, rs.cells_);
  return rs;
}

const CellRecord* ResultSet::find(const std::string& id) const {
  auto it = cells_.find(id);
  return it == cells_.end() ? nullptr : &it->second;
}

void ResultSet::add(const CellRecord& cell) {
  nlohmann::json j = cell;
  write_file_atomically((fs::path(dir_) / "cells" / cell_file_name(cell.id())).string(), j.dump(2) + "\n");
  cells_[cell.id()] = cell;
  write_views();
}

void ResultSet::add_all(const std::vector<CellRecord>& cells) {
  for (const auto& cell : cells) {
    nlohmann::json j = cell;
    write_file_atomically((fs::path(dir_) / "cells" / cell_file_name(cell.id())).string(), j.dump(2) + "\n");
    cells_[cell.id()] = cell;
  }
  write_views();
}

void ResultSet::set_meta(const std::string& key, const nlohmann::json& value) {
  meta_[key] = value;
  write_views();  // rewrites meta.json
}

std::vector<CellRecord> ResultSet::cells() const {
  std::vector<CellRecord> out;
  for (auto& [id, c] : cells_) out.push_back(c);
  return out;
}

void ResultSet::write_views() const {
  auto all = cells();
  nlohmann::json arr = nlohmann::json::array();
  std::string csv = csv_header() + "\n";
  for (auto& c : all) {
    arr.push_back(c);
    csv += csv_row(c) + "\n";
  }
  write_file_atomically((fs::path(dir_) / "cells.json").string(), arr.dump(2) + "\n");
  // meta.json carries a fingerprint of every cell's keys and order, so two devices (or commits) can
  // be checked for identical encodings at a glance (`raysort compare --fail-if keys_hash!=` per cell).
  nlohmann::json meta = meta_;
  nlohmann::json fingerprints = nlohmann::json::object();
  for (auto& c : all) fingerprints[c.id()] = {{"keys", c.keys_hash}, {"order", c.order_hash}};
  meta["fingerprints"] = fingerprints;
  meta["noise"] = summarize_noise(all).to_json();
  write_file_atomically((fs::path(dir_) / "meta.json").string(), meta.dump(2) + "\n");
  write_file_atomically((fs::path(dir_) / "cells.csv").string(), csv);
  write_file_atomically((fs::path(dir_) / "tables.md").string(), render_tables(all, meta_));
}

void ResultSet::write_plots() const { raysort::write_plots(cells(), dir_); }

NoiseSummary summarize_noise(const std::vector<CellRecord>& cells) {
  NoiseSummary n;
  std::map<std::string, const CellRecord*> by_id;
  for (const auto& c : cells) by_id[c.id()] = &c;
  std::vector<double> widths;
  std::vector<unsigned> rounds;
  for (const auto& c : cells) {
    if (!c.ok() || c.rounds == 0) continue;
    // A permute cell measured in the rounds of its gather sibling repeats that cell's A/A interval.
    bool shared_rounds = false;
    if (c.access == "permute") {
      CellRecord sibling = c;
      sibling.access = "gather";
      auto it = by_id.find(sibling.id());
      shared_rounds = it != by_id.end() && it->second->ok() && it->second->samples.count("nosort") &&
                      c.samples.count("nosort") && it->second->samples.at("nosort") == c.samples.at("nosort");
    }
    if (!shared_rounds) {
      rounds.push_back(c.rounds);
      n.stopped_by_noise += c.stopped_by == "noise";
      n.stopped_by_time += c.stopped_by == "time";
      n.stopped_by_rounds += c.stopped_by == "rounds";
      if (c.aa.has_interval()) {
        ++n.aa_intervals;
        n.aa_containing_one += c.aa.contains(1.0);
      }
    }
    if (c.encoder == kBaselineEncoder) continue;
    if (c.same_order_as_nosort) {
      ++n.same_order_cells;
      continue;
    }
    if (c.speedup.has_interval()) {
      ++n.cells_with_interval;
      widths.push_back(c.speedup.relative_half_width());
      n.speedups_containing_one += c.speedup.contains(1.0);
    }
  }
  auto quantile = [](std::vector<double> v, double q) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5))];
  };
  n.median_half_width = quantile(widths, 0.5);
  n.p90_half_width = quantile(widths, 0.9);
  n.max_half_width = widths.empty() ? 0.0 : *std::max_element(widths.begin(), widths.end());
  if (!rounds.empty()) {
    std::sort(rounds.begin(), rounds.end());
    n.median_rounds = rounds[rounds.size() / 2];
    n.min_rounds = rounds.front();
    n.max_rounds = rounds.back();
  }
  return n;
}

nlohmann::json NoiseSummary::to_json() const {
  return {{"aa_intervals", aa_intervals},
          {"aa_containing_one", aa_containing_one},
          {"aa_coverage", aa_coverage()},
          {"cells_with_interval", cells_with_interval},
          {"speedup_half_width", {{"median", median_half_width}, {"p90", p90_half_width}, {"max", max_half_width}}},
          {"rounds", {{"median", median_rounds}, {"min", min_rounds}, {"max", max_rounds}}},
          {"stopped_by", {{"noise", stopped_by_noise}, {"time", stopped_by_time}, {"rounds", stopped_by_rounds}}},
          {"same_order_cells", same_order_cells},
          {"speedups_containing_one", speedups_containing_one}};
}

}  // namespace raysort
