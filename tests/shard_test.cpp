// Sharded matrix runs (issue 10): the shard plan (bench/shard.h) is deterministic, covers every cell
// once and balances estimated cost; `raysort run --shard i/N` + `raysort merge` reproduce a full run
// cell for cell; merge refuses inputs that are not one run's shards, naming the input and the fix.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "bench/matrix.h"
#include "bench/merge.h"
#include "bench/result_set.h"
#include "bench/shard.h"
#include "test_util.h"
#include "util/atomic_file.h"
#include "util/error.h"

namespace fs = std::filesystem;
using namespace raysort;

namespace {

// Scenes of very different sizes and effects, without loading anything.
SceneFacts fake_facts(const std::string& scene) {
  if (scene == "small") return {1000, 48 * 27, 1, 1};
  if (scene == "large") return {2'000'000, 48 * 27, 1, 1};
  if (scene == "unlit") return {50'000, 48 * 27, 0, 2};  // no lights: no shadow batches; bounce1, bounce2
  return {100'000, 96 * 54, 2, 1};                         // two shadow rays per hit
}

MatrixSpec fake_matrix() {
  MatrixSpec spec = matrix_preset("quick");
  spec.scenes = {"small", "large", "unlit", "medium"};
  spec.batches = {};  // every batch the effects imply
  spec.key_length_scenes = {"large"};
  spec.top_bits = {8};
  spec.variants = {TraceVariant::Robust, TraceVariant::Fast};
  return spec;
}

std::string expect_error(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no Error thrown";
  return "";
}

void expect_contains(const std::string& text, const std::vector<std::string>& parts) {
  for (const auto& p : parts) EXPECT_NE(text.find(p), std::string::npos) << "no '" << p << "' in:\n" << text;
}

}  // namespace

TEST(ShardSpec, ParsesOneBasedAndRefusesTheRest) {
  ShardSpec s = ShardSpec::parse("2/4");
  EXPECT_EQ(s.index, 2u);
  EXPECT_EQ(s.count, 4u);
  EXPECT_EQ(s.str(), "2/4");
  EXPECT_EQ(ShardSpec::parse("1/1").count, 1u);
  expect_contains(expect_error([] { ShardSpec::parse("0/4"); }), {"'0/4'", "numbered from 1", "1/4 ... 4/4"});
  expect_contains(expect_error([] { ShardSpec::parse("5/4"); }), {"'5/4'", "1/4 ... 4/4"});
  expect_contains(expect_error([] { ShardSpec::parse("1/0"); }), {"'1/0'", "at least 1"});
  expect_contains(expect_error([] { ShardSpec::parse("2"); }), {"'2'", "expected i/N", "--shard 2/4"});
  expect_contains(expect_error([] { ShardSpec::parse("a/b"); }), {"expected i/N"});
}

TEST(ShardPlan, CellsFollowTheScenesEffects) {
  auto cells = matrix_cells(fake_matrix(), fake_facts);
  std::set<std::string> ids;
  for (auto& c : cells) ids.insert(c.id);
  EXPECT_EQ(ids.size(), cells.size()) << "a cell planned twice";
  EXPECT_TRUE(ids.count("small/shadow0/nosort/0"));
  EXPECT_TRUE(ids.count("small/bounce1/hcc/32/top8/fast"));
  EXPECT_TRUE(ids.count("large/primary/mlhcc/64"));  // key-length scene
  EXPECT_FALSE(ids.count("small/primary/mlhcc/64"));
  EXPECT_TRUE(ids.count("unlit/bounce2/ppc/32"));
  for (auto& id : ids) EXPECT_EQ(id.rfind("unlit/shadow", 0), std::string::npos) << id << ": the scene has no lights";
  // A requested batch the scene cannot produce has no cells.
  MatrixSpec spec = fake_matrix();
  spec.batches = {"shadow0", "bounce1"};
  for (auto& c : matrix_cells(spec, fake_facts)) EXPECT_FALSE(c.scene == "unlit" && c.batch == "shadow0");
}

TEST(ShardPlan, DeterministicCompleteContiguousAndBalancedByCost) {
  const auto cells = matrix_cells(fake_matrix(), fake_facts);
  std::uint64_t total = 0, largest_group = 0;
  std::map<std::string, std::uint64_t> group_cost;
  for (auto& c : cells) total += c.cost, group_cost[round_group(c)] += c.cost;
  for (auto& [g, cost] : group_cost) largest_group = std::max(largest_group, cost);
  std::set<std::string> scenes;
  for (auto& c : cells) scenes.insert(c.scene);
  for (unsigned n = 1; n <= 12; ++n) {
    const auto plan = plan_shards(cells, n);
    std::map<std::string, unsigned> a, b;
    for (auto& c : plan) a[c.id] = c.shard;
    for (auto& c : plan_shards(cells, n)) b[c.id] = c.shard;
    EXPECT_EQ(a, b) << n << " shards: not deterministic";
    // Every cell exactly once, in a shard 1..n.
    ASSERT_EQ(a.size(), cells.size());
    for (auto& [id, shard] : a) EXPECT_TRUE(shard >= 1 && shard <= n) << id;
    // Contiguous: shards are consecutive runs of the visiting order, so a shard loads few scenes:
    // n shards hold at most scenes + n - 1 (scene, shard) pairs.
    std::set<std::pair<std::string, unsigned>> scene_shards;
    for (std::size_t i = 0; i < plan.size(); ++i) {
      if (i > 0) {
        EXPECT_GE(plan[i].shard, plan[i - 1].shard) << plan[i].id;
      }
      scene_shards.insert({plan[i].scene, plan[i].shard});
    }
    EXPECT_LE(scene_shards.size(), scenes.size() + n - 1) << n << " shards";
    // A round group (an encoder's access modes, timed in the same rounds) is never split.
    std::map<std::string, std::set<unsigned>> group_shards;
    for (auto& c : plan) group_shards[round_group(c)].insert(c.shard);
    for (auto& [g, shards] : group_shards) EXPECT_EQ(shards.size(), 1u) << g << " split over shards";
    // Balanced by cost: every shard within one round group's cost of the mean.
    const auto loads = shard_loads(plan, n);
    std::size_t count = 0;
    for (auto& l : loads) {
      count += l.cells;
      EXPECT_LE(static_cast<double>(l.cost), static_cast<double>(total) / n + static_cast<double>(largest_group))
          << n << " shards";
      EXPECT_GE(static_cast<double>(l.cost), static_cast<double>(total) / n - static_cast<double>(largest_group))
          << n << " shards";
    }
    EXPECT_EQ(count, cells.size());
  }
  // With many groups per shard that bound is tight: 4 shards within 3 % of the mean, while the
  // cell counts differ (the large scene's cells cost more than the small one's).
  const auto loads = shard_loads(plan_shards(cells, 4), 4);
  std::uint64_t most = 0;
  std::size_t fewest = cells.size(), most_cells = 0;
  for (auto& l : loads) {
    most = std::max(most, l.cost);
    fewest = std::min(fewest, l.cells), most_cells = std::max(most_cells, l.cells);
  }
  EXPECT_LE(static_cast<double>(most), 1.03 * static_cast<double>(total) / 4);
  EXPECT_NE(fewest, most_cells) << "balanced by count, not by cost";
  std::string text = format_plan(plan_shards(cells, 4), 4);
  expect_contains(text, {"4 shards", "1/4", "4/4", "vs mean", "small/primary/nosort/0", "largest round group"});
}

// The plan of the quick preset names exactly the cells a full run produces (the golden set is the
// quick preset run on one machine); loads the procedural scenes, no device needed.
TEST(ShardPlan, QuickPresetPlanEqualsTheCellsOfAFullRun) {
  MatrixSpec spec = matrix_preset("quick");
  spec.frame = {48, 27, 1};
  spec.reps = 1;
  spec.warmup = 0;
  auto plan = [&] {
    std::set<std::string> ids;
    for (auto& c : matrix_cells(spec, [&](const std::string& s) { return load_scene_facts(s, spec, ""); }))
      ids.insert(c.id);
    return ids;
  };
  auto cells_of = [](const std::string& dir) {
    std::set<std::string> ids;
    for (auto& c : ResultSet::load(dir).cells()) ids.insert(c.id());
    return ids;
  };
  // scripts/golden.sh names one trace class per golden set (--layout binary, --layout wide); the
  // binary set was written before the class was an axis, and its cells read with the class in the id.
  spec.layouts = {TraceLayout::Binary};
  EXPECT_EQ(plan(), cells_of("tests/golden/quick-tiny-binary"));  // the preset's own baseline: pixel
  spec.layouts = {TraceLayout::Wide};
  spec.baselines = parse_baseline_orders("all");                  // scripts/golden.sh: --baseline all
  EXPECT_EQ(plan(), cells_of("tests/golden/quick-tiny"));
  // The preset itself runs packets of the device's width beside single rays.
  EXPECT_EQ(matrix_preset("quick").layouts, (std::vector<TraceLayout>{TraceLayout::Wide, TraceLayout::Packet}));
}

namespace {

using Cli = raysort::testing::CliResult;

// What must be equal between a sharded and a full run: everything but the timings.
std::map<std::string, std::string> deterministic(const ResultSet& rs) {
  std::map<std::string, std::string> m;
  for (auto& c : rs.cells())
    m[c.id()] = fmt::format("{} {} {} {} {} {} {} {} {}", c.status, c.rays, c.keys_hash, c.order_hash, c.anc,
                            c.simt_lane_efficiency, c.simt_distinct_per_visit, c.hits_match_nosort,
                            c.order_is_permutation);
  return m;
}

void edit_meta(const fs::path& dir, const std::function<void(nlohmann::json&)>& f) {
  auto meta = nlohmann::json::parse(read_file((dir / "meta.json").string()));
  f(meta);
  write_file_atomically((dir / "meta.json").string(), meta.dump(2));
}

// Expects `raysort merge inputs -o out` to fail, print every one of `parts`, and write nothing.
void expect_merge_refused(const std::vector<fs::path>& inputs, const fs::path& out,
                          const std::vector<std::string>& parts) {
  std::vector<std::string> args{"merge"};
  for (auto& in : inputs) args.push_back(in.string());
  args.insert(args.end(), {"-o", out.string()});
  Cli r = raysort::testing::run_cli(args);
  EXPECT_NE(r.code, 0) << r.err;
  expect_contains(r.err, parts);
  EXPECT_FALSE(fs::exists(out)) << "a refused merge wrote " << out;
  for (auto& e : fs::directory_iterator(out.parent_path()))
    EXPECT_EQ(e.path().filename().string().find(".merging-"), std::string::npos) << "left behind: " << e.path();
}

}  // namespace

TEST(ShardedRun, MergeOfShardsEqualsTheFullRunAndRefusesWhatIsNotOneRun) {
  const fs::path root = raysort::testing::temp_path("sharded");
  fs::create_directories(root);
  const std::vector<std::string> matrix{"run",     "--scenes",     "cornell,detail-room", "--encoders",
                                        "hcc,origin,mlhcc", "--bits",  "16,32",         "--batches",
                                        "primary,shadow0", "--resolution", "48x27", "--reps", "1", "--warmup", "0",
                                        "--max-time", "0"};
  auto run = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = matrix;
    args.insert(args.end(), extra.begin(), extra.end());
    return raysort::testing::run_cli(args);
  };

  // The plan, printed without running anything.
  Cli plan = run({"--shard-plan", "3"});
  ASSERT_EQ(plan.code, 0) << plan.err;
  expect_contains(plan.out, {"28 cells in 3 shards", "1/3", "3/3", "cornell/primary/nosort/0"});

  Cli full = run({"--out", (root / "full").string()});
  ASSERT_EQ(full.code, 0) << full.err;
  std::vector<fs::path> shards;
  for (int i = 1; i <= 3; ++i) {
    shards.push_back(root / fmt::format("shard{}", i));
    Cli r = run({"--shard", fmt::format("{}/3", i), "--out", shards.back().string()});
    ASSERT_EQ(r.code, 0) << r.err;
  }
  // Each shard records which shard it is and the whole plan; together they hold every cell once.
  std::size_t sum = 0;
  for (int i = 0; i < 3; ++i) {
    ResultSet rs = ResultSet::load(shards[i].string());
    EXPECT_EQ(rs.meta()["shard"]["index"], i + 1);
    EXPECT_EQ(rs.meta()["shard"]["count"], 3);
    EXPECT_EQ(rs.meta()["shard"]["cells"], 28);
    EXPECT_GT(rs.cells().size(), 5u) << "an unbalanced shard";
    sum += rs.cells().size();
  }
  EXPECT_EQ(sum, 28u);

  // Resume works per shard: the same command runs nothing; a lost cell is run again.
  Cli again = run({"--shard", "2/3", "--out", shards[1].string()});
  EXPECT_EQ(again.code, 0) << again.err;
  EXPECT_NE(again.out.find("0 cells run"), std::string::npos) << again.out;
  auto lost = *fs::directory_iterator(shards[1] / "cells");
  fs::path lost_copy = root / "lost.json";
  fs::copy_file(lost.path(), lost_copy);
  fs::remove(lost.path());
  expect_merge_refused(shards, root / "merged", {shards[1].string(), "shard 2/3", "lacks 1 of its", "--shard 2/3"});
  // The lost cell's batch shared its rounds: it is measured again whole, its other cells too.
  CellRecord lost_cell;
  from_json(nlohmann::json::parse(std::ifstream(lost_copy)), lost_cell);
  std::size_t batch_cells = 0;
  for (const auto& c : ResultSet::load(shards[1].string()).cells())
    batch_cells += c.scene == lost_cell.scene && c.batch == lost_cell.batch && c.variant == lost_cell.variant &&
                   c.layout == lost_cell.layout && c.baseline == lost_cell.baseline;
  again = run({"--shard", "2/3", "--out", shards[1].string()});
  EXPECT_EQ(again.code, 0) << again.err;
  EXPECT_NE(again.out.find(fmt::format("{} cells run ({} ok cells measured again with the rest of their batch)",
                                       batch_cells + 1, batch_cells)),
            std::string::npos)
      << again.out;
  // ...and only into its own folder.
  Cli wrong = run({"--shard", "1/3", "--out", shards[1].string()});
  EXPECT_NE(wrong.code, 0);
  expect_contains(wrong.err, {shards[1].string(), "holds shard 2/3", "not shard 1/3", "its own --out"});
  Cli bad = run({"--shard", "0/3", "--out", (root / "bad").string()});
  EXPECT_NE(bad.code, 0);
  expect_contains(bad.err, {"--shard '0/3'", "numbered from 1"});
  EXPECT_FALSE(fs::exists(root / "bad"));

  // The merge equals the full run cell for cell (deterministic figures exactly, timings present).
  const fs::path merged = root / "merged";
  Cli m = raysort::testing::run_cli({"merge", shards[2].string(), shards[0].string(), shards[1].string(), "-o", merged.string()});
  ASSERT_EQ(m.code, 0) << m.err;
  EXPECT_NE(m.out.find("merged 28 cells of 3 shards"), std::string::npos) << m.out;
  ResultSet a = ResultSet::load((root / "full").string()), b = ResultSet::load(merged.string());
  EXPECT_EQ(deterministic(a), deterministic(b));
  for (auto& c : b.cells()) {
    EXPECT_GT(c.trace.median_ms, 0) << c.id();
    if (c.encoder != "nosort") {
      EXPECT_GT(c.encode.median_ms + c.sort.median_ms, 0) << c.id();
    }
  }
  EXPECT_EQ(a.meta()["matrix"], b.meta()["matrix"]);
  EXPECT_FALSE(b.meta().contains("shard"));
  EXPECT_EQ(b.meta()["merged_from"].size(), 3u);
  for (const char* view : {"tables.md", "cells.csv", "cells.json"}) EXPECT_TRUE(fs::exists(merged / view)) << view;
  // The merged set is the full matrix: `raysort run` of the same matrix resumes it with nothing to do.
  Cli resumed = run({"--out", merged.string()});
  EXPECT_EQ(resumed.code, 0) << resumed.err;
  EXPECT_NE(resumed.out.find("0 cells run,"), std::string::npos) << resumed.out;

  // Refusals, each naming the input and the fix; nothing written.
  const fs::path out = root / "refused";
  expect_merge_refused({shards[0], shards[1]}, out, {"no input is shard 3/3", "--shard 3/3"});
  expect_merge_refused({shards[0], shards[1], shards[2], shards[2]}, out, {"are both shard 3/3", "each shard once"});
  expect_merge_refused({shards[0], root / "full"}, out, {(root / "full").string(), "is not a shard", "--shard i/N"});
  expect_merge_refused({shards[0], root / "nowhere"}, out, {(root / "nowhere").string(), "not a result set"});
  // A cell in two inputs (under its own file name: a file named otherwise is refused on read).
  fs::copy(shards[1], root / "dup", fs::copy_options::recursive);
  const fs::path first_cell = fs::directory_iterator(shards[0] / "cells")->path();
  fs::copy_file(first_cell, root / "dup" / "cells" / first_cell.filename());
  expect_merge_refused({shards[0], root / "dup", shards[2]}, out, {(root / "dup").string(), "both hold 1 cell"});
  // Another configuration, device or build.
  auto altered = [&](const std::string& name, const std::function<void(nlohmann::json&)>& f) {
    fs::copy(shards[2], root / name, fs::copy_options::recursive);
    edit_meta(root / name, f);
    return root / name;
  };
  expect_merge_refused({shards[0], shards[1], altered("res", [](auto& j) { j["matrix"]["resolution"] = "96x54"; })},
                       out, {(root / "res").string(), "another matrix", "resolution \"96x54\" vs \"48x27\""});
  expect_merge_refused({shards[0], shards[1], altered("dev", [](auto& j) { j["device"]["name"] = "NVIDIA H100"; })},
                       out, {(root / "dev").string(), "NVIDIA H100", "same kind of node"});
  expect_merge_refused({shards[0], shards[1], altered("commit", [](auto& j) { j["git_commit"] = "0123456789ab"; })},
                       out, {(root / "commit").string(), "commit 0123456789ab", "same raysort build"});
  expect_merge_refused({shards[0], shards[1], altered("plan", [](auto& j) { j["shard"]["plan_hash"] = "x"; })}, out,
                       {(root / "plan").string(), "planned its shards differently", "same scene files"});
  // Several problems at once: each on its own line.
  Cli many = raysort::testing::run_cli({"merge", shards[0].string(), (root / "dev").string(), (root / "commit").string(), "-o",
                          out.string()});
  EXPECT_NE(many.code, 0);
  EXPECT_GE(std::count(many.err.begin(), many.err.end(), '\n'), 3) << many.err;
  expect_contains(many.err, {"NVIDIA H100", "commit 0123456789ab"});
  // An existing result set is never overwritten without --force, and never an input even with it.
  const std::string before = read_file((merged / "cells.csv").string());
  Cli onto = raysort::testing::run_cli({"merge", shards[0].string(), shards[1].string(), shards[2].string(), "-o", merged.string()});
  EXPECT_NE(onto.code, 0);
  expect_contains(onto.err, {merged.string(), "already exists", "--force"});
  EXPECT_EQ(read_file((merged / "cells.csv").string()), before);
  Cli forced = raysort::testing::run_cli(
      {"merge", shards[0].string(), shards[1].string(), shards[2].string(), "-o", merged.string(), "--force"});
  EXPECT_EQ(forced.code, 0) << forced.err;
  EXPECT_EQ(deterministic(ResultSet::load(merged.string())), deterministic(a));
  for (const auto& [target, part] : std::vector<std::pair<fs::path, std::string>>{
           {shards[1] / "cells" / "merged.json", "inside the input"}, {shards[1], "inside the input"}, {root, "holds the input"}}) {
    Cli into = raysort::testing::run_cli(
        {"merge", shards[0].string(), shards[1].string(), shards[2].string(), "-o", target.string(), "--force"});
    EXPECT_NE(into.code, 0) << target;
    expect_contains(into.err, {part, "-o " + target.string()});
  }
  EXPECT_FALSE(fs::exists(shards[1] / "cells" / "merged.json"));
  Cli still = run({"--shard", "2/3", "--out", shards[1].string()});  // the input still resumes
  EXPECT_EQ(still.code, 0) << still.err;
  EXPECT_NE(still.out.find("0 cells run,"), std::string::npos) << still.out;
  fs::remove_all(root);
}
