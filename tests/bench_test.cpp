// The benchmark matrix: result sets (atomic cells, resume, format version), compare and its
// regression rules, and the quick preset end to end at a tiny resolution, including a run killed
// with SIGKILL and resumed.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <thread>

#include "bench/compare.h"
#include "bench/learned_inputs.h"
#include "bench/result_set.h"
#include "bench/runner.h"
#include "bench/shard.h"
#include "bench/sweep.h"
#include "bvh/prepared_scene.h"
#include "encode/encode.h"
#include "render/batches.h"
#include "render/frame_memory.h"
#include "scene/provenance.h"
#include "test_util.h"
#include "trace/tracer.h"
#include "util/atomic_file.h"

namespace raysort {

namespace fs = std::filesystem;

namespace {

std::string temp_dir(const std::string& name) {
  const std::string p = raysort::testing::temp_path(name);  // removed when every test passed
  fs::create_directories(p);
  return p;
}

// Strings are moved in, not assigned from const char* (g++ 12 -O2 flags a false -Wrestrict there).
CellRecord cell(const std::string& encoder, unsigned bits, double mrays, double anc) {
  CellRecord c;
  c.scene = std::string("s"), c.batch = std::string("bounce1"), c.encoder = encoder, c.bits = bits, c.rays = 100;
  c.trace_mrays = mrays, c.speedup = {mrays / 10.0, NAN, NAN, 0}, c.anc = anc;
  c.keys_hash = std::string("00000000000000aa"), c.order_hash = std::string("00000000000000bb");
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

// detail-room at 64x36, 1 spp: the scene of the tests of the encoders' per-batch inputs.
const PreparedScene& tiny_detail_room() {
  static const PreparedScene p = [] {
    SceneOptions so;
    so.frame = {64, 36, 1};
    return prepare_scene("detail-room", so);
  }();
  return p;
}

// Two split trees of hcc-region are the same split by split (RsRegionSplit is a C struct).
void expect_same_splits(const std::vector<RsRegionSplit>& a, const std::vector<RsRegionSplit>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].axis, b[k].axis) << "split " << k;
    EXPECT_EQ(a[k].at, b[k].at) << "split " << k;
  }
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
  // Without intervals (as here, or in a version 1 set) a relative rule compares the points and says so.
  EXPECT_NE(compare_result_sets(a, b, {}, {FailRule::parse("trace_mrays<-10%")}).violations[0].find("point rule"),
            std::string::npos);
  EXPECT_THROW(FailRule::parse("speed<-5%"), Error);   // unknown metric
  EXPECT_THROW(FailRule::parse("anc<-"), Error);       // relative rule without a percentage
  EXPECT_THROW(FailRule::parse("keys_hash<-5%"), Error);
}

// A relative rule on a figure with intervals fires only when the change passes the threshold between
// the intervals' nearest ends: a point change inside the noise is reported as such, not as a
// regression.
TEST(Compare, RelativeRulesFireOnlyOnSignificantChanges) {
  std::string da = temp_dir("cia"), db = temp_dir("cib");
  auto with_speedup = [](const std::string& encoder, double v, double lo, double hi) {
    CellRecord c = cell(encoder, 32, 10.0, 2.0);
    c.speedup = {v, lo, hi, 12};
    return c;
  };
  {
    auto a = ResultSet::open_for_run(da, meta_for("quick"));
    a.add(with_speedup("hcc", 1.20, 1.17, 1.23));
    a.add(with_speedup("origin", 1.10, 1.08, 1.12));
    a.add(with_speedup("ppc", 1.30, 1.28, 1.32));
    a.add(with_speedup("aila", 1.30, 1.28, 1.32));
    auto b = ResultSet::open_for_run(db, meta_for("quick"));
    b.add(with_speedup("hcc", 1.10, 1.05, 1.18));     // 8 % lower, intervals overlap: noise
    b.add(with_speedup("origin", 1.00, 0.98, 1.02));  // 9 % lower, 1.02 < 0.95 · 1.08: a regression
    b.add(with_speedup("ppc", 1.29, 1.27, 1.31));     // within the threshold
    b.add(with_speedup("aila", 1.22, 1.21, 1.23));    // 6 % lower, apart, but 1.23 > 0.95 · 1.28
  }
  auto a = ResultSet::load(da), b = ResultSet::load(db);
  const CompareResult r = compare_result_sets(a, b, {"speedup"}, {FailRule::parse("speedup<-5%")});
  ASSERT_EQ(r.violations.size(), 1u);
  EXPECT_NE(r.violations[0].find("s/bounce1/origin/32"), std::string::npos) << r.violations[0];
  ASSERT_EQ(r.within_noise.size(), 2u);
  EXPECT_NE(r.within_noise[0].find("s/bounce1/aila/32"), std::string::npos) << r.within_noise[0];
  EXPECT_NE(r.within_noise[1].find("s/bounce1/hcc/32"), std::string::npos) << r.within_noise[1];
  // With a 0 % threshold, any change whose intervals are apart fires.
  EXPECT_EQ(compare_result_sets(a, b, {}, {FailRule::parse("speedup<-0%")}).violations.size(), 2u);
  EXPECT_NE(r.report.find("1.2 [1.17, 1.23]"), std::string::npos) << r.report;
  EXPECT_NE(r.report.find("**apart**"), std::string::npos);
  // The same rule as a rise, and deterministic rules stay exact.
  EXPECT_TRUE(compare_result_sets(a, b, {}, {FailRule::parse("speedup>+5%")}).violations.empty());
  EXPECT_TRUE(compare_result_sets(a, b, {}, {FailRule::parse("anc!=")}).violations.empty());
}

// NoSort's ANC is null (no keys): null in both sets is no change, null in one set only is one, for
// the exact rule and the absolute one; and a set written before the fix (NoSort ANC 0) reads as null.
TEST(Compare, NullFiguresAreEqualOnlyToNull) {
  std::string da = temp_dir("cna"), db = temp_dir("cnb");
  {
    auto a = ResultSet::open_for_run(da, meta_for("quick"));
    a.add(cell("nosort", 0, 10.0, NAN));
    a.add(cell("hcc", 32, 10.0, NAN));
    auto b = ResultSet::open_for_run(db, meta_for("quick"));
    b.add(cell("nosort", 0, 11.0, NAN));
    b.add(cell("hcc", 32, 10.0, 2.5));
  }
  auto a = ResultSet::load(da), b = ResultSet::load(db);
  EXPECT_TRUE(std::isnan(a.find("s/bounce1/nosort/0")->anc));
  for (const char* rule : {"anc!=", "anc!=0.5"}) {
    const auto v = compare_result_sets(a, b, {}, {FailRule::parse(rule)}).violations;
    ASSERT_EQ(v.size(), 1u) << rule;
    EXPECT_NE(v[0].find("s/bounce1/hcc/32"), std::string::npos) << v[0];
  }
  nlohmann::json old_nosort = cell("nosort", 0, 10.0, 0.0);
  EXPECT_EQ(old_nosort.at("anc"), 0.0);
  EXPECT_TRUE(std::isnan(nlohmann::json::parse(old_nosort.dump()).get<CellRecord>().anc));  // as read from a file
  EXPECT_TRUE(nlohmann::json(cell("nosort", 0, 10.0, NAN)).at("anc").is_null());
}

// Result sets of format version 1 (point figures) stay readable, so older sets can be compared.
TEST(ResultSet, ReadsFormatVersionOne) {
  std::string dir = temp_dir("v1");
  fs::create_directories(dir + "/cells");
  write_file_atomically(dir + "/meta.json", R"({"format_version": 1, "matrix": {"preset": "quick"}})");
  write_file_atomically(dir + "/cells/s__bounce1__hcc__32.json", R"({
    "format_version": 1, "id": "s/bounce1/hcc/32", "scene": "s", "batch": "bounce1", "encoder": "hcc", "bits": 32,
    "top_bits": 0, "variant": "robust", "access": "gather", "rays": 100, "status": "ok", "error": "",
    "trace_mrays": 12.5, "speedup": 1.25, "net_speedup": 1.1, "overhead_pct": 12.0, "anc": 1.5,
    "simt_lane_efficiency": 0.5, "simt_distinct_per_visit": 0.3, "simt_lane_efficiency_ratio": 1.2,
    "simt_distinct_per_visit_ratio": 0.8, "hits_match_nosort": true, "order_is_permutation": true,
    "keys_hash": "00000000000000aa", "order_hash": "00000000000000bb",
    "encode_ms": {"median": 1, "min": 1, "max": 1}, "sort_ms": {"median": 2, "min": 2, "max": 2},
    "trace_ms": {"median": 8, "min": 7, "max": 9}})");
  auto rs = ResultSet::load(dir);
  const CellRecord* c = rs.find("s/bounce1/hcc/32");
  ASSERT_NE(c, nullptr);
  EXPECT_DOUBLE_EQ(c->speedup.value, 1.25);
  EXPECT_FALSE(c->speedup.has_interval());
  EXPECT_DOUBLE_EQ(c->trace.median_ms, 8.0);
  // A run does not resume into it: it would mix two formats in one set.
  EXPECT_THROW(ResultSet::open_for_run(dir, meta_for("quick")), Error);
}

// Counts read from a cell file are counts: a float format version or key length is refused, never
// cast to an integer (undefined for 7.8e50; found by fuzz/result_set_fuzzer). test-sanitize runs
// this under UBSan.
TEST(ResultSet, FloatCountsAreRefusedNotCast) {
  std::string dir = temp_dir("float-counts");
  fs::create_directories(dir + "/cells");
  write_file_atomically(dir + "/meta.json", R"({"format_version": 2, "matrix": {"preset": "quick"}})");
  for (const char* field : {R"("format_version": 7.77778e+50, "bits": 32)", R"("format_version": 1, "bits": 1e300)",
                            R"("format_version": 1, "bits": 32.5)", R"("format_version": -1, "bits": 32)"}) {
    write_file_atomically(dir + "/cells/s__bounce1__hcc__32.json", std::string("{") + field + R"(, "id": "s/bounce1/hcc/32", "scene": "s", "batch": "bounce1", "encoder": "hcc", "top_bits": 0})");
    EXPECT_THROW(ResultSet::load(dir), Error) << field;
  }
}

TEST(Matrix, RefusesImpossibleCombinationsBeforeWork) {
  // The command line's text is refused where it is parsed, naming the value and the valid ones.
  EXPECT_THROW(parse_encoders({"no-such-encoder"}), Error);
  EXPECT_EQ(parse_encoders({"all"}).size(), all_encoders().size());
  EXPECT_EQ(parse_encoders({"HCC", "hierarchy_cut", "regular-grid"}), (std::vector<Encoder>{Encoder::HCC, Encoder::RegularGrid}));
  EXPECT_THROW(parse_resolution("0x100"), Error);
  EXPECT_THROW(parse_resolution("640x"), Error);
  EXPECT_THROW(parse_ray_accesses("gather,scatter"), Error);
  EXPECT_EQ(parse_ray_accesses("all").size(), 2u);
  EXPECT_THROW(parse_trace_variants("robust,slow"), Error);
  EXPECT_EQ(parse_trace_variants("both"), (std::vector<TraceVariant>{TraceVariant::Robust, TraceVariant::Fast}));
  EXPECT_EQ(parse_trace_variants("fast,robust,fast"), (std::vector<TraceVariant>{TraceVariant::Fast, TraceVariant::Robust}));
  // What parsing cannot see, validate_matrix refuses before any work.
  MatrixSpec m = matrix_preset("quick");
  m.frame.width = 0;
  EXPECT_THROW(validate_matrix(m), Error);
  m = matrix_preset("quick");
  m.batches = {"bounce0"};
  EXPECT_THROW(validate_matrix(m), Error);
  m = matrix_preset("quick");
  m.encoders = {Encoder::MLHCC};
  m.bits = {33};
  EXPECT_THROW(validate_matrix(m), Error);
  m = matrix_preset("quick");
  m.accesses.clear();
  EXPECT_THROW(validate_matrix(m), Error);
  m = matrix_preset("quick");
  m.max_noise = 0;
  EXPECT_THROW(validate_matrix(m), Error);
  m = matrix_preset("quick");
  m.max_time_s = -1;
  EXPECT_THROW(validate_matrix(m), Error);
  EXPECT_THROW(matrix_preset("nope"), Error);
  EXPECT_NO_THROW(validate_matrix(matrix_preset("quick")));
  EXPECT_NO_THROW(validate_matrix(matrix_preset("paper")));
}

// Issue 22: the appendix tables. HCC against HCC_DIR and HCC one bit shorter (Table 8), and the
// subsequent-bounce table, each with the best SIMT lane-efficiency ratio in bold; neither appears
// in a set without its cells.
TEST(Tables, HccDirAndSubsequentBounceTables) {
  auto with = [](CellRecord c, const std::string& batch, double lanes) {
    c.batch = batch, c.simt_lane_efficiency_ratio = lanes;
    return c;
  };
  CellRecord nosort = cell(kBaselineEncoder, 0, 10.0, NAN);
  std::vector<CellRecord> cells{with(nosort, "bounce1", 1.0),          with(cell("hcc", 32, 13.0, 2.0), "bounce1", 1.31),
                                with(cell("hcc-dir", 32, 12.0, 2.0), "bounce1", 1.22),
                                with(cell("hcc", 31, 12.5, 2.0), "bounce1", 1.27)};
  const std::string no_bounces = render_tables(cells, meta_for("paper-hcc-dir"));
  EXPECT_NE(no_bounces.find("## HCC with direction information (paper appendix Table 8), bounce1 rays"), std::string::npos)
      << no_bounces;
  EXPECT_NE(no_bounces.find("| scene | HCC 32b | HCC_DIR 32b | HCC 31b |"), std::string::npos) << no_bounces;
  EXPECT_NE(no_bounces.find("| s | 13.00 (1.300 · **1.310**) | 12.00 (1.200 · 1.220) | 12.50 (1.250 · 1.270) |"),
            std::string::npos) << no_bounces;
  EXPECT_EQ(no_bounces.find("Subsequent bounces"), std::string::npos);

  std::vector<CellRecord> deep{with(nosort, "bounce1", 1.0), with(nosort, "bounce2", 1.0),
                               with(cell("hcc", 32, 13.0, 2.0), "bounce1", 1.31),
                               with(cell("hcc", 32, 11.0, 2.0), "bounce2", 1.08),
                               with(cell("ppc", 32, 12.0, 2.0), "bounce1", 1.25),
                               with(cell("ppc", 32, 12.0, 2.0), "bounce2", 1.12)};
  deep[1].rays = 60;
  const std::string md = render_tables(deep, meta_for("paper-bounces"));
  EXPECT_NE(md.find("## Subsequent bounces, s, 32-bit keys, access gather"), std::string::npos) << md;
  EXPECT_NE(md.find("| rays | 100 | 60 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| hcc | 1.300 · **1.310** | 1.100 · 1.080 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| ppc | 1.200 · 1.250 | 1.200 · **1.120** |"), std::string::npos) << md;
  EXPECT_EQ(md.find("HCC with direction information"), std::string::npos);
}

// Issue 22: a hyperparameter sweep is read from sets that differ in one encoder parameter only,
// laid out one column per value (ascending) with the row's best lane-efficiency ratio in bold.
TEST(Sweep, SetsDifferingInOneParameterSideBySide) {
  auto make_set = [](const std::string& name, nlohmann::json matrix, double lanes) {
    const std::string dir = temp_dir(name);
    nlohmann::json meta = meta_for("paper-1spp");
    for (auto& [k, v] : matrix.items()) meta["matrix"][k] = v;
    auto rs = ResultSet::open_for_run(dir, meta);
    CellRecord c = cell("hcc", 32, 13.0, 2.0);
    c.simt_lane_efficiency_ratio = lanes;
    rs.add(c);
    return dir;
  };
  const std::string a = make_set("sweep-a", {{"had_lambda", 0.5}, {"spp", 1}}, 1.10);
  const std::string b = make_set("sweep-b", {{"had_lambda", 0.125}, {"spp", 1}}, 1.25);
  const Sweep sweep = load_sweep({a, b});
  EXPECT_EQ(sweep.parameter, "had_lambda");
  ASSERT_EQ(sweep.points.size(), 2u);
  EXPECT_EQ(sweep.points[0].value, 0.125);
  const std::string md = render_sweep(sweep);
  EXPECT_NE(md.find("# Sweep of λ (HAD, Eq. 1)"), std::string::npos) << md;
  EXPECT_NE(md.find("## hcc 32-bit, bounce1 rays, access gather\n\n| scene | 0.125 | 0.5 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| s | **1.250** · 1.30 | 1.100 · 1.30 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| mean lane ratio | 1.250 | 1.100 |"), std::string::npos) << md;

  // Another difference (spp), no difference, and a repeated value are refused with the reason.
  const std::string c = make_set("sweep-c", {{"had_lambda", 1.0}, {"spp", 8}}, 1.0);
  auto refusal = [](const std::vector<std::string>& dirs) {
    try {
      load_sweep(dirs);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(refusal({a, c}).find("differ in spp as well"), std::string::npos) << refusal({a, c});
  EXPECT_NE(refusal({a, a}).find("the sets ran the same matrix"), std::string::npos) << refusal({a, a});
  EXPECT_NE(refusal({a}).find("two or more result sets"), std::string::npos);

  // The knobs of the encoders beyond the paper (issue 21) are sweepable too.
  const std::string r2 = make_set("sweep-r2", {{"region_bits", 2}}, 1.2);
  const std::string r4 = make_set("sweep-r4", {{"region_bits", 4}}, 1.3);
  const Sweep regions = load_sweep({r4, r2});
  EXPECT_EQ(regions.parameter, "region_bits");
  EXPECT_EQ(regions.points[0].value, 2.0);
  EXPECT_NE(render_sweep(regions).find("hcc-region region bits"), std::string::npos);
  const std::string t0 = make_set("sweep-t0", {{"traffic_blend", 0.0}}, 1.2);
  const std::string t1 = make_set("sweep-t1", {{"traffic_blend", 1.0}}, 1.3);
  EXPECT_EQ(load_sweep({t0, t1}).parameter, "traffic_blend");
}

// A matrix records the new encoders' knobs only when it runs them, so the sets written before they
// existed keep their meta.json entry (and resume).
TEST(Matrix, NewEncoderKnobsAreRecordedOnlyWhenRun) {
  MatrixSpec spec;
  spec.encoders = {Encoder::HCC};
  EXPECT_FALSE(spec.to_json().contains("region_bits"));
  EXPECT_FALSE(spec.to_json().contains("traffic_blend"));
  spec.encoders = {Encoder::HCC_REGION};
  spec.params.region_bits = 5;
  EXPECT_EQ(spec.to_json().at("region_bits"), 5);
  EXPECT_EQ(spec.to_json().at("traffic_blend"), 0.5);  // hcc-region's cuts blend traffic too
  spec.encoders = {Encoder::HCC_TRAFFIC};
  spec.params.traffic_blend = 0.25;
  EXPECT_EQ(spec.to_json().at("traffic_blend"), 0.25);
  EXPECT_FALSE(spec.to_json().contains("region_bits"));
  spec.encoders = {Encoder::MLHCC_COST};
  EXPECT_FALSE(spec.to_json().contains("cost_bits"));  // the default, an eighth of the key
  spec.params.cost_bits = 6;
  EXPECT_EQ(spec.to_json().at("cost_bits"), 6);
  EXPECT_EQ(matrix_preset("paper").encoders, all_encoders());  // all three in the paper preset
}

// Issue 41: the list axes of the command line (variant, access mode, baseline order) are parsed by
// one parser; each refuses an unknown name and an empty list with the same sentences as before.
TEST(ListAxes, OneParserForEveryAxis) {
  auto refusal = [](auto parse) {
    try {
      parse();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(refusal([] { parse_trace_variants("robust,slow"); }),
            "--variant 'slow': the trace variants are robust and fast (or both)");
  EXPECT_EQ(refusal([] { parse_trace_variants(","); }), "--variant: name at least one trace variant (robust, fast)");
  EXPECT_EQ(refusal([] { parse_ray_accesses("gather,scatter"); }),
            "--access 'scatter': the access modes are gather and permute (or all)");
  EXPECT_EQ(refusal([] { parse_baseline_orders(""); }), "--baseline: name at least one baseline order (pixel, shuffled)");
  EXPECT_EQ(refusal([] { parse_baseline_orders("pixel,random"); }),
            "--baseline 'random': the baseline orders are pixel and shuffled (or all)");
  EXPECT_EQ(parse_baseline_orders("shuffled,pixel,shuffled"),
            (std::vector<BaselineOrder>{BaselineOrder::Shuffled, BaselineOrder::Pixel}));
  EXPECT_EQ(parse_trace_variants("all"), (std::vector<TraceVariant>{TraceVariant::Robust, TraceVariant::Fast}));
  EXPECT_EQ(parse_ray_accesses("all"), (std::vector<RayAccess>{RayAccess::Gather, RayAccess::Permute}));
}

// mlhcc-cost is causal (issue 21): its estimates for a batch come from the same batch of another
// frame (seed + 1), traced on the host; never from the frame being measured.
TEST(Matrix, CostEstimatesComeFromAnotherFrame) {
  const PreparedScene& p = tiny_detail_room();
  const EncodeScene keys(p.bvh, p.scene.bounds());
  RayGenOptions gen;
  gen.seed = 7;
  LearnedInputs learned(p, gen, keys, {Encoder::MLHCC_COST});
  RayGenOptions next = gen;
  next.seed = 8;
  const std::vector<ReferencedBatch> other = generate_batches(p.scene, p.tris, p.bvh, next);
  const std::vector<ReferencedBatch> own = generate_batches(p.scene, p.tris, p.bvh, gen);
  auto means_of = [&](LearnedInputs& from, const std::string& name) -> const std::vector<std::uint64_t>* {
    const LearnedInputs::Learned* l = from.learned(Encoder::MLHCC_COST, name, {}, keys);
    return l && l->input ? &dynamic_cast<const CostEstimates&>(*l->input).mean_steps : nullptr;
  };
  for (std::size_t k = 0; k < other.size(); ++k) {
    const std::string& name = other[k].batch.name;
    const std::vector<std::uint64_t>* means = means_of(learned, name);
    ASSERT_NE(means, nullptr) << name;
    std::vector<std::uint32_t> steps;
    trace_reference(p.bvh, other[k].batch.rays, nullptr, other[k].batch.any_hit(), &steps);
    EXPECT_EQ(*means, cost_statistics(keys.frame(), other[k].batch.rays, steps)) << name;
    EXPECT_GE(learned.learned(Encoder::MLHCC_COST, name, {}, keys)->ms, 0.0) << name;
    // hcc-region was not asked for: nothing studied for it.
    EXPECT_EQ(learned.learned(Encoder::HCC_REGION, name, {}, keys)->input, nullptr) << name;
    // The measured frame's own statistics differ: its rays are not the ones counted.
    std::vector<std::uint32_t> own_steps;
    trace_reference(p.bvh, own[k].batch.rays, nullptr, own[k].batch.any_hit(), &own_steps);
    EXPECT_NE(*means, cost_statistics(keys.frame(), own[k].batch.rays, own_steps)) << name;
  }
  // Only the batches asked for are traced (a matrix's batches).
  LearnedInputs some(p, gen, keys, {Encoder::MLHCC_COST}, {"bounce1", "shadow9"});
  ASSERT_NE(means_of(some, "bounce1"), nullptr);
  EXPECT_EQ(*means_of(some, "bounce1"), *means_of(learned, "bounce1"));
  EXPECT_EQ(means_of(some, "shadow0"), nullptr);
}

// A previous frame whose batch has no rays (every primary ray missed, say) still gives hcc-region
// statistics of the right shape: every split halves its cell, no region has traffic, and every
// region's cut is HCC's.
TEST(Matrix, RegionStatisticsOfAnEmptyBatch) {
  const PreparedScene& p = tiny_detail_room();
  EncoderParams params;
  params.region_bits = 3;
  EncodeScene keys(p.bvh, p.scene.bounds(), params);
  const RegionStatistics stats = region_statistics(p.bvh, p.scene.bounds(), {}, false, 3);
  ASSERT_EQ(stats.splits.size(), 7u);
  ASSERT_EQ(stats.visits.size(), 8u);
  for (const auto& region : stats.visits) EXPECT_TRUE(region.empty());
  const std::vector<RsRegionSplit> halves = median_region_splits(p.scene.bounds(), {}, 3);
  const Aabb box = p.scene.bounds();
  rs_u32 longest = 0;
  for (rs_u32 a = 1; a < 3; ++a)
    if (box.max[a] - box.min[a] > box.max[longest] - box.min[longest]) longest = a;
  EXPECT_EQ(halves[0].axis, longest);
  EXPECT_EQ(halves[0].at, 0.5f * (box.min[longest] + box.max[longest]));
  expect_same_splits(stats.splits, halves);
  set_region_statistics(keys, stats);
  for (const auto& cut : region_inputs(keys, 32).cuts) EXPECT_EQ(cut, keys.hcc_cut(29));
}

// hcc-region is causal too: its splits and per-region traffic for a batch come from the same batch
// of the frame of seed + 1, for the encoder's region bits and scene box.
TEST(Matrix, RegionStatisticsComeFromAnotherFrame) {
  const PreparedScene& p = tiny_detail_room();
  EncoderParams params;
  params.region_bits = 2;
  const EncodeScene keys(p.bvh, p.scene.bounds(), params);
  RayGenOptions gen;
  gen.seed = 7;
  LearnedInputs learned(p, gen, keys, {Encoder::HCC_REGION}, {"bounce1"});
  EXPECT_EQ(learned.learned(Encoder::HCC_REGION, "shadow0", {}, keys)->input, nullptr);  // not asked for
  EXPECT_EQ(learned.learned(Encoder::MLHCC_COST, "bounce1", {}, keys)->input, nullptr);  // not asked for
  const LearnedInputs::Learned* l = learned.learned(Encoder::HCC_REGION, "bounce1", {}, keys);
  ASSERT_TRUE(l && l->input);
  const RegionStatistics& b = dynamic_cast<const LearnedRegions&>(*l->input).stats;
  ASSERT_EQ(b.splits.size(), 3u);
  ASSERT_EQ(b.visits.size(), 4u);
  RayGenOptions next = gen;
  next.seed = 8;
  const auto other = generate_batches(p.scene, p.tris, p.bvh, next);
  const auto own = generate_batches(p.scene, p.tris, p.bvh, gen);
  auto bounce1 = [](const std::vector<ReferencedBatch>& frame) -> const ReferencedBatch& {
    return *std::find_if(frame.begin(), frame.end(), [](const ReferencedBatch& x) { return x.batch.name == "bounce1"; });
  };
  const RegionStatistics expected = region_statistics(p.bvh, p.scene.bounds(), bounce1(other).batch.rays, false, 2);
  EXPECT_EQ(b.visits, expected.visits);
  expect_same_splits(b.splits, expected.splits);
  const RegionStatistics from_own = region_statistics(p.bvh, p.scene.bounds(), bounce1(own).batch.rays, false, 2);
  EXPECT_NE(b.visits, from_own.visits);
  // The regions' traffic adds up to the batch's: every ray starts in exactly one region.
  const std::vector<std::uint64_t> all = node_traffic(p.bvh, bounce1(other).batch.rays, false);
  std::vector<std::uint64_t> sum(all.size(), 0);
  for (const auto& region : b.visits)
    for (const auto& [node, count] : region) sum[node] += count;
  EXPECT_EQ(sum, all);
}

namespace {

// hcc-traffic's input for batch `name` of `frame`, as the runner's LearnedInputs makes it.
std::vector<std::uint64_t> traffic_before(const PreparedScene& p, const std::vector<ReferencedBatch>& frame,
                                          const std::string& name) {
  const EncodeScene keys(p.bvh, p.bvh.bounds());
  LearnedInputs learned(p, {}, keys, {});  // no encoder that learns from a previous frame: none drawn
  const LearnedInputs::Learned* l = learned.learned(Encoder::HCC_TRAFFIC, name, frame, keys);
  return l && l->input ? dynamic_cast<const NodeTraffic&>(*l->input).visits : std::vector<std::uint64_t>{};
}

}  // namespace

// hcc-traffic is causal (issue 21): the traffic for batch k is the previous batch's node traffic,
// and it does not change when batch k or any later batch changes; the frame's first batch has none.
TEST(Matrix, TrafficForABatchComesOnlyFromTheBatchBefore) {
  const PreparedScene& p = tiny_detail_room();
  std::vector<ReferencedBatch> frame = generate_batches(p.scene, p.tris, p.bvh, {});
  ASSERT_GE(frame.size(), 4u);
  EXPECT_EQ(frame[0].batch.name, "primary");
  EXPECT_TRUE(traffic_before(p, frame, "primary").empty());
  EXPECT_TRUE(traffic_before(p, frame, "bounce9").empty());  // not in the frame
  for (std::size_t k = 1; k < frame.size(); ++k) {
    const std::string name = frame[k].batch.name;
    const auto traffic = traffic_before(p, frame, name);
    EXPECT_EQ(traffic, node_traffic(p.bvh, frame[k - 1].batch.rays, frame[k - 1].batch.any_hit())) << name;
    EXPECT_GT(traffic.at(0), 0u) << name;
    // Batch k and the later ones replaced (rays moved and turned): the same traffic for k.
    std::vector<ReferencedBatch> changed = frame;
    for (std::size_t j = k; j < changed.size(); ++j)
      for (RsRay& r : changed[j].batch.rays) r.d[0] = -r.d[0], r.o[1] += 0.1f;
    EXPECT_EQ(traffic_before(p, changed, name), traffic) << name;
    // The batch before it changed: other traffic.
    std::vector<ReferencedBatch> earlier = frame;
    for (RsRay& r : earlier[k - 1].batch.rays) r.d[0] = -r.d[0], r.d[2] = -r.d[2];
    EXPECT_NE(traffic_before(p, earlier, name), traffic) << name;
  }
  // The cut built from it: β = 0 gives HCC's cut whatever the traffic.
  EncoderParams p0;
  p0.traffic_blend = 0.0;
  EncodeScene s0(p.bvh, p.bvh.bounds(), p0);
  set_node_traffic(s0, traffic_before(p, frame, frame[2].batch.name));
  EXPECT_EQ(traffic_cut(s0, 32), s0.hcc_cut(32));
}

// Issue 22: the paper preset samples as the paper did (§5: "two shadow rays per bounce and eight
// samples per pixel") at 1920×1080. The batch sizes it implies for one of its scenes, exactly, and
// the same overrides on a frame small enough to generate here.
TEST(MatrixPreset, PaperSamplesAsThePaper) {
  const MatrixSpec paper = matrix_preset("paper");
  EXPECT_EQ(paper.frame.width, 1920u);
  EXPECT_EQ(paper.frame.height, 1080u);
  EXPECT_EQ(paper.frame.spp, 8u);
  EXPECT_EQ(paper.frame.shadow_rays, 2u);
  EXPECT_EQ(paper.to_json().at("shadow_rays"), 2);
  const SceneFacts f = load_scene_facts("detail-room", paper, "");
  EXPECT_EQ(f.rays_per_batch, 16'588'800u);  // 1920 × 1080 × 8 paths: bounce1 at most
  EXPECT_EQ(f.shadow_rays_per_bounce, 2u);   // the scene file says 1
  const FrameMemory m = estimate_frame_memory(1920, 1080, 8, f.shadow_rays_per_bounce, f.max_bounces);
  EXPECT_EQ(m.paths, 16'588'800u);
  EXPECT_EQ(m.largest_batch, 33'177'600u);   // shadow0: two per path
  EXPECT_NO_THROW(check_frame_memory(m, nullptr, "paper preset")) << "the paper preset must fit this machine";

  // paper-1spp: the same matrix at 1 spp and the scenes' own shadow rays (no override recorded).
  const MatrixSpec one = matrix_preset("paper-1spp");
  EXPECT_EQ(one.scenes, paper.scenes);
  EXPECT_EQ(one.batches, paper.batches);
  EXPECT_EQ(one.frame.spp, 1u);
  EXPECT_EQ(one.frame.shadow_rays, 0u);
  EXPECT_FALSE(one.to_json().contains("shadow_rays"));
  EXPECT_EQ(load_scene_facts("detail-room", one, "").shadow_rays_per_bounce, 1u);
  EXPECT_EQ(load_scene_facts("detail-room", one, "").rays_per_batch, 2'073'600u);

  // Generated: 8 samples per pixel make 8 primary rays per pixel, and 2 shadow rays per bounce
  // give each diffuse hit two candidate shadow rays (those toward a light below the surface are
  // dropped), so shadow0 grows toward twice its 1-ray size and never past 2 per primary hit.
  auto batches_at = [](std::uint32_t shadow_rays) {
    const PreparedScene p = prepare_scene("detail-room", SceneOptions{"", FrameSize{16, 9, 8, shadow_rays, 0}});
    std::map<std::string, std::size_t> sizes;
    for (const auto& b : generate_batches(p.scene, p.tris, p.bvh, RayGenOptions{})) sizes[b.batch.name] = b.batch.size();
    return sizes;
  };
  auto one_ray = batches_at(1), two_rays = batches_at(2);
  EXPECT_EQ(two_rays.at("primary"), 16u * 9u * 8u);
  EXPECT_EQ(one_ray.at("primary"), two_rays.at("primary"));
  EXPECT_EQ(one_ray.at("bounce1"), two_rays.at("bounce1"));
  EXPECT_GT(two_rays.at("shadow0"), one_ray.at("shadow0") * 3 / 2);
  EXPECT_LE(two_rays.at("shadow0"), 2 * two_rays.at("primary"));

  // Every preset is a valid matrix; paper-bounces reaches bounce 5, paper-hcc-dir runs HCC at 31 bits.
  for (const auto& name : preset_names()) EXPECT_NO_THROW(validate_matrix(matrix_preset(name))) << name;
  const MatrixSpec bounces = matrix_preset("paper-bounces");
  EXPECT_EQ(bounces.frame.bounces, 5u);
  EXPECT_EQ(load_scene_facts("detail-room", bounces, "").max_bounces, 5u);
  EXPECT_EQ(matrix_preset("paper-hcc-dir").bits_for("sibenik"), (std::vector<unsigned>{31, 32}));
}

// A small matrix end to end (the full quick preset runs in the golden test, scripts/golden.sh):
// every cell checks itself (permutation, hits equal NoSort). A rerun of the same command resumes:
// every encoder cell is skipped.
TEST(Matrix, EndToEndAndResume) {
  MatrixSpec spec = matrix_preset("quick");
  spec.scenes = {"cornell", "multi-instance"};
  spec.key_length_scenes = {"cornell"};
  spec.top_bits = {8};
  spec.frame = {48, 27, 1};
  spec.reps = 1;
  spec.warmup = 0;
  spec.max_time_s = 0;
  RunOptions opts;
  opts.out = temp_dir("quick");
  RunSummary s = run_matrix(spec, opts);
  EXPECT_FALSE(s.interrupted);
  EXPECT_EQ(s.cells_failed, 0u);
  // 2 trace classes (wide, packet) x 2 scenes x 3 batches x (NoSort + 13 encoders x (bits + top-k)
  // x 2 access modes); cornell runs 3 key lengths.
  EXPECT_EQ(s.cells_run, 2u * (3u * (1 + 13 * 4 * 2) + 3u * (1 + 13 * 2 * 2)));
  auto rs = ResultSet::load(opts.out);
  for (auto& c : rs.cells()) {
    EXPECT_TRUE(c.ok()) << c.id() << ": " << c.error;
    EXPECT_TRUE(c.hits_match_nosort) << c.id();
    EXPECT_TRUE(c.order_is_permutation) << c.id();
    EXPECT_EQ(c.rounds, 1u) << c.id();  // --reps 1 and no time to sample more
    EXPECT_EQ(c.samples.at("nosort").size(), 1u) << c.id();
    if (c.encoder == kBaselineEncoder) {
      EXPECT_TRUE(std::isnan(c.anc)) << c.id() << ": NoSort has no keys, its ANC is null";
    } else {
      EXPECT_GE(c.anc, 1.0) << c.id();
      EXPECT_LE(c.anc, 32.0) << c.id();
      EXPECT_GT(c.trace_mrays, 0.0) << c.id();
      EXPECT_EQ(c.samples.count("permute"), c.access == "permute" ? 1u : 0u) << c.id();
      // One round has no interval: the figures say so rather than invent one.
      EXPECT_FALSE(c.speedup.has_interval() && !c.same_order_as_nosort) << c.id();
    }
  }
  // hcc-traffic, hcc-region and mlhcc-cost (issue 21): every cell records its per-batch host cost
  // (the traffic count and cut; the previous frame's statistics, cuts and tables), no other cell does; on primary (no
  // earlier batch) hcc-traffic's cut is HCC's, so are its keys; later it uses the previous batch's
  // traffic.
  for (auto& c : rs.cells()) {
    if (c.encoder == "hcc-traffic" || c.encoder == "hcc-region" || c.encoder == "mlhcc-cost") {
      EXPECT_GE(c.cut_ms, 0.0) << c.id();
    } else {
      EXPECT_EQ(c.cut_ms, -1.0) << c.id();
    }
  }
  for (const std::string scene : {"cornell", "multi-instance"})
    EXPECT_EQ(rs.find(scene + "/primary/hcc-traffic/32")->keys_hash, rs.find(scene + "/primary/hcc/32")->keys_hash);
  EXPECT_NE(rs.find("multi-instance/bounce1/hcc-traffic/32")->keys_hash,
            rs.find("multi-instance/bounce1/hcc/32")->keys_hash);
  EXPECT_NE(read_file(opts.out + "/cells.csv").find(",cut_ms,"), std::string::npos);
  std::string tables = read_file(opts.out + "/tables.md");
  EXPECT_NE(tables.find("## Trace speed, bounce1 rays"), std::string::npos);
  EXPECT_NE(tables.find("access permute"), std::string::npos);
  EXPECT_NE(tables.find("## Gather against permute"), std::string::npos);
  EXPECT_NE(tables.find("## Key length, cornell"), std::string::npos);
  EXPECT_NE(tables.find("## Top-k sorting"), std::string::npos);
  EXPECT_NE(tables.find("## Noise floor"), std::string::npos);
  EXPECT_TRUE(fs::exists(opts.out + "/overhead-vs-gain-bounce1-32b.png"));
  EXPECT_TRUE(fs::exists(opts.out + "/overhead-vs-gain-bounce1-32b-permute.png"));
  // The packet class beside it: its own section, plots and ids.
  const std::string packet = trace_layout_name(resolve_trace_layout(TraceLayout::Packet, select_device("")));
  EXPECT_NE(tables.find("## Trace classes"), std::string::npos);
  EXPECT_TRUE(fs::exists(opts.out + "/overhead-vs-gain-bounce1-32b-" + packet + ".png"));
  EXPECT_NE(rs.find("cornell/bounce1/hcc/32/" + packet + "/permute"), nullptr);
  // meta.json fingerprints every cell's keys and order.
  auto meta = nlohmann::json::parse(read_file(opts.out + "/meta.json"));
  EXPECT_EQ(meta["matrix"]["region_bits"], 4);  // the new encoders' knobs, since the matrix runs them
  EXPECT_EQ(meta["matrix"]["traffic_blend"], 0.5);
  ASSERT_TRUE(meta.contains("fingerprints"));
  EXPECT_EQ(meta["fingerprints"].size(), rs.cells().size());
  EXPECT_EQ(meta["fingerprints"]["cornell/bounce1/hcc/32"]["keys"], rs.find("cornell/bounce1/hcc/32")->keys_hash);
  // raysort report writes the views and plots again from the cell files alone.
  fs::remove(opts.out + "/tables.md");
  fs::remove(opts.out + "/overhead-vs-gain-bounce1-32b.png");
  ASSERT_EQ(run_cli({"report", opts.out}), 0);
  EXPECT_EQ(read_file(opts.out + "/tables.md"), tables);
  EXPECT_TRUE(fs::exists(opts.out + "/overhead-vs-gain-bounce1-32b.png"));
  RunSummary again = run_matrix(spec, opts);
  EXPECT_EQ(again.cells_run, 0u);
  // Every cell carries its own NoSort traces, so NoSort cells are skipped like the others.
  EXPECT_EQ(again.cells_skipped, s.cells_run);
  EXPECT_EQ(ResultSet::load(opts.out).cells().size(), rs.cells().size());
}

// The case that made the old runner report 1.9x: on primary rays every origin is the camera, so
// Origin's keys are all equal, the stable sort keeps the generation order, and the sorted trace is
// the NoSort trace. Such a cell is flagged and reports exactly 1, and what its rounds measured
// (NoSort against the same order, paired) stays near 1 too: the protocol treats both arms alike.
// A cell whose order does differ is not flagged. Every cell has an A/A interval.
TEST(Matrix, IdenticalOrderIsNeverReportedAsASpeedup) {
  MatrixSpec spec;
  spec.scenes = {"detail-room"};
  spec.batches = {"primary", "bounce1"};
  spec.encoders = {Encoder::Origin, Encoder::HCC};
  spec.bits = {32};
  spec.frame = {96, 54, 1};
  spec.accesses = {RayAccess::Gather, RayAccess::Permute};
  spec.reps = 12;
  spec.max_time_s = 0.5;
  RunOptions opts;
  opts.out = temp_dir("same-order");
  ASSERT_EQ(run_matrix(spec, opts).cells_failed, 0u);
  auto rs = ResultSet::load(opts.out);
  for (const std::string access : {"", "/permute"}) {
    const CellRecord* same = rs.find("detail-room/primary/origin/32" + access);
    ASSERT_NE(same, nullptr);
    EXPECT_TRUE(same->same_order_as_nosort);
    EXPECT_EQ(same->speedup.value, 1.0);
    EXPECT_EQ(same->speedup.lo, 1.0);
    EXPECT_EQ(same->speedup.hi, 1.0);
    // Before the paired protocol this ratio was 1.4-1.9 at this size.
    const Estimate measured = ratio_interval(same->samples.at("nosort"), same->samples.at("trace"));
    EXPECT_GT(measured.value, 0.85) << access;
    EXPECT_LT(measured.value, 1.18) << access;
    const CellRecord* different = rs.find("detail-room/bounce1/origin/32" + access);
    ASSERT_NE(different, nullptr);
    EXPECT_FALSE(different->same_order_as_nosort);
  }
  for (const auto& c : rs.cells()) {
    EXPECT_GE(c.rounds, 12u) << c.id();
    EXPECT_TRUE(c.aa.has_interval()) << c.id();
    EXPECT_TRUE(c.speedup.has_interval()) << c.id();
    EXPECT_TRUE(c.stopped_by == "noise" || c.stopped_by == "time") << c.id() << " " << c.stopped_by;
  }
  const std::string tables = read_file(opts.out + "/tables.md");
  EXPECT_NE(tables.find("(= NoSort)"), std::string::npos);
  EXPECT_NE(tables.find("A/A calibration"), std::string::npos);
  EXPECT_TRUE(nlohmann::json::parse(read_file(opts.out + "/meta.json")).contains("noise"));
}

// The baseline-order axis (render/batches.h): one run holds pixel and shuffled cells, each against
// its own NoSort; the shuffled NoSort traces the same rays (same hits, scattered back) in another
// order, which the SIMT model sees as less coherent; the tables set them side by side.
TEST(Matrix, BaselineOrderIsAnAxis) {
  MatrixSpec spec;
  spec.scenes = {"detail-room"};
  spec.batches = {"primary", "bounce1"};
  spec.encoders = {Encoder::HCC};
  spec.frame = {64, 36, 1};
  spec.baselines = parse_baseline_orders("all");
  spec.reps = 1, spec.warmup = 0, spec.max_time_s = 0;
  RunOptions opts;
  opts.out = temp_dir("baselines");
  RunSummary s = run_matrix(spec, opts);
  EXPECT_EQ(s.cells_failed, 0u);
  EXPECT_EQ(s.cells_run, 2u * 2u * 2u);  // 2 batches x 2 baselines x (NoSort + HCC)
  auto rs = ResultSet::load(opts.out);
  for (const std::string batch : {"primary", "bounce1"}) {
    const CellRecord* pixel = rs.find("detail-room/" + batch + "/nosort/0");
    const CellRecord* shuffled = rs.find("detail-room/" + batch + "/nosort/0/shuffled");
    ASSERT_TRUE(pixel && shuffled) << batch;
    EXPECT_EQ(shuffled->baseline, "shuffled");
    EXPECT_EQ(pixel->rays, shuffled->rays);
    EXPECT_NE(pixel->keys_hash + pixel->order_hash, "");
    EXPECT_LT(shuffled->simt_lane_efficiency, pixel->simt_lane_efficiency) << batch;
    EXPECT_GT(shuffled->simt_distinct_per_visit, pixel->simt_distinct_per_visit) << batch;
    const CellRecord* hcc = rs.find("detail-room/" + batch + "/hcc/32/shuffled");
    ASSERT_NE(hcc, nullptr);
    EXPECT_TRUE(hcc->hits_match_nosort);
    // The same rays in another generation order: other key and order fingerprints; and sorting a
    // shuffle recovers coherence the shuffle took away.
    const CellRecord* hcc_pixel = rs.find("detail-room/" + batch + "/hcc/32");
    ASSERT_NE(hcc_pixel, nullptr);
    EXPECT_NE(hcc->keys_hash, hcc_pixel->keys_hash);
    EXPECT_GT(hcc->simt_lane_efficiency_ratio, 1.0) << batch;
    EXPECT_LT(hcc->simt_distinct_per_visit_ratio, 1.0) << batch;
  }
  const std::string tables = read_file(opts.out + "/tables.md");
  EXPECT_NE(tables.find("## Baseline order: pixel against shuffled"), std::string::npos);
  const auto meta = nlohmann::json::parse(read_file(opts.out + "/meta.json"));
  EXPECT_EQ(meta["matrix"]["baseline"], "pixel,shuffled");
  EXPECT_TRUE(meta["baseline"].contains("shuffled"));
}

// The permutation of a shuffled baseline is drawn by a fixed rule: a permutation, the same on every
// call (and machine: std::mt19937_64's sequence is fixed by the standard, and the bounded draw is
// not a library distribution), different per batch name and seed; the batch's rays, pixels and
// reference hits move together.
TEST(Baseline, ShuffledOrderIsAFixedPermutation) {
  const auto p = baseline_permutation(1000, "bounce1", 1);
  std::vector<std::uint32_t> sorted = p;
  std::sort(sorted.begin(), sorted.end());
  for (std::uint32_t i = 0; i < 1000; ++i) ASSERT_EQ(sorted[i], i);
  EXPECT_EQ(p, baseline_permutation(1000, "bounce1", 1));
  EXPECT_NE(p, baseline_permutation(1000, "bounce2", 1));
  EXPECT_NE(p, baseline_permutation(1000, "bounce1", 2));
  // Pinned: a change to the rule changes every shuffled result set, so it must be deliberate.
  EXPECT_EQ((std::vector<std::uint32_t>(p.begin(), p.begin() + 4)), (std::vector<std::uint32_t>{493, 356, 949, 50}));
  ReferencedBatch b;
  b.batch.name = "bounce1";
  for (std::uint32_t i = 0; i < 100; ++i) {
    RsRay r{};
    r.o[0] = static_cast<float>(i);
    b.batch.rays.push_back(r);
    b.batch.pixel.push_back(i);
    b.batch.sample.push_back(0);
    RsHit h{};
    h.tri = i;
    b.reference_hits.push_back(h);
  }
  const ReferencedBatch same = in_baseline_order(b, BaselineOrder::Pixel, 1);
  EXPECT_EQ(same.batch.pixel, b.batch.pixel);
  const ReferencedBatch s = in_baseline_order(b, BaselineOrder::Shuffled, 1);
  const auto q = baseline_permutation(100, "bounce1", 1);
  for (std::size_t i = 0; i < 100; ++i) {
    EXPECT_EQ(s.batch.pixel[i], q[i]);
    EXPECT_EQ(s.batch.rays[i].o[0], static_cast<float>(q[i]));
    EXPECT_EQ(s.reference_hits[i].tri, q[i]);
  }
  EXPECT_THROW(parse_baseline_orders("pixel,random"), Error);
  EXPECT_EQ(parse_baseline_orders("shuffled,pixel,shuffled").size(), 2u);
}

// --layout binary: the trace kernel and the SIMT model walk the binary tree, every cell and meta.json
// say so, the hits still match, and the model differs from the wide tree's (fewer, wider steps there).
TEST(Matrix, LayoutIsRecordedAndModelled) {
  MatrixSpec spec;
  spec.scenes = {"multi-instance"};
  spec.batches = {"bounce1"};
  spec.encoders = {Encoder::HCC};
  spec.frame = {64, 36, 1};
  spec.reps = 1, spec.warmup = 0, spec.max_time_s = 0;
  std::map<std::string, ResultSet> sets;
  for (TraceLayout layout : {TraceLayout::Wide, TraceLayout::Binary}) {
    spec.layouts = {layout};
    RunOptions opts;
    opts.out = temp_dir(std::string("layout-") + trace_layout_name(layout));
    ASSERT_EQ(run_matrix(spec, opts).cells_failed, 0u);
    const auto meta = nlohmann::json::parse(read_file(opts.out + "/meta.json"));
    EXPECT_EQ(meta["bvh"]["layout"], trace_layout_name(layout));
    EXPECT_EQ(meta["bvh"]["width"], layout == TraceLayout::Wide ? 4 : 2);
    EXPECT_EQ(meta["bvh"]["max_leaf_size"], BvhBuildOptions{}.max_leaf_size);
    // The sort's shape on this device (a CPU: one work-item per tile, 8-bit digits, the hybrid).
    EXPECT_EQ(meta["sort"]["shape"], "cpu") << meta["sort"].dump();
    EXPECT_EQ(meta["sort"]["digit_bits"], 8) << meta["sort"].dump();
    EXPECT_NE(meta["sort"]["passes"].get<std::string>().find("MSD-first hybrid"), std::string::npos)
        << meta["sort"].dump();
    sets.emplace(trace_layout_name(layout), ResultSet::load(opts.out));
    for (const auto& c : sets.at(trace_layout_name(layout)).cells()) {
      EXPECT_EQ(c.layout, trace_layout_name(layout)) << c.id();
      EXPECT_TRUE(c.ok() && (c.encoder == kBaselineEncoder || c.hits_match_nosort)) << c.id() << " " << c.error;
    }
  }
  const CellRecord* wide = sets.at("wide").find("multi-instance/bounce1/nosort/0");
  const CellRecord* binary = sets.at("binary").find("multi-instance/bounce1/nosort/0/binary");
  ASSERT_TRUE(wide && binary);
  EXPECT_NE(wide->simt_lane_efficiency, binary->simt_lane_efficiency);
  EXPECT_NE(wide->simt_distinct_per_visit, binary->simt_distinct_per_visit);
}

// The trace class is an axis (issue 40): one run traces every class, each cell names its class
// (wide cells keep their ids, the others end in /<class>), every class's hits equal its host twin,
// an order's keys do not depend on the class, a class named twice (packet = packet<device width>)
// runs once, meta.json lists the classes, and tables.md sets them side by side.
TEST(Matrix, TraceClassesAreAnAxisOfOneRun) {
  MatrixSpec spec;
  spec.scenes = {"multi-instance"};
  spec.batches = {"bounce1"};
  spec.encoders = {Encoder::HCC};
  spec.accesses = {RayAccess::Gather, RayAccess::Permute};
  spec.frame = {64, 36, 1};
  spec.reps = 1, spec.warmup = 0, spec.max_time_s = 0;
  const TraceLayout packet = resolve_trace_layout(TraceLayout::Packet, select_device(""));
  spec.layouts = {TraceLayout::Wide, TraceLayout::Packet4, TraceLayout::Packet, TraceLayout::Hybrid8, packet};
  std::vector<std::string> classes{"wide", "packet4"};
  if (packet != TraceLayout::Packet4) classes.push_back(trace_layout_name(packet));
  classes.push_back("hybrid8");
  RunOptions opts;
  opts.out = temp_dir("classes-axis");
  ASSERT_EQ(run_matrix(spec, opts).cells_failed, 0u);
  const auto meta = nlohmann::json::parse(read_file(opts.out + "/meta.json"));
  std::string listed;
  for (const auto& c : classes) listed += (listed.empty() ? "" : ",") + c;
  EXPECT_EQ(meta["matrix"]["layout"], listed);
  EXPECT_EQ(meta["bvh"]["classes"].size(), classes.size());
  const ResultSet set = ResultSet::load(opts.out);
  EXPECT_EQ(set.cells().size(), 3 * classes.size());  // NoSort, HCC gather, HCC permute per class
  EXPECT_EQ(std::distance(fs::directory_iterator(opts.out + "/cells"), fs::directory_iterator()),
            static_cast<std::ptrdiff_t>(3 * classes.size()));
  const CellRecord* wide = set.find("multi-instance/bounce1/hcc/32");
  ASSERT_NE(wide, nullptr);
  EXPECT_EQ(wide->layout, "wide");
  for (const auto& l : classes) {
    const std::string suffix = l == "wide" ? "" : "/" + l;
    for (const std::string cell : {"nosort/0", "hcc/32", "hcc/32/permute"}) {
      std::string id = "multi-instance/bounce1/" + cell;
      id.insert(id.find("/permute") == std::string::npos ? id.size() : id.find("/permute"), suffix);
      const CellRecord* c = set.find(id);
      ASSERT_NE(c, nullptr) << id;
      EXPECT_EQ(c->layout, l) << id;
      EXPECT_TRUE(c->ok() && (c->encoder == kBaselineEncoder || c->hits_match_nosort)) << id << " " << c->error;
      if (c->encoder != kBaselineEncoder) {
        EXPECT_EQ(c->keys_hash, wide->keys_hash) << id;
      }
    }
  }
  const std::string tables = read_file(opts.out + "/tables.md");
  EXPECT_NE(tables.find("## Trace classes"), std::string::npos);
  EXPECT_NE(tables.find("| multi-instance | bounce1 | hybrid8 |"), std::string::npos);
}

// A packet's companions decide which of two triangles at exactly the same t its ray meets first:
// breakfast_room's bounce rays hit shared edges and coplanar duplicates, so an HCC order and pixel
// order give some rays the other triangle of a tie. The cell check accepts exactly those (same t,
// or for shadow rays the same occluded / free answer) and nothing else; single rays stay bit for bit.
TEST(Matrix, PacketCellsEqualNoSortUpToTiesOnARealScene) {
  RAYSORT_REQUIRE_REAL_SCENES();
  MatrixSpec spec;
  spec.scenes = {"breakfast_room"};
  spec.batches = {"bounce1", "shadow1"};
  spec.encoders = {Encoder::HCC};
  spec.accesses = {RayAccess::Gather, RayAccess::Permute};
  spec.layouts = {TraceLayout::Wide, TraceLayout::Packet8};
  spec.frame = {480, 270, 1};
  spec.reps = 1, spec.warmup = 0, spec.max_time_s = 0;
  RunOptions opts;
  opts.out = temp_dir("packet-ties");
  const RunSummary s = run_matrix(spec, opts);
  for (const auto& c : ResultSet::load(opts.out).cells())
    EXPECT_TRUE(c.ok() && (c.encoder == kBaselineEncoder || c.hits_match_nosort)) << c.id() << ": " << c.error;
  EXPECT_EQ(s.cells_failed, 0u);
}

// A run records the SHA-256 of every scene file it traced (meta.json "scene_files"); a resume on a
// changed file is refused, and compare says when two sets traced different files.
TEST(Matrix, SceneFileChecksumsAreRecordedAndCompared) {
  const std::string dir = temp_dir("scene-files");
  const std::string obj = dir + "/quad.obj";
  auto write_obj = [&](const std::string& z) {
    std::ofstream(obj) << "v 0 0 " << z << "\nv 1 0 " << z << "\nv 1 1 " << z << "\nv 0 1 " << z << "\nf 1 2 3 4\n";
  };
  write_obj("0");
  MatrixSpec spec;
  spec.scenes = {obj};
  spec.batches = {"primary"};
  spec.encoders = {Encoder::HCC};
  spec.frame = {16, 9, 1};
  spec.reps = 1, spec.warmup = 0, spec.max_time_s = 0;
  RunOptions a, b;
  a.out = dir + "/a", b.out = dir + "/b";
  ASSERT_EQ(run_matrix(spec, a).cells_failed, 0u);
  const auto meta = nlohmann::json::parse(read_file(a.out + "/meta.json"));
  ASSERT_TRUE(meta["scene_files"].contains(obj)) << meta["scene_files"].dump();
  EXPECT_EQ(meta["scene_files"][obj]["sha256"], sha256_file(obj));
  EXPECT_EQ(meta["scene_files"][obj]["status"], "uncatalogued");
  write_obj("1");  // one byte changed
  try {
    run_matrix(spec, a);
    ADD_FAILURE() << "resumed on a changed scene file";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("other scene files"), std::string::npos) << e.what();
  }
  ASSERT_EQ(run_matrix(spec, b).cells_failed, 0u);
  const CompareResult r = compare_result_sets(ResultSet::load(a.out), ResultSet::load(b.out), {"keys_hash"}, {});
  ASSERT_EQ(r.scene_files.size(), 1u);
  EXPECT_NE(r.scene_files[0].find(obj), std::string::npos) << r.scene_files[0];
  EXPECT_NE(r.report.find("traced different scene files"), std::string::npos);
}

// SIGKILL at several points, rerun after each: the final set equals an uninterrupted run's, each
// cell once, and no file is corrupt.
TEST(Matrix, KilledRunResumesToTheSameCells) {
  std::vector<std::string> args = {"run", "--scenes", "cornell", "--batches", "bounce1,shadow0", "--bits", "16,32",
                                   "--resolution", "40x30", "--reps", "1", "--warmup", "0", "--max-time", "0"};
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
