#include "bench/result_set.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <set>

#include "bench/encoder_files.h"
#include "bench/plots.h"
#include "bench/record_columns.h"
#include "scene/provenance.h"
#include "util/atomic_file.h"
#include "util/error.h"
#include "util/text.h"

namespace raysort {

namespace fs = std::filesystem;

namespace {

// A character that stands for itself in a cell file name; anything else is %XX. '_' stands for
// itself only alone inside a part (never first, last or beside another '_'), so "__" always
// separates the id's parts and no two ids share a name.
bool plain_in_file_name(const std::string& part, std::size_t i) {
  const char c = part[i];
  if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '.') return true;
  return c == '_' && i > 0 && i + 1 < part.size() && part[i - 1] != '_' && part[i + 1] != '_';
}

// File names stay well below NAME_MAX (255 bytes) with room for write_file_atomically's suffix.
constexpr std::size_t kMaxCellFileStem = 180;

}  // namespace

std::string cell_file_name(const std::string& id) {
  std::string stem;
  std::vector<std::string> parts{""};
  for (char c : id) {
    if (c == '/') parts.emplace_back();
    else parts.back().push_back(c);
  }
  for (std::size_t p = 0; p < parts.size(); ++p) {
    const std::string& part = parts[p];
    if (p > 0) stem += "__";
    for (std::size_t i = 0; i < part.size(); ++i)
      stem += plain_in_file_name(part, i) ? std::string(1, part[i])
                                          : fmt::format("%{:02X}", static_cast<unsigned char>(part[i]));
  }
  if (stem.size() > kMaxCellFileStem) {
    // A long id (a scene given by a long path): its start, then '~' (never plain, so no short name
    // has one) and the FNV-1a hash of the whole id; the record inside names the cell in full.
    std::size_t cut = kMaxCellFileStem - 17;
    if (stem[cut - 1] == '%') cut -= 1;  // never split a %XX escape
    else if (stem[cut - 2] == '%') cut -= 2;
    stem = stem.substr(0, cut) + "~" + fnv1a_hex(id.data(), id.size());
  }
  return stem + ".json";
}

std::string legacy_cell_file_name(const std::string& id) {
  std::string s;
  for (char c : id) s += (c == '/') ? std::string("__") : std::string(1, c);
  return s + ".json";
}

namespace {

// Reading accepts every version this raysort knows (older sets stay comparable); a run resumes
// only into a set of the current version (for_run).
void check_version(const nlohmann::json& meta, const std::string& path, bool for_run) {
  // check_meta_shape has made it a count when present.
  const std::uint64_t v = meta.contains("format_version") ? meta["format_version"].get<std::uint64_t>() : 0;
  if (for_run && v != kResultFormatVersion)
    throw Error(fmt::format("{}: result format version {} but this raysort writes version {}; "
                            "run into a new --out folder, or resume with the raysort that wrote it",
                            path, v, kResultFormatVersion));
  if (v < kOldestReadableFormatVersion || v > kResultFormatVersion)
    throw Error(fmt::format("{}: result format version {} but this raysort reads versions {} to {}; "
                            "rerun with this version into a new --out folder, or use the raysort that wrote it",
                            path, v, kOldestReadableFormatVersion, kResultFormatVersion));
}

// The files a result set's writer writes at its top level (util/atomic_file.h).
constexpr const char* kSetFiles[] = {"meta.json", "cells.json", "cells.csv", "tables.md"};

// A leftover of write_file_atomically (util/atomic_file.h: "meta.json.tmp.<pid>") from a writer that
// was killed mid-write: of one of the set's own files, or in cells/ of a cell file. A user's file
// ("analysis.tmp.notes") is never one.
bool is_temporary_file(const fs::path& p, bool in_cells) {
  const std::string name = p.filename().string();
  const std::size_t at = name.rfind(".tmp.");
  if (at == std::string::npos) return false;
  const std::string target = name.substr(0, at);
  if (!is_temporary_file_of(name, target)) return false;
  if (in_cells) return target.size() > 5 && target.ends_with(".json");
  return std::find(std::begin(kSetFiles), std::end(kSetFiles), target) != std::end(kSetFiles);
}

// meta.json is read by resume, compare, merge and the views: every entry they read must have the
// type they read it as, or one Error names the entry (not a json exception deep in a reader).
void check_meta_shape(const nlohmann::json& meta, const std::string& path) {
  if (!meta.is_object())
    throw Error(fmt::format("{}: not a result set's meta.json (a JSON object), but a JSON {}; restore the file, or "
                            "choose another folder",
                            path, meta.type_name()));
  enum Kind { Count, Text, Object, List };
  auto expect = [&](const nlohmann::json& obj, const std::string& where, const char* key, Kind kind) {
    if (!obj.contains(key)) return;
    const nlohmann::json& v = obj[key];
    const bool ok = kind == Count ? v.is_number_unsigned() : kind == Text ? v.is_string() : kind == Object ? v.is_object()
                                                                                                         : v.is_array();
    if (!ok)
      throw Error(fmt::format("{}: \"{}{}\" is a JSON {}, not {}; restore the file (it was edited or damaged)", path,
                              where, key, v.type_name(),
                              kind == Count ? "a count" : kind == Text ? "a string" : kind == Object ? "an object" : "a list"));
  };
  expect(meta, "", "format_version", Count);
  expect(meta, "", "matrix", Object);
  expect(meta, "", "device", Object);
  expect(meta, "", "shard", Object);
  expect(meta, "", "absent_cells", List);
  expect(meta, "", "merged_from", List);
  expect(meta, "", "resumed", Count);
  expect(meta, "", "kernels", Object);
  if (meta.contains("kernels"))
    for (const char* key : {"source", "hash", "cl_options"}) expect(meta["kernels"], "kernels.", key, Text);
  for (const char* key : {"git_commit", "raysort_version", "command", "date", "host_cpu"}) expect(meta, "", key, Text);
  expect(meta, "", "encoder_files", Object);
  if (meta.contains("encoder_files"))
    for (const auto& [name, file] : meta["encoder_files"].items()) {
      const std::string where = "encoder_files." + name;
      if (!file.is_object())
        throw Error(fmt::format("{}: \"{}\" is a JSON {}, not an object; restore the file (it was edited or damaged)",
                                path, where, file.type_name()));
      for (const char* key : {"path", "sha256"}) expect(file, where + ".", key, Text);
    }
  if (meta.contains("device"))
    for (const char* key : {"name", "type", "platform", "platform_version", "opencl", "opencl_c", "driver", "slug"})
      expect(meta["device"], "device.", key, Text);
  if (meta.contains("shard")) {
    const nlohmann::json& shard = meta["shard"];
    for (const char* key : {"index", "count", "cells"}) expect(shard, "shard.", key, Count);
    expect(shard, "shard.", "plan_hash", Text);
    expect(shard, "shard.", "plan", Object);
    if (shard.contains("plan"))
      for (const auto& [id, index] : shard["plan"].items())
        if (!index.is_number_unsigned())
          throw Error(fmt::format("{}: shard.plan[\"{}\"] is not a shard number; restore the file", path, id));
  }
  if (meta.contains("absent_cells"))
    for (const auto& id : meta["absent_cells"])
      if (!id.is_string()) throw Error(fmt::format("{}: absent_cells holds a {}, not a cell id; restore the file", path, id.type_name()));
}

}  // namespace

CellRecord parse_cell_record(const std::string& text, const std::string& file, const nlohmann::json& matrix) {
  const std::string fix = "delete the file to rerun that cell";
  CellRecord r;
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
    r = j.get<CellRecord>();
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(fmt::format("{}: unreadable cell record ({}); {}", file, e.what(), fix));
  }
  const std::string id = r.id();
  // A cell of another class than wide written before the class was an axis names itself without it.
  const std::string old_id = r.id_before_class_axis();
  if (j.contains("id") && j["id"] != id && j["id"] != old_id)
    throw Error(fmt::format("{}: its \"id\" is {} but its fields make cell {}; {}", file, j["id"].dump(), id, fix));
  const std::string name = fs::path(file).filename().string();
  // Its own name, or the name an older raysort gave it: before ids were escaped ("/" became "__"
  // and nothing else changed), or before the trace class was an axis.
  auto named = [&](const std::string& cell) { return name == cell_file_name(cell) || name == legacy_cell_file_name(cell); };
  if (!named(id) && !(old_id != id && named(old_id) && j.value("id", old_id) == old_id))
    throw Error(fmt::format("{} holds cell {}, whose file is {}: a cell file names its cell (an edited or copied "
                            "record); {}",
                            file, id, cell_file_name(id), fix));
  if (std::string problem = cell_record_problem(r); !problem.empty())
    throw Error(fmt::format("{}: cell {}: {}; {}", file, id, problem, fix));
  if (std::string outside = cell_outside_matrix(r, matrix); !outside.empty())
    throw Error(fmt::format("{}: cell {} is outside the matrix of this result set ({}); {}", file, id, outside, fix));
  return r;
}

nlohmann::json parse_meta(const std::string& text, const std::string& path) {
  nlohmann::json meta;
  try {
    meta = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw Error(fmt::format("{}: not valid JSON ({}); restore the file, or choose another folder", path, e.what()));
  }
  check_meta_shape(meta, path);
  return meta;
}

namespace {

// One cell file: the record it holds, the cell its name says, valid and inside the set's matrix.
CellRecord read_cell_file(const fs::path& p, const nlohmann::json& matrix) {
  std::error_code ec;
  if (!fs::is_regular_file(p, ec))
    throw Error(fmt::format("{}: not a cell record (not a regular file); remove it", p.string()));
  return parse_cell_record(read_file(p.string()), p.string(), matrix);
}

void read_cells(const std::string& dir, const nlohmann::json& meta, std::map<std::string, CellRecord>& cells) {
  const fs::path cdir = fs::path(dir) / "cells";
  std::error_code ec;
  if (!fs::exists(cdir, ec)) return;
  if (!fs::is_directory(cdir, ec))
    throw Error(fmt::format("{}: not a folder, so {} is not a result set (its cells live in cells/); restore it, or "
                            "choose another folder",
                            cdir.string(), dir));
  const nlohmann::json matrix = meta.value("matrix", nlohmann::json());
  std::vector<fs::path> files;
  for (fs::directory_iterator it(cdir, ec), end; !ec && it != end; it.increment(ec))
    if (it->path().extension() == ".json") files.push_back(it->path());  // *.tmp.<pid> leftovers are not cells
  if (ec) throw Error(fmt::format("cannot list {}: {}", cdir.string(), ec.message()));
  std::sort(files.begin(), files.end());  // the first error found is the same on every machine
  for (const auto& p : files) {
    CellRecord r = read_cell_file(p, matrix);
    const std::string id = r.id();
    if (!cells.emplace(id, std::move(r)).second)  // unreachable while names are checked; kept as the invariant
      throw Error(fmt::format("{}: a second file holds cell {}; delete one of them", p.string(), id));
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

// A resumed set's new cells must be measured as its first ones were: on the same device and driver,
// by the same raysort build, from the same kernels with the same build options. A set started
// before an entry was recorded is not checked on it.
void check_same_build(const nlohmann::json& old, const nlohmann::json& meta, const std::string& dir) {
  std::vector<std::string> diffs;
  auto compare = [&](const char* key, const char* what) {
    if (!old.contains(key) || !meta.contains(key) || old[key] == meta[key]) return;
    const std::string d = old[key].is_object() && meta[key].is_object() ? json_differences(old[key], meta[key])
                                                                         : fmt::format("{} vs {}", old[key].dump(), meta[key].dump());
    diffs.push_back(fmt::format("{} ({})", what, d));
  };
  compare("device", "device");
  compare("raysort_version", "raysort version");
  compare("git_commit", "commit");
  compare("kernels", "kernels");
  if (diffs.empty()) return;
  std::string list;
  for (const auto& d : diffs) list += (list.empty() ? "" : "; ") + d;
  throw Error(fmt::format("{}: what it was started with differs from now: {} (then vs now); its cells and new ones "
                          "would not be comparable: resume it with the same device, build, kernels and "
                          "RAYSORT_CL_OPTIONS, or choose another --out folder",
                          dir, list));
}

}  // namespace

namespace {

// The entries of a folder that are not a writer's own leftovers (the lock file, temporary files).
bool has_user_entries(const fs::path& dir) {
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    if (it->path().filename() != FolderLock::kFileName && !is_temporary_file(it->path(), false)) return true;
  return false;
}

// cells/ must be the set's own folder: a link would send a resume's cells somewhere else.
void check_no_linked_cells(const std::string& dir) {
  std::error_code ec;
  if (fs::is_symlink(fs::symlink_status(fs::path(dir) / "cells", ec)))
    throw Error(fmt::format("{}/cells is a symbolic link; a result set keeps its cells in a folder of its own (raysort "
                            "never writes through a link): replace the link by the folder it points to",
                            dir));
}

bool has_cell_files(const fs::path& cdir) {
  std::error_code ec;
  for (fs::directory_iterator it(cdir, ec), end; !ec && it != end; it.increment(ec))
    if (it->path().extension() == ".json") return true;
  return false;
}

void remove_temporary_files(const fs::path& dir) {
  std::error_code ec;
  std::vector<fs::path> leftovers;
  for (const fs::path& d : {dir, dir / "cells"})
    for (fs::directory_iterator it(d, ec), end; !ec && it != end; it.increment(ec))
      if (is_temporary_file(it->path(), d != dir) && fs::is_regular_file(it->symlink_status())) leftovers.push_back(it->path());
  for (const auto& p : leftovers) fs::remove(p, ec);
}

}  // namespace

ResultSet ResultSet::open_for_run(const std::string& dir, const nlohmann::json& meta) {
  ResultSet rs;
  rs.dir_ = dir;
  rs.meta_ = meta;
  const fs::path meta_path = fs::path(dir) / "meta.json";
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw Error(fmt::format("--out {}: a file, not a folder; choose a new folder for the result set", dir));
  const bool looks_like_set = fs::exists(meta_path, ec) || fs::exists(fs::path(dir) / "cells", ec) ||
                              fs::exists(fs::path(dir) / FolderLock::kFileName, ec);
  if (!looks_like_set && fs::exists(dir, ec) && has_user_entries(dir))
    throw Error(fmt::format("--out {}: the folder is not empty and is not a result set (no meta.json); choose a new "
                            "or empty folder (raysort never writes among other files)",
                            dir));
  check_no_linked_cells(dir);
  fs::create_directories(fs::path(dir) / "cells", ec);
  if (ec) throw Error(fmt::format("cannot create result folder '{}': {}", dir, ec.message()));
  rs.lock_ = FolderLock::acquire(dir, meta.value("command", "raysort"), "result set");
  remove_temporary_files(dir);
  if (!fs::exists(meta_path, ec) && has_cell_files(fs::path(dir) / "cells"))
    throw Error(fmt::format("--out {}: holds cell records but no meta.json, so what they measured cannot be checked "
                            "(and a run would measure every cell again over them); restore its meta.json, or choose "
                            "another folder",
                            dir));
  if (fs::exists(meta_path, ec)) {
    const nlohmann::json old = parse_meta(read_file(meta_path.string()), meta_path.string());
    check_version(old, meta_path.string(), true);
    if (canonical_matrix(old.value("matrix", nlohmann::json())) != canonical_matrix(meta.value("matrix", nlohmann::json())))
      // The canonical entries differ: name only those (lists written in another order are no difference).
      throw Error(fmt::format("{} holds results of a different matrix configuration ({}); choose another --out folder "
                              "(or delete it to start over)",
                              dir, json_differences(canonical_matrix(meta.value("matrix", nlohmann::json::object())),
                                                    canonical_matrix(old.value("matrix", nlohmann::json::object())))));
    check_same_shard(old, meta, dir);
    check_same_build(old, meta, dir);
    // A scene file changed since the set was started: resumed cells would trace another file.
    if (old.contains("scene_files") && meta.contains("scene_files"))
      if (const auto diff = scene_file_differences(old, meta); !diff.empty())
        throw Error(fmt::format("{} was started on other scene files ({}); its cells and new ones would not be "
                                "comparable (A: when it was started, B: now); restore the files, or choose another --out "
                                "folder",
                                dir, diff.front()));
    // An encoder file changed since the set was started: resumed cells would use other keys.
    if (const auto diff = encoder_file_differences(old, meta); !diff.empty())
      throw Error(fmt::format("{} was started with other encoder files ({}); its cells and new ones would not be "
                              "comparable (A: when it was started, B: now); restore the file, or choose another --out "
                              "folder",
                              dir, diff.front()));
    // The ray file of run --rays changed since the set was started: resumed cells would trace other rays.
    if (const auto diff = ray_file_differences(old, meta); !diff.empty())
      throw Error(fmt::format("{} was started with another ray file ({}); its cells and new ones would not be "
                              "comparable (A: when it was started, B: now); restore the file, or choose another --out "
                              "folder",
                              dir, diff.front()));
    read_cells(dir, old, rs.cells_);
    // Keep the original meta (first start), but record that the run was resumed.
    rs.meta_ = old;
    rs.meta_["resumed"] = rs.meta_.value("resumed", 0) + 1;
  }
  write_file_atomically(meta_path.string(), rs.meta_.dump(2) + "\n");
  return rs;
}

namespace {

// meta.json's fingerprints name every cell whose views were written (a cell's file is written
// before them): a listed cell without its file was deleted or lost, and views written now would
// silently drop it. (Readers go on: compare counts such a cell as missing, merge as a shard that
// did not finish, and a run measures it again.)
void check_listed_cells_present(const std::string& dir, const nlohmann::json& meta,
                                const std::map<std::string, CellRecord>& cells) {
  const auto it = meta.find("fingerprints");
  if (it == meta.end() || !it->is_object()) return;
  std::vector<std::string> lost;
  for (const auto& [id, fp] : it->items())
    if (!cells.count(id)) lost.push_back(id);
  if (lost.empty()) return;
  std::error_code ec;
  const bool no_folder = !fs::exists(fs::path(dir) / "cells", ec);
  throw Error(fmt::format("{}: meta.json lists {} cell(s) whose files are missing{} (e.g. {}); restore them, or run "
                          "the set's command again to measure them (meta.json \"command\")",
                          dir, lost.size(), no_folder ? " (there is no cells/ folder)" : " from cells/", lost.front()));
}

}  // namespace

ResultSet ResultSet::load(const std::string& dir) {
  fs::path meta_path = fs::path(dir) / "meta.json";
  std::error_code ec;
  if (!fs::is_regular_file(meta_path, ec)) throw Error(fmt::format("'{}' is not a result set (no meta.json)", dir));
  ResultSet rs;
  rs.dir_ = dir;
  rs.meta_ = parse_meta(read_file(meta_path.string()), meta_path.string());
  check_version(rs.meta_, meta_path.string(), false);
  read_cells(dir, rs.meta_, rs.cells_);
  return rs;
}

ResultSet ResultSet::load_for_writing(const std::string& dir, const std::string& command) {
  std::error_code ec;
  if (!fs::is_regular_file(fs::path(dir) / "meta.json", ec))
    throw Error(fmt::format("'{}' is not a result set (no meta.json)", dir));
  // The lock first: a run writing into the set is refused before anything is read.
  check_no_linked_cells(dir);
  std::shared_ptr<FolderLock> lock = FolderLock::acquire(dir, command, "result set");
  remove_temporary_files(dir);
  ResultSet rs = load(dir);
  check_listed_cells_present(dir, rs.meta_, rs.cells_);
  rs.lock_ = std::move(lock);
  return rs;
}

const CellRecord* ResultSet::find(const std::string& id) const {
  auto it = cells_.find(id);
  return it == cells_.end() ? nullptr : &it->second;
}

void ResultSet::write_cell(const CellRecord& cell) {
  nlohmann::json j = cell;
  const fs::path cells = fs::path(dir_) / "cells";
  const std::string name = cell_file_name(cell.id());
  write_file_atomically((cells / name).string(), j.dump(2) + "\n");
  // A rerun cell whose file an older raysort named differently (see parse_cell_record): the new
  // record replaces it, or two files would hold one cell. Such a name may be another cell's (a wide
  // cell's, or a colliding id's under the old "__" names): only a record of this very cell goes.
  const std::string old_id = cell.id_before_class_axis();
  for (const std::string& old_name : {legacy_cell_file_name(cell.id()), cell_file_name(old_id), legacy_cell_file_name(old_id)}) {
    if (old_name == name) continue;
    const fs::path old_file = cells / old_name;
    std::error_code ec;
    if (!fs::is_regular_file(fs::symlink_status(old_file, ec))) continue;
    const nlohmann::json old = nlohmann::json::parse(read_file(old_file.string()), nullptr, false);
    if (!old.is_object()) continue;
    CellRecord held;
    try {
      held = old.get<CellRecord>();
    } catch (const std::exception&) {
      continue;
    }
    if (held.id() == cell.id()) fs::remove(old_file, ec);
  }
  cells_[cell.id()] = cell;
}

void ResultSet::add(const CellRecord& cell) {
  write_cell(cell);
  write_views();
}

void ResultSet::add_all(const std::vector<CellRecord>& cells) {
  for (const auto& cell : cells) write_cell(cell);
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
  // Embree's columns only for the paths the cells hold: a set without them keeps its columns.
  const std::vector<CellColumn> columns = cell_columns_for(all);
  std::string csv = csv_header(columns) + "\n";
  for (auto& c : all) {
    arr.push_back(c);
    csv += csv_row(c, columns) + "\n";
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

std::string cell_outside_matrix(const CellRecord& c, const nlohmann::json& m) {
  if (!m.is_object()) return "";
  // A list entry (scenes, encoders, bits, ...) or a comma-joined string (variant, access); a set
  // written before an axis existed has no entry for it, and every value passes.
  auto listed = [&](const char* key, const nlohmann::json& v) {
    if (!m.contains(key)) return true;
    const auto& e = m[key];
    if (e.is_string()) {
      const std::vector<std::string> items = split_list(e.get<std::string>());
      return v.is_string() && std::find(items.begin(), items.end(), v.get<std::string>()) != items.end();
    }
    if (!e.is_array()) return true;
    return std::find(e.begin(), e.end(), v) != e.end();
  };
  if (!listed("scenes", c.scene)) return fmt::format("scene '{}' is not one of its scenes", c.scene);
  if (m.contains("batches") && m["batches"].is_array() && !m["batches"].empty() && !listed("batches", c.batch))
    return fmt::format("batch '{}' is not one of its batches", c.batch);
  if (!listed("variant", c.variant)) return fmt::format("trace variant '{}' is not one of its variants", c.variant);
  if (!listed("layout", c.layout)) return fmt::format("trace class '{}' is not one of its classes", c.layout);
  // Embree's figures only for the paths the matrix named (none when it named none).
  for (const auto& e : c.embree)
    if (!m.contains("embree_paths") || !listed("embree_paths", e.path))
      return fmt::format("Embree path '{}' is not one of its --embree-paths", e.path);
  if (c.encoder == kBaselineEncoder) {
    if (c.bits != 0 || c.top_bits != 0 || c.access != "gather")
      return "a NoSort cell has 0 key bits, no top-k and gather access";
    return "";
  }
  if (!listed("encoders", c.encoder)) return fmt::format("encoder '{}' is not one of its encoders", c.encoder);
  const bool key_length_scene = m.contains("key_length_scenes") && listed("key_length_scenes", c.scene) &&
                                m["key_length_scenes"].is_array() && !m["key_length_scenes"].empty();
  if (!listed("bits", c.bits) && !(key_length_scene && listed("key_length_bits", c.bits)))
    return fmt::format("{}-bit keys are not among its key lengths for scene '{}'", c.bits, c.scene);
  if (c.top_bits != 0 && !listed("top_bits", c.top_bits)) return fmt::format("top-{} is not one of its top-k", c.top_bits);
  if (!listed("access", c.access)) return fmt::format("access mode '{}' is not one of its access modes", c.access);
  return "";
}

nlohmann::json canonical_matrix(const nlohmann::json& matrix) {
  if (!matrix.is_object()) return matrix;
  nlohmann::json m = matrix;
  // Axes whose order is only the visiting order: "--encoders hcc,mlhcc" and "mlhcc,hcc" measure the
  // same cells. The trace classes keep theirs (the first is the tables' main class).
  for (const char* key :
       {"scenes", "batches", "encoders", "bits", "key_length_scenes", "key_length_bits", "top_bits", "embree_paths"})
    if (m.contains(key) && m[key].is_array()) std::sort(m[key].begin(), m[key].end());
  for (const char* key : {"variant", "access", "baseline"})
    if (m.contains(key) && m[key].is_string()) {
      std::vector<std::string> items = split_list(m[key].get<std::string>());
      std::sort(items.begin(), items.end());
      std::string joined;
      for (const auto& item : items) joined += (joined.empty() ? "" : ",") + item;
      m[key] = joined;
    }
  return m;
}

std::string json_differences(const nlohmann::json& a, const nlohmann::json& b, const std::vector<std::string>& only) {
  std::set<std::string> keys(only.begin(), only.end());
  if (only.empty()) {
    if (a.is_object())
      for (auto& [k, v] : a.items()) keys.insert(k);
    if (b.is_object())
      for (auto& [k, v] : b.items()) keys.insert(k);
  }
  std::string out;
  for (const auto& k : keys) {
    nlohmann::json va = a.is_object() ? a.value(k, nlohmann::json()) : nlohmann::json();
    nlohmann::json vb = b.is_object() ? b.value(k, nlohmann::json()) : nlohmann::json();
    if (va != vb) out += fmt::format("{}{} {} vs {}", out.empty() ? "" : "; ", k, va.dump(), vb.dump());
  }
  return out;
}

void check_output_path(const std::string& out, const std::vector<std::string>& inputs, bool force,
                       const std::string& option) {
  if (out.empty()) throw Error(fmt::format("{} '': name the output, e.g. {} merged", option, option));
  std::error_code ec;
  const fs::path target = fs::weakly_canonical(fs::absolute(out, ec), ec);
  auto within = [](const fs::path& inner, const fs::path& outer) {  // inner == outer or below it
    auto [o, i] = std::mismatch(outer.begin(), outer.end(), inner.begin(), inner.end());
    return o == outer.end();
  };
  for (const auto& in : inputs) {
    const fs::path input = fs::weakly_canonical(fs::absolute(in, ec), ec);
    if (within(target, input))
      throw Error(fmt::format("{} {}: inside the input {}; write the output outside every input folder (an input "
                              "must stay readable as it was)",
                              option, out, in));
    if (within(input, target))
      throw Error(fmt::format("{} {}: holds the input {}; write the output to a folder of its own", option, out, in));
  }
  if (!fs::exists(target, ec) || force) return;
  // A folder holding nothing but a writer's lock file is empty: whoever holds it is found by the lock.
  if (fs::is_directory(target, ec) && !has_user_entries(target)) return;
  throw Error(fmt::format("{} {}: already exists; choose a new name, or pass --force to replace it", option, out));
}

void ResultSet::write_plots() const { raysort::write_plots(cells(), dir_); }

NoiseSummary summarize_noise(const std::vector<CellRecord>& cells) {
  NoiseSummary n;
  std::set<std::pair<std::string, std::vector<double>>> seen_rounds;
  std::vector<double> widths;
  std::vector<unsigned> rounds;
  for (const auto& c : cells) {
    if (!c.ok() || c.rounds == 0) continue;
    // Cells of one batch share their rounds (bench/cell_measure.h): the gather and permute cells of
    // one sort, and groups that stopped at the same round, hold the same NoSort and A/A samples and
    // repeat one A/A interval. Each distinct one counts once.
    const bool shared_rounds =
        c.samples.count("nosort") &&
        !seen_rounds.insert({fmt::format("{}/{}/{}/{}/{}", c.scene, c.batch, c.variant, c.layout, c.baseline),
                             c.samples.at("nosort")})
             .second;
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
