#include "bench/merge.h"

#include <fmt/format.h>
#include <fcntl.h>
#include <stdio.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <algorithm>
#include <filesystem>
#include <map>
#include <optional>
#include <set>

#include "bench/encoder_files.h"
#include "bench/result_set.h"
#include "util/folder_lock.h"
#include "util/error.h"

namespace raysort {

namespace fs = std::filesystem;

namespace {

std::string device_name(const nlohmann::json& meta) {
  const auto& d = meta.value("device", nlohmann::json::object());
  return fmt::format("'{}' (driver {})", d.value("name", "?"), d.value("driver", "?"));
}

std::string build_name(const nlohmann::json& meta) {
  return fmt::format("raysort {} commit {}", meta.value("raysort_version", "?"), meta.value("git_commit", "?"));
}

struct Input {
  std::string dir;
  ResultSet set;
  unsigned index = 0, count = 0;
};

}  // namespace

namespace {

// One line per problem, after the folder merge would write.
[[noreturn]] void refuse(const std::string& out, const std::vector<std::string>& problems) {
  std::string text = fmt::format("cannot merge into {}:", out);
  for (const auto& p : problems) text += "\n  - " + p;
  throw Error(text);
}

// The inputs that are shards; what is not (or cannot be read) goes to problems.
std::vector<Input> load_shards(const std::vector<std::string>& inputs, std::vector<std::string>& problems) {
  std::vector<Input> sets;
  for (const auto& dir : inputs) {
    try {
      ResultSet rs = ResultSet::load(dir);
      const nlohmann::json& meta = rs.meta();
      if (!meta.contains("shard")) {
        problems.push_back(fmt::format("{} is not a shard (its meta.json has no \"shard\"); merge takes the result sets "
                                       "of `raysort run ... --shard i/N`",
                                       dir));
        continue;
      }
      const unsigned index = meta["shard"].value("index", 0u), count = meta["shard"].value("count", 0u);
      sets.push_back({dir, std::move(rs), index, count});
    } catch (const Error& e) {
      problems.push_back(e.what());
    }
  }
  return sets;
}

// The shards must be one run's: the same matrix, split, plan, device and build, each shard once.
// Returns shard index -> input folder.
std::map<unsigned, std::string> check_one_run(const std::vector<Input>& sets, std::vector<std::string>& problems) {
  for (std::size_t i = 1; i < sets.size(); ++i) {
    const Input& ref = sets[0];
    const Input& in = sets[i];
    const nlohmann::json &a = ref.set.meta(), &b = in.set.meta();
    if (canonical_matrix(a.value("matrix", nlohmann::json())) != canonical_matrix(b.value("matrix", nlohmann::json())))
      problems.push_back(fmt::format("{} ran another matrix than {} ({}); merge only the shards of one `raysort run` "
                                     "command (the same options, each with its own --shard i/N)",
                                     in.dir, ref.dir, json_differences(b["matrix"], a["matrix"])));
    else if (in.count != ref.count)
      problems.push_back(fmt::format("{} is shard {}/{} but {} is shard {}/{}; merge the shards of one --shard i/N "
                                     "split",
                                     in.dir, in.index, in.count, ref.dir, ref.index, ref.count));
    else if (a["shard"].value("plan_hash", "") != b["shard"].value("plan_hash", "") ||
             a["shard"].value("plan", nlohmann::json()) != b["shard"].value("plan", nlohmann::json()))
      problems.push_back(fmt::format("{} planned its shards differently from {} (the scene files differ between the "
                                     "machines that ran them); run every shard against the same scene files",
                                     in.dir, ref.dir));
    if (a.value("device", nlohmann::json()) != b.value("device", nlohmann::json()))
      problems.push_back(fmt::format("{} ran on device {} but {} on {}; one matrix is measured on one kind of device: "
                                     "rerun that shard on the same kind of node (one Slurm partition)",
                                     in.dir, device_name(b), ref.dir, device_name(a)));
    if (build_name(a) != build_name(b))
      problems.push_back(fmt::format("{} was run by {} but {} by {}; rerun that shard with the same raysort build",
                                     in.dir, build_name(b), ref.dir, build_name(a)));
    if (const std::vector<std::string> d = encoder_file_differences(a, b); !d.empty())
      problems.push_back(fmt::format("{} ran other encoder files than {} ({}); rerun that shard with the same files",
                                     in.dir, ref.dir, d.front()));
    if (const std::vector<std::string> d = ray_file_differences(a, b); !d.empty())
      problems.push_back(fmt::format("{} traced other ray files than {} ({}); rerun that shard with the same files",
                                     in.dir, ref.dir, d.front()));
  }
  std::map<unsigned, std::string> shard_dir;  // shard index -> input folder
  for (const auto& in : sets) {
    // The plan is the one list of cells a merge trusts: it must hold as many cells as the shard
    // says the whole matrix plans, each with a shard of the split.
    const nlohmann::json& shard = in.set.meta()["shard"];
    const nlohmann::json plan = shard.value("plan", nlohmann::json::object());
    bool in_range = true;
    for (const auto& [id, index] : plan.items())
      in_range = in_range && index.get<unsigned>() >= 1 && index.get<unsigned>() <= in.count;
    if (!in_range || plan.size() != shard.value("cells", std::size_t{0}))
      problems.push_back(fmt::format("{}: its meta.json's shard plan holds {} cells{} but says the matrix plans {}; "
                                     "the file was edited or damaged: rerun that shard into a new folder",
                                     in.dir, plan.size(), in_range ? "" : " (some of another split)",
                                     shard.value("cells", std::size_t{0})));
    auto [it, fresh] = shard_dir.emplace(in.index, in.dir);
    if (!fresh)
      problems.push_back(fmt::format("{} and {} are both shard {}/{}; pass each shard once", it->second, in.dir,
                                     in.index, in.count));
  }
  return shard_dir;
}

// Every planned cell exactly once (or absent: its batch does not exist); returns the cells, and
// the absent ids in `absent`.
std::vector<CellRecord> collect_cells(const std::vector<Input>& sets, const std::map<unsigned, std::string>& shard_dir,
                                      std::set<std::string>& absent, std::vector<std::string>& problems) {
  const nlohmann::json& plan = sets[0].set.meta()["shard"].value("plan", nlohmann::json::object());
  std::map<std::string, const Input*> owner;
  std::map<std::pair<std::string, std::string>, std::vector<std::string>> duplicates;  // (a, b) -> cells
  std::map<std::string, std::vector<std::string>> unplanned;                           // dir -> cells
  std::vector<CellRecord> cells;
  for (const auto& in : sets) {
    for (const auto& id : in.set.meta().value("absent_cells", std::vector<std::string>{})) absent.insert(id);
    for (auto& c : in.set.cells()) {
      const std::string id = c.id();
      if (!plan.contains(id)) {
        unplanned[in.dir].push_back(id);
        continue;
      }
      auto [it, fresh] = owner.emplace(id, &in);
      if (!fresh) {
        duplicates[{it->second->dir, in.dir}].push_back(id);
        continue;
      }
      cells.push_back(std::move(c));
    }
  }
  for (const auto& [dir, ids] : unplanned)
    problems.push_back(fmt::format("{} holds {} cell(s) the plan of this matrix does not have (e.g. {}); it is not a "
                                   "shard of this run: remove those cells or that input",
                                   dir, ids.size(), ids[0]));
  for (const auto& [dirs, ids] : duplicates)
    problems.push_back(fmt::format("{} and {} both hold {} cell(s) (e.g. {}); each cell must come from one shard: "
                                   "merge each shard's own result set once",
                                   dirs.first, dirs.second, ids.size(), ids[0]));
  std::map<unsigned, std::vector<std::string>> missing;  // shard -> cells
  std::map<unsigned, std::size_t> planned_per_shard;
  for (const auto& [id, shard] : plan.items()) {
    ++planned_per_shard[shard.get<unsigned>()];
    if (!owner.count(id) && !absent.count(id)) missing[shard.get<unsigned>()].push_back(id);
  }
  const unsigned count = sets[0].count;
  for (const auto& [shard, ids] : missing) {
    auto it = shard_dir.find(shard);
    if (it == shard_dir.end()) {
      problems.push_back(fmt::format("no input is shard {}/{} ({} cells missing, e.g. {}); add its result folder to "
                                     "the merge, or run it (`raysort run ... --shard {}/{}`)",
                                     shard, count, ids.size(), ids[0], shard, count));
      continue;
    }
    const Input& in = *std::find_if(sets.begin(), sets.end(), [&](const Input& s) { return s.dir == it->second; });
    problems.push_back(fmt::format("{} (shard {}/{}) lacks {} of its {} cells (e.g. {}): the shard did not finish; "
                                   "resume it by running its command again (`{}`), then merge again",
                                   in.dir, shard, count, ids.size(), planned_per_shard[shard], ids[0],
                                   in.set.meta().value("command", "raysort run ... --shard i/N")));
  }
  return cells;
}

// The merged meta: the first shard's, without what belonged to one shard, plus where it came from.
nlohmann::json merged_meta(const std::vector<Input>& sets, const std::map<unsigned, std::string>& shard_dir,
                           const std::set<std::string>& absent, const std::string& command) {
  const unsigned count = sets[0].count;
  nlohmann::json meta = sets[0].set.meta();
  nlohmann::json from = nlohmann::json::array();
  for (const auto& [index, dir] : shard_dir) {
    // Captured through a plain reference: clang before 16 cannot capture a structured binding.
    const std::string& shard_folder = dir;
    const auto& m =
        std::find_if(sets.begin(), sets.end(), [&](const Input& s) { return s.dir == shard_folder; })->set.meta();
    from.push_back({{"dir", dir},
                    {"shard", fmt::format("{}/{}", index, count)},
                    {"command", m.value("command", "")},
                    {"date", m.value("date", "")},
                    {"host_cpu", m.value("host_cpu", "")},
                    {"resumed", m.value("resumed", 0)}});
  }
  for (const char* key : {"shard", "resumed", "fingerprints", "absent_cells"}) meta.erase(key);
  meta["command"] = command;
  meta["merged_from"] = from;
  meta["sharding"] = {{"count", count}, {"plan_hash", sets[0].set.meta()["shard"].value("plan_hash", "")}};
  if (!absent.empty()) meta["absent_cells"] = std::vector<std::string>(absent.begin(), absent.end());

  return meta;
}

// OUT while a merge writes it: created when absent and locked like any result set
// (util/folder_lock.h), so a run, report or second merge into OUT is refused until the merge ends,
// and the merge is refused while one of them holds OUT.
class LockedOutput {
 public:
  LockedOutput(const std::string& out, const std::string& command) : out_(out) {
    std::error_code ec;
    target_ = fs::absolute(fs::path(out).lexically_normal());
    if (target_.filename().empty()) target_ = target_.parent_path();  // "merged/" names the folder "merged"
    created_ = !fs::exists(fs::symlink_status(target_, ec));
    fs::create_directories(target_, ec);
    if (ec) throw Error(fmt::format("-o {}: cannot create the folder ({})", out, ec.message()));
    try {
      lock_ = FolderLock::acquire(target_.string(), command, "result set");
    } catch (...) {
      discard_if_created();
      throw;
    }
    remove_stale_leftovers();
  }
  // A refused merge leaves no folder it created.
  void discard_if_created() {
    if (!created_) return;
    lock_.reset();
    std::error_code ec;
    fs::remove(target_ / FolderLock::kFileName, ec);
    fs::remove(target_, ec);  // only if empty
  }
  const fs::path& target() const { return target_; }
  const std::string& name() const { return out_; }  // as the user wrote it, for messages
  fs::path beside(const char* what) const {
    return target_.parent_path() / fmt::format(".{}.{}-{}", target_.filename().string(), what, ::getpid());
  }

 private:
  // ".OUT.merging-PID" and ".OUT.replaced-PID" folders of merges into OUT that were killed: with
  // OUT locked no other merge into it is running, so every such folder is a leftover.
  void remove_stale_leftovers() {
    std::error_code ec;
    const std::string name = target_.filename().string();
    std::vector<fs::path> stale;
    for (fs::directory_iterator it(target_.parent_path(), ec), end; !ec && it != end; it.increment(ec)) {
      const std::string f = it->path().filename().string();
      for (const std::string& prefix : {"." + name + ".merging-", "." + name + ".replaced-"})
        if (f.size() > prefix.size() && f.compare(0, prefix.size(), prefix) == 0 &&
            f.find_first_not_of("0123456789", prefix.size()) == std::string::npos &&
            fs::is_directory(it->symlink_status()))
          stale.push_back(it->path());
    }
    for (const auto& p : stale) fs::remove_all(p, ec);
  }

  std::string out_;
  fs::path target_;
  bool created_ = false;
  std::shared_ptr<FolderLock> lock_;
};

// Built beside OUT (same file system), then swapped into place in one step (renameat2's
// RENAME_EXCHANGE), so OUT is at every moment either its old content or the complete merged set.
void write_merged(LockedOutput& out, const nlohmann::json& meta, const std::vector<CellRecord>& cells) {
  std::error_code ec;
  const fs::path tmp = out.beside("merging");
  fs::remove_all(tmp, ec);
  try {
    // Its lock is held until the swap is done: a writer that finds the merged set at OUT waits.
    ResultSet merged = ResultSet::open_for_run(tmp.string(), meta);
    merged.add_all(cells);
    merged.write_plots();
    if (::renameat2(AT_FDCWD, tmp.c_str(), AT_FDCWD, out.target().c_str(), RENAME_EXCHANGE) != 0) {
      // A file system without the exchange: the old content moved aside first, then the new one in.
      if (errno != EINVAL && errno != ENOSYS)
        throw Error(fmt::format("-o {}: cannot move the merged result set into place ({}); nothing was written", out.name(),
                                std::strerror(errno)));
      const fs::path old = out.beside("replaced");
      fs::rename(out.target(), old);
      fs::rename(tmp, out.target());
      fs::remove_all(old, ec);
      return;
    }
    fs::remove_all(tmp, ec);  // now OUT's old content: an empty folder, or the set --force replaced
  } catch (const fs::filesystem_error& e) {
    fs::remove_all(tmp, ec);
    throw Error(fmt::format("-o {}: cannot write the merged result set ({}); nothing was written", out.name(), e.what()));
  } catch (...) {
    fs::remove_all(tmp, ec);
    throw;
  }
}

}  // namespace

MergeSummary merge_result_sets(const std::vector<std::string>& inputs, const std::string& out,
                               const std::string& command, bool force) {
  if (inputs.empty()) throw Error("raysort merge: name the shards' result folders to merge, e.g. shards/* -o merged");
  check_output_path(out, inputs, force, "-o");
  std::error_code ec;
  if (force && fs::exists(out, ec) && !(fs::is_directory(out, ec) && fs::is_empty(out, ec)) &&
      !fs::is_regular_file(fs::path(out) / "meta.json", ec))
    throw Error(fmt::format("-o {} --force: replaces a result set only, and {} is not one (no meta.json); choose "
                            "another folder",
                            out, out));
  LockedOutput locked(out, command);
  // Checked again under the lock: a writer may have filled OUT since the check above.
  if (!force && fs::exists(locked.target() / "meta.json", ec))
    throw Error(fmt::format("-o {}: already exists; choose a new name, or pass --force to replace it", out));
  std::vector<std::string> problems;
  const std::vector<Input> sets = load_shards(inputs, problems);
  const std::map<unsigned, std::string> shard_dir = check_one_run(sets, problems);
  std::set<std::string> absent;
  std::vector<CellRecord> cells;
  if (problems.empty() && !sets.empty()) cells = collect_cells(sets, shard_dir, absent, problems);
  if (!problems.empty() || sets.empty()) {
    locked.discard_if_created();
    refuse(out, problems);
  }
  write_merged(locked, merged_meta(sets, shard_dir, absent, command), cells);
  MergeSummary s;
  s.cells = cells.size();
  s.absent = absent.size();
  for (const auto& c : cells) s.failed += !c.ok();
  s.shard_count = sets[0].count;
  return s;
}

}  // namespace raysort
