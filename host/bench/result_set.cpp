#include "bench/result_set.h"

#include <fmt/format.h>

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

void check_version(const nlohmann::json& meta, const std::string& path) {
  int v = meta.value("format_version", 0);
  if (v != kResultFormatVersion)
    throw Error(fmt::format("{}: result format version {} but this raysort reads version {}; "
                            "rerun with this version into a new --out folder, or use the raysort that wrote it",
                            path, v, kResultFormatVersion));
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
    check_version(old, meta_path.string());
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
  check_version(rs.meta_, meta_path.string());
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
  write_file_atomically((fs::path(dir_) / "meta.json").string(), meta.dump(2) + "\n");
  write_file_atomically((fs::path(dir_) / "cells.csv").string(), csv);
  write_file_atomically((fs::path(dir_) / "tables.md").string(), render_tables(all, meta_));
}

void ResultSet::write_plots() const { raysort::write_plots(cells(), dir_); }

}  // namespace raysort
