// The benchmark matrix: result sets (atomic cells, resume, format version), compare and its
// regression rules, and the quick preset end to end at a tiny resolution, including a run killed
// with SIGKILL and resumed.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "bench/compare.h"
#include "bench/result_set.h"
#include "bench/runner.h"
#include "test_util.h"
#include "util/atomic_file.h"

namespace raysort {

namespace fs = std::filesystem;

namespace {

std::string temp_dir(const std::string& name) {
  fs::path p = fs::temp_directory_path() / ("raysort-test-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p.string();
}

CellRecord cell(const std::string& encoder, unsigned bits, double mrays, double anc) {
  CellRecord c;
  c.scene = "s", c.batch = "bounce1", c.encoder = encoder, c.bits = bits, c.rays = 100;
  c.trace_mrays = mrays, c.speedup = mrays / 10.0, c.anc = anc;
  c.keys_hash = "00000000000000aa", c.order_hash = "00000000000000bb";
  c.hits_match_nosort = c.order_is_permutation = true;
  return c;
}

nlohmann::json meta_for(const std::string& preset) {
  return {{"format_version", kResultFormatVersion}, {"matrix", {{"preset", preset}}}};
}

// Deterministic part of a result set: id -> (status, keys, order, ANC, SIMT).
std::map<std::string, std::string> deterministic(const ResultSet& rs) {
  std::map<std::string, std::string> m;
  for (auto& c : rs.cells())
    m[c.id()] = c.status + " " + c.keys_hash + " " + c.order_hash + " " + std::to_string(c.anc) + " " +
                std::to_string(c.simt_lane_efficiency) + " " + std::to_string(c.simt_distinct_per_visit);
  return m;
}

int run_cli(const std::vector<std::string>& args, int kill_after_ms = -1, int kill_after_cells = 0) {
  pid_t pid = fork();
  if (pid == 0) {
    if (kill_after_cells > 0) ::setenv("RAYSORT_TEST_KILL_AFTER_CELLS", std::to_string(kill_after_cells).c_str(), 1);
    std::vector<char*> argv;
    std::string bin = RAYSORT_BINARY;
    argv.push_back(bin.data());
    std::vector<std::string> copy = args;
    for (auto& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    int devnull = ::open("/dev/null", O_WRONLY);
    ::dup2(devnull, 1);
    ::dup2(devnull, 2);
    ::execv(bin.c_str(), argv.data());
    _exit(127);
  }
  if (kill_after_ms >= 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(kill_after_ms));
    ::kill(pid, SIGKILL);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
}

}  // namespace

TEST(ResultSet, CellsPersistAndResume) {
  std::string dir = temp_dir("rs");
  {
    auto rs = ResultSet::open_for_run(dir, meta_for("quick"));
    rs.add(cell("hcc", 32, 12.0, 3.0));
    rs.add(cell("origin", 32, 11.0, 5.0));
  }
  // A leftover temporary file of a killed writer is ignored.
  std::ofstream(dir + "/cells/s__bounce1__ppc__32.json.tmp.123") << "{ half written";
  auto rs = ResultSet::open_for_run(dir, meta_for("quick"));
  EXPECT_TRUE(rs.has("s/bounce1/hcc/32"));
  EXPECT_TRUE(rs.has("s/bounce1/origin/32"));
  EXPECT_FALSE(rs.has("s/bounce1/ppc/32"));
  EXPECT_EQ(rs.cells().size(), 2u);
  EXPECT_TRUE(fs::exists(dir + "/cells.csv"));
  EXPECT_TRUE(fs::exists(dir + "/tables.md"));
  auto loaded = ResultSet::load(dir);
  ASSERT_NE(loaded.find("s/bounce1/hcc/32"), nullptr);
  EXPECT_EQ(loaded.find("s/bounce1/hcc/32")->anc, 3.0);
  // CSV: a header and one row per cell.
  std::string csv = read_file(dir + "/cells.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 3);
}

TEST(ResultSet, RefusesAnotherMatrixAndAnotherFormat) {
  std::string dir = temp_dir("rs2");
  ResultSet::open_for_run(dir, meta_for("quick")).add(cell("hcc", 32, 1, 1));
  EXPECT_THROW(ResultSet::open_for_run(dir, meta_for("paper")), Error);
  auto meta = nlohmann::json::parse(read_file(dir + "/meta.json"));
  meta["format_version"] = kResultFormatVersion + 1;
  write_file_atomically(dir + "/meta.json", meta.dump());
  try {
    ResultSet::load(dir);
    FAIL() << "a newer format must be refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("format version"), std::string::npos) << e.what();
  }
}

TEST(Compare, TablesAndRules) {
  std::string da = temp_dir("ca"), db = temp_dir("cb");
  {
    auto a = ResultSet::open_for_run(da, meta_for("quick"));
    a.add(cell("hcc", 32, 10.0, 3.0));
    a.add(cell("origin", 32, 10.0, 5.0));
    a.add(cell("ppc", 32, 10.0, 2.0));
    auto b = ResultSet::open_for_run(db, meta_for("quick"));
    b.add(cell("hcc", 32, 8.0, 3.0));    // 20 % slower
    b.add(cell("origin", 32, 10.5, 5.5));  // ANC changed
    b.add(cell("aila", 32, 10.0, 4.0));  // only in B
  }
  auto a = ResultSet::load(da), b = ResultSet::load(db);
  auto r = compare_result_sets(a, b, {"trace_mrays", "anc", "keys_hash"}, {});
  EXPECT_TRUE(r.violations.empty());
  EXPECT_NE(r.report.find("s/bounce1/hcc/32"), std::string::npos);
  EXPECT_NE(r.report.find("A only: `s/bounce1/ppc/32`"), std::string::npos);
  EXPECT_NE(r.report.find("B only: `s/bounce1/aila/32`"), std::string::npos);

  EXPECT_EQ(compare_result_sets(a, b, {}, {FailRule::parse("trace_mrays<-10%")}).violations.size(), 1u);
  EXPECT_EQ(compare_result_sets(a, b, {}, {FailRule::parse("trace_mrays<-25%")}).violations.size(), 0u);
  EXPECT_EQ(compare_result_sets(a, b, {}, {FailRule::parse("anc!=")}).violations.size(), 1u);
  EXPECT_EQ(compare_result_sets(a, b, {}, {FailRule::parse("anc!=0.6")}).violations.size(), 0u);
  EXPECT_EQ(compare_result_sets(a, b, {}, {FailRule::parse("keys_hash!=")}).violations.size(), 0u);
  EXPECT_EQ(compare_result_sets(a, b, {}, {FailRule::parse("missing")}).violations.size(), 1u);
  EXPECT_EQ(compare_result_sets(a, b, {}, {FailRule::parse("trace_mrays>+4%")}).violations.size(), 1u);
  EXPECT_THROW(FailRule::parse("speed<-5%"), Error);   // unknown metric
  EXPECT_THROW(FailRule::parse("anc<-"), Error);       // relative rule without a percentage
  EXPECT_THROW(FailRule::parse("keys_hash<-5%"), Error);
}

TEST(Matrix, RefusesImpossibleCombinationsBeforeWork) {
  MatrixSpec m = matrix_preset("quick");
  m.encoders = {"no-such-encoder"};
  EXPECT_THROW(validate_matrix(m), Error);
  m = matrix_preset("quick");
  m.resolution = "0x100";
  EXPECT_THROW(validate_matrix(m), Error);
  m = matrix_preset("quick");
  m.batches = {"bounce0"};
  EXPECT_THROW(validate_matrix(m), Error);
  m = matrix_preset("quick");
  m.encoders = {"mlhcc"};
  m.bits = {33};
  EXPECT_THROW(validate_matrix(m), Error);
  EXPECT_THROW(matrix_preset("nope"), Error);
  EXPECT_NO_THROW(validate_matrix(matrix_preset("quick")));
  EXPECT_NO_THROW(validate_matrix(matrix_preset("paper")));
}

// A small matrix end to end (the full quick preset runs in the golden test, scripts/golden.sh):
// every cell checks itself (permutation, hits equal NoSort). A rerun of the same command resumes:
// every encoder cell is skipped.
TEST(Matrix, EndToEndAndResume) {
  MatrixSpec spec = matrix_preset("quick");
  spec.scenes = {"cornell", "multi-instance"};
  spec.key_length_scenes = {"cornell"};
  spec.top_bits = {8};
  spec.resolution = "48x27";
  spec.reps = 1;
  spec.warmup = 0;
  RunOptions opts;
  opts.out = temp_dir("quick");
  RunSummary s = run_matrix(spec, opts);
  EXPECT_FALSE(s.interrupted);
  EXPECT_EQ(s.cells_failed, 0u);
  // 2 scenes x 3 batches x (NoSort + 10 encoders x (bits + top-k)); cornell runs 3 key lengths.
  EXPECT_EQ(s.cells_run, 3u * (1 + 10 * 4) + 3u * (1 + 10 * 2));
  auto rs = ResultSet::load(opts.out);
  for (auto& c : rs.cells()) {
    EXPECT_TRUE(c.ok()) << c.id() << ": " << c.error;
    EXPECT_TRUE(c.hits_match_nosort) << c.id();
    EXPECT_TRUE(c.order_is_permutation) << c.id();
    if (c.encoder != kBaselineEncoder) {
      EXPECT_GE(c.anc, 1.0) << c.id();
      EXPECT_LE(c.anc, 32.0) << c.id();
      EXPECT_GT(c.trace_mrays, 0.0) << c.id();
    }
  }
  std::string tables = read_file(opts.out + "/tables.md");
  EXPECT_NE(tables.find("## Trace speed, bounce1 rays"), std::string::npos);
  EXPECT_NE(tables.find("## Key length, cornell"), std::string::npos);
  EXPECT_NE(tables.find("## Top-k sorting"), std::string::npos);
  EXPECT_TRUE(fs::exists(opts.out + "/overhead-vs-gain-bounce1.png"));
  // meta.json fingerprints every cell's keys and order.
  auto meta = nlohmann::json::parse(read_file(opts.out + "/meta.json"));
  ASSERT_TRUE(meta.contains("fingerprints"));
  EXPECT_EQ(meta["fingerprints"].size(), rs.cells().size());
  EXPECT_EQ(meta["fingerprints"]["cornell/bounce1/hcc/32"]["keys"], rs.find("cornell/bounce1/hcc/32")->keys_hash);
  RunSummary again = run_matrix(spec, opts);
  EXPECT_EQ(again.cells_run, 0u);
  EXPECT_EQ(again.cells_skipped, s.cells_run - 2 * 3);  // NoSort cells are re-measured, not skipped
  EXPECT_EQ(ResultSet::load(opts.out).cells().size(), rs.cells().size());
}

// SIGKILL at several points, rerun after each: the final set equals an uninterrupted run's, each
// cell once, and no file is corrupt.
TEST(Matrix, KilledRunResumesToTheSameCells) {
  std::vector<std::string> args = {"run", "--scenes", "cornell", "--batches", "bounce1,shadow0",
                                   "--bits", "16,32", "--resolution", "40x30", "--reps", "1", "--warmup", "0"};
  std::string clean = temp_dir("clean"), killed = temp_dir("killed");
  auto with_out = [&](const std::string& out) {
    auto a = args;
    a.push_back("--out");
    a.push_back(out);
    return a;
  };
  ASSERT_EQ(run_cli(with_out(clean)), 0);
  // Deterministic kill points: SIGKILL right after the 3rd, 7th and 12th new cell of each run.
  for (int cells : {3, 7, 12}) EXPECT_EQ(run_cli(with_out(killed), -1, cells), -SIGKILL) << "kill after " << cells;
  // And at arbitrary moments (possibly mid-write, possibly after the run finished).
  for (int kill_ms : {150, 700}) run_cli(with_out(killed), kill_ms);
  ASSERT_EQ(run_cli(with_out(killed)), 0);
  auto a = ResultSet::load(clean), b = ResultSet::load(killed);
  EXPECT_EQ(deterministic(a), deterministic(b));
  std::size_t files = 0;
  for (auto& e : fs::directory_iterator(killed + "/cells")) files += e.path().extension() == ".json";
  EXPECT_EQ(files, b.cells().size());
  EXPECT_NO_THROW({
    auto parsed = nlohmann::json::parse(read_file(killed + "/cells.json"));
    EXPECT_EQ(parsed.size(), b.cells().size());
  });
}

}  // namespace raysort
