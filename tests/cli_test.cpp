// The command line as a user meets it (issue 8): unknown names list the valid ones, impossible
// combinations are refused in one line before any work starts, and device faults in a matrix run
// (an allocation over the device limit, a cell over --timeout) fail only their cells.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <cstdlib>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bench/result_set.h"
#include "encode/encoder_params.h"
#include "test_util.h"

namespace fs = std::filesystem;
using namespace raysort;

namespace {

using raysort::testing::CliResult;
using raysort::testing::run_cli;

std::string temp_dir(const std::string& name) {
  return raysort::testing::temp_path(name);  // removed when every test passed
}

// Expects exit code != 0, exactly one line on stderr containing every one of `parts`, and (for
// `run`) no result folder: refused before any work started.
void expect_refused(std::vector<std::string> args, const std::vector<std::string>& parts) {
  std::string out = temp_dir("refused");
  if (args[0] == "run") args.insert(args.end(), {"--out", out});
  CliResult r = run_cli(args);
  std::string cmd;
  for (auto& a : args) cmd += a + " ";
  EXPECT_NE(r.code, 0) << cmd;
  ASSERT_FALSE(r.err.empty()) << cmd;
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << cmd << ": not one line:\n" << r.err;
  for (const auto& p : parts) EXPECT_NE(r.err.find(p), std::string::npos) << cmd << ": no '" << p << "' in " << r.err;
  EXPECT_FALSE(fs::exists(out)) << cmd << ": work started (result folder created)";
}

}  // namespace

TEST(Cli, UnknownNamesListTheValidOnes) {
  expect_refused({"run", "--scenes", "cornell", "--encoders", "nope"},
                 {"unknown encoder 'nope'", "nosort", "mlhcc", "hcc-dir"});
  expect_refused({"run", "--scenes", "nope"}, {"unknown scene 'nope'", "cornell", "landscape"});
  expect_refused({"run", "--scenes", "cornell", "--batches", "nope"}, {"unknown batch 'nope'", "primary", "shadow<k>"});
  expect_refused({"run", "--preset", "nope"}, {"unknown preset 'nope'", "quick", "paper"});
  expect_refused({"run", "--scenes", "cornell", "--gpu-model", "nope"}, {"unknown GPU profile 'nope'", "rtx3060", "h100"});
  expect_refused({"run", "--scenes", "/nonexistent/x.obj"}, {"OBJ file not found: /nonexistent/x.obj"});
  expect_refused({"run", "--scenes", "/tmp"}, {"'/tmp' is a directory"});
  expect_refused({"trace", "--scene", "nope"}, {"unknown scene 'nope'", "cornell"});
}

// With PoCL's single-threaded `basic` device listed first, and Oclgrind registered (when installed),
// the default is still PoCL's pthread device, and the others are marked (issue 19, item 5).
TEST(Cli, DefaultDeviceIsNeverTheSimulatorOrPoclBasic) {
  std::vector<std::string> env = {"POCL_DEVICES=basic pthread", "RAYSORT_DEVICE="};
  const fs::path oclgrind = "/usr/lib/oclgrind/liboclgrind-rt-icd.so";
  const bool with_oclgrind = fs::exists(oclgrind);
  if (with_oclgrind) {
    const fs::path vendors = raysort::testing::temp_path("icd-vendors");
    fs::create_directories(vendors);
    if (fs::is_directory("/etc/OpenCL/vendors"))
      for (const auto& e : fs::directory_iterator("/etc/OpenCL/vendors"))
        if (e.path().extension() == ".icd") fs::copy_file(e.path(), vendors / e.path().filename());
    std::ofstream(vendors / "oclgrind.icd") << oclgrind.string() << "\n";
    env.push_back("OCL_ICD_VENDORS=" + vendors.string());
  }
  CliResult r = run_cli({"devices"}, env);
  ASSERT_EQ(r.code, 0) << r.err;
  auto default_line = [&] {  // the line marked "(default)"
    std::istringstream in(r.out);
    for (std::string line; std::getline(in, line);)
      if (line.find("(default)") != std::string::npos) return line;
    return std::string();
  };
  if (r.out.find("basic-") == std::string::npos) {
    GTEST_SKIP() << "PoCL lists no basic device here:\n" << r.out;
  }
  EXPECT_NE(default_line().find("pthread-"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("(single-threaded: one core, never the default)"), std::string::npos) << r.out;
  if (with_oclgrind) {
    EXPECT_NE(r.out.find("(simulator:"), std::string::npos) << r.out;
  }
}

TEST(Cli, ImpossibleCombinationsRefusedBeforeWork) {
  expect_refused({"run", "--scenes", "cornell", "--resolution", "0x100"}, {"resolution '0x100'"});
  expect_refused({"run", "--scenes", "cornell", "--resolution", "wide"}, {"resolution 'wide'"});
  // Key lengths outside 1..64 are refused where --bits is parsed (issue 44), for every encoder.
  expect_refused({"run", "--scenes", "cornell", "--encoders", "origin", "--bits", "0"},
                 {"--bits 0 is not valid: give a whole number from 1 to 64"});
  expect_refused({"run", "--scenes", "cornell", "--bits", "65"}, {"--bits 65 is not valid"});
  expect_refused({"run", "--scenes", "cornell", "--encoders", "MLHCC", "--bits", "31"},
                 {"encoder mlhcc with 31-bit keys", "even number of bits"});
  expect_refused({"run", "--scenes", "cornell", "--top-bits", "40", "--bits", "32"}, {"--top-bits 40"});
  expect_refused({"run", "--scenes", "cornell", "--reps", "0"}, {"--reps"});
  expect_refused({"run", "--scenes", "cornell", "--timeout", "-1"}, {"--timeout -1"});
  // The knobs of the encoders beyond the paper (issue 21).
  expect_refused({"run", "--scenes", "cornell", "--region-bits", "9"}, {"--region-bits 9 is not valid", "from 0 to 8"});
  expect_refused({"run", "--scenes", "cornell", "--encoders", "hcc-region", "--region-bits", "4", "--bits", "4"},
                 {"encoder hcc-region with 4-bit keys", "more than 4 bits"});
  expect_refused({"run", "--scenes", "cornell", "--traffic-blend", "1.5"},
                 {"--traffic-blend 1.5 is not valid", "from 0 to 1"});
  expect_refused({"run", "--scenes", "cornell", "--cost-bits", "0"}, {"--cost-bits 0 is not valid", "from 1 to 31"});
  expect_refused({"run", "--scenes", "cornell", "--encoders", "mlhcc-cost", "--cost-bits", "8", "--bits", "16"},
                 {"encoder mlhcc-cost with 16-bit keys", "leaves no low-level cut"});
  expect_refused({"trace", "--scene", "cornell", "--adjudicate"}, {"--adjudicate judges", "--variant both"});
  expect_refused({"trace", "--scene", "cornell", "--disagreements", "x"}, {"--disagreements DIR goes with --adjudicate"});
  // A broken OBJ given by path is read before the run starts, not after the first scenes ran.
  fs::path bad = raysort::testing::temp_path("nan.obj");
  std::ofstream(bad) << "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n";
  expect_refused({"run", "--scenes", "cornell," + bad.string()}, {bad.string() + ":3: vertex 3 has a non-finite"});
  fs::remove(bad);
}

// `raysort trace --reference embree --embree-paths`: every path is an arm with a line of its own
// after the batch's row (call and flag, threads, ms, MRays/s, ours/path speed, agreement), then the
// best path; an unknown path is refused with the valid names, before any work.
TEST(CliTrace, EmbreePathsAllPrintsALinePerPath) {
  expect_refused({"trace", "--scene", "cornell", "--embree-paths", "1M"}, {"--embree-paths 1M goes with --reference embree"});
  expect_refused({"trace", "--scene", "cornell", "--embree-isa", "avx2"}, {"--embree-isa avx2 goes with --reference embree"});
#ifdef RAYSORT_HAVE_EMBREE
  expect_refused({"trace", "--scene", "cornell", "--reference", "embree", "--embree-isa", "avx3"},
                 {"unknown Embree instruction set 'avx3' in --embree-isa; the sets are native, sse2"});
  // Held to SSE2: the embree line says so, and 8-ray packets are not native.
  CliResult held = run_cli({"trace", "--scene", "cornell", "--resolution", "16x16", "--reps", "1", "--warmup", "0",
                            "--reference", "embree", "--embree-isa", "sse2", "--embree-paths", "1,8"});
  ASSERT_EQ(held.code, 0) << held.out << held.err;
  EXPECT_NE(held.out.find(" held to sse2, "), std::string::npos) << held.out;
  EXPECT_NE(held.out.find("native packets: 8 no"), std::string::npos) << held.out;
  expect_refused({"trace", "--scene", "cornell", "--reference", "embree", "--embree-paths", "1,17"},
                 {"unknown Embree path '17' in --embree-paths", "1 (rtcIntersect1)", "1M-coherent", "16-coherent", "or all"});
  expect_refused({"trace", "--scene", "cornell", "--reference", "embree", "--embree-paths", ""},
                 {"--embree-paths: name at least one Embree path", "1M-coherent"});
  // rtcIntersect1 alone, named: the columns of the batch row, as without --embree-paths.
  CliResult one = run_cli({"trace", "--scene", "cornell", "--resolution", "16x16", "--reps", "1", "--warmup", "0",
                           "--reference", "embree", "--embree-paths", "1"});
  ASSERT_EQ(one.code, 0) << one.out << one.err;
  EXPECT_NE(one.out.find("emb ms  ours/emb speed  same %  +ties %"), std::string::npos) << one.out;
  EXPECT_EQ(one.out.find("Embree call and flag"), std::string::npos) << one.out;
  CliResult r = run_cli({"trace", "--scene", "cornell", "--resolution", "40x24", "--variant", "both", "--reps", "6",
                         "--warmup", "0", "--max-time", "0", "--reference", "embree", "--embree-paths", "all"});
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("rtcIntersect1 / rtcOccluded1, rtcIntersect1M incoherent / rtcOccluded1M incoherent"),
            std::string::npos) << r.out;
  EXPECT_NE(r.out.find("native packets: 4 "), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("emb ms"), std::string::npos) << "the single-path columns are off with more paths:\n" << r.out;
  // Per batch: a line per path, whose words are: key, call and flag (2 words, or 1 for rtcIntersect1),
  // threads, ms [lo, hi], MRays/s, fast/path [lo, hi], robust/path [lo, hi], same %, +ties %.
  std::map<std::string, int> lines;  // key -> lines seen
  int batches = 0, best = 0;
  std::istringstream in(r.out);
  for (std::string line; std::getline(in, line);) {
    std::istringstream words(line);
    std::vector<std::string> w;
    for (std::string x; words >> x;) w.push_back(x);
    if (!w.empty() && (w[0] == "primary" || w[0].rfind("shadow", 0) == 0 || w[0].rfind("bounce", 0) == 0)) ++batches;
    if (line.rfind("  best ", 0) == 0) {
      ++best;
      EXPECT_NE(line.find("has the lowest median of Embree's paths"), std::string::npos) << line;
    }
    // Path lines are indented by two spaces (notes by more); the header's first word is "path".
    if (line.rfind("  ", 0) != 0 || line.size() < 3 || line[2] == ' ' || w[0] == "best" || w[0] == "path") continue;
    const bool single = w[1] == "rtcIntersect1" || w[1] == "rtcOccluded1";
    ASSERT_EQ(w.size(), single ? 15u : 16u) << line;
    // The threads column: EmbreeScene's default, one per hardware thread.
    EXPECT_EQ(w[single ? 2 : 3], std::to_string(std::max(1u, std::thread::hardware_concurrency()))) << line;
    const double same = std::stod(w[w.size() - 2]), ties = std::stod(w[w.size() - 1]);
    EXPECT_GE(ties, 99.9) << line;
    EXPECT_LE(same, ties) << line;
    ++lines[w[0]];
  }
  EXPECT_GE(batches, 3) << r.out;
  EXPECT_EQ(best, batches) << r.out;
  for (const char* key : {"1", "1M", "1M-coherent", "4", "8", "16", "4-coherent", "8-coherent", "16-coherent"})
    EXPECT_EQ(lines[key], batches) << key << "\n" << r.out;
#endif
}

// An allocation over the device's limit (forced with the RAYSORT_TEST_MAX_ALLOC_BYTES hook, here
// for the one buffer that only the grid encoder's 64-bit cells allocate) fails that cell with a
// message naming the buffer, its size and the limit; the cells after it still run.
TEST(Cli, AllocationOverTheDeviceLimitFailsOnlyItsCell) {
  std::string out = temp_dir("alloc");
  CliResult r = run_cli({"run", "--scenes", "cornell", "--batches", "primary", "--encoders", "grid,origin", "--bits",
                         "32,64", "--resolution", "16x16", "--reps", "1", "--warmup", "0", "--out", out},
                        {"RAYSORT_TEST_MAX_ALLOC_BYTES=1:grid 64-bit cut boxes"});
  EXPECT_EQ(r.code, 1) << r.err;  // a cell failed
  ResultSet rs = ResultSet::load(out);
  std::map<std::string, std::pair<std::string, std::string>> status;
  for (const auto& c : rs.cells()) status[c.encoder + "/" + std::to_string(c.bits)] = {c.status, c.error};
  ASSERT_EQ(status.size(), 5u) << r.err;  // NoSort + 2 encoders x 2 bits, each once
  EXPECT_EQ(status[std::string(kBaselineEncoder) + "/0"].first, "ok");
  for (const char* ok : {"grid/32", "origin/32", "origin/64"}) EXPECT_EQ(status[ok].first, "ok") << ok << status[ok].second;
  EXPECT_EQ(status["grid/64"].first, "failed");
  const std::string& msg = status["grid/64"].second;
  EXPECT_NE(msg.find("allocating 'grid 64-bit cut boxes' ("), std::string::npos) << msg;
  EXPECT_NE(msg.find("larger than the device's maximum allocation of 1 B"), std::string::npos) << msg;
  fs::remove_all(out);
}

// `run` measures with no warm-up round unless asked (MatrixSpec::warmup: a batch's setup runs each
// kernel once, the sort and the permute included), and its permute cells, whose buffer that setup
// touches first, are measured and checked as before.
TEST(Cli, RunHasNoWarmupRoundByDefault) {
  std::string out = temp_dir("nowarmup");
  CliResult r = run_cli({"run", "--scenes", "cornell", "--batches", "primary,bounce1", "--encoders", "origin,hcc",
                         "--bits", "32", "--access", "all", "--resolution", "16x16", "--reps", "2", "--max-time", "0",
                         "--out", out});
  ASSERT_EQ(r.code, 0) << r.err;
  ResultSet rs = ResultSet::load(out);
  EXPECT_EQ(rs.meta()["matrix"]["warmup"], 0) << rs.meta()["matrix"].dump();
  ASSERT_EQ(rs.cells().size(), 10u) << r.err;  // per batch: NoSort + 2 encoders x 2 access modes
  for (const auto& c : rs.cells()) {
    EXPECT_EQ(c.status, "ok") << c.id() << ": " << c.error;
    EXPECT_TRUE(c.hits_match_nosort) << c.id();
  }
  fs::remove_all(out);
}

// A batch's cells are recorded together when its shared rounds end; the ETA of their lines counts
// them all from the first line on. It once divided the elapsed time by the one cell printed so far:
// "[1/158] ... (elapsed 405s, ETA 1059m00s)" for a run that ended 4 minutes later. Two batches of
// equal size, each sampled for a second: the first cell's ETA is about the time spent so far.
TEST(Cli, RunEtaCountsABatchsCellsFromItsFirstLine) {
  std::string out = temp_dir("eta");
  CliResult r = run_cli({"run", "--scenes", "cornell", "--batches", "primary,shadow0", "--encoders", "origin,hcc",
                         "--bits", "32", "--resolution", "128x128", "--reps", "7", "--max-noise", "0.001", "--max-time",
                         "1", "--out", out});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::regex first(R"(\n\[1/6\] [^\n]*\(elapsed (\d+)s, ETA (\d+)s\)\n)");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.err, m, first)) << r.err;
  const int elapsed = std::stoi(m[1]), eta = std::stoi(m[2]);
  EXPECT_GE(elapsed, 1) << r.err;  // a second of rounds at least: the check below can tell
  EXPECT_LE(eta, 2 * elapsed + 1) << r.err;
  fs::remove_all(out);
}

// A cell over --timeout is recorded as "timeout" and the run goes on to the next cell.
TEST(Cli, CellOverTimeoutRecordedAsTimeout) {
  std::string out = temp_dir("timeout");
  CliResult r = run_cli({"run", "--scenes", "cornell", "--batches", "primary", "--encoders", "origin,costa", "--bits",
                         "32", "--resolution", "16x16", "--reps", "2", "--warmup", "0", "--timeout", "0.000001",
                         "--out", out});
  EXPECT_EQ(r.code, 1) << r.err;
  ResultSet rs = ResultSet::load(out);
  ASSERT_EQ(rs.cells().size(), 3u) << r.err;
  for (const auto& c : rs.cells()) {
    EXPECT_EQ(c.status, "timeout") << c.id();
    EXPECT_NE(c.error.find("over --timeout 1e-06 s"), std::string::npos) << c.error;
  }
  EXPECT_NE(r.err.find("TIMEOUT"), std::string::npos) << r.err;
  fs::remove_all(out);
}

// `raysort scenes --lights`: the paper's Table 1 from the scene files, lights with the same
// radius and power grouped into one row ("3-12"), the radius in percent of the largest extent.
TEST(CliScenes, LightsPrintThePapersTable1) {
  CliResult r = run_cli({"scenes", "--lights", "--scenes", "cornell,landscape"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("| scene | light index | relative radius | power | sky |"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("| cornell | 0 | 2.50 % | 40 | no |"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("| landscape | 0 | 3.00 % | 100000 | yes |"), std::string::npos) << r.out;
  expect_refused({"scenes", "--scenes", "cornell"}, {"--scenes applies to --lights only"});
}

TEST(CliScenes, LightsGroupSibeniksThirteenLightsAsThePaperDoes) {
  RAYSORT_REQUIRE_REAL_SCENES();
  CliResult r = run_cli({"scenes", "--lights", "--scenes", "sibenik"});
  EXPECT_NE(r.out.find("| sibenik | 0 | 7.50 % | 2000 | no |\n|  | 1-2 | 2.50 % | 300 |  |\n|  | 3-12 | 0.50 % | 20 |  |"),
            std::string::npos) << r.out;
}

// `raysort scenes` checks real scene files against scenes/sources.toml: a scene root holding only
// the Cornell box files lists them as present and every other file as missing, exits 0 (the
// listing is informational), and a copy with one byte changed is listed as different.
TEST(CliScenes, ListsPresentMissingAndDifferentFiles) {
  RAYSORT_REQUIRE_REAL_SCENES();
  const fs::path real = raysort::testing::real_scene_root();
  const fs::path root = temp_dir("scene-root");
  fs::create_directories(root / "cornell_box");
  for (const char* f : {"cornell_box/CornellBox-Original.obj", "cornell_box/CornellBox-Original.mtl"})
    fs::copy_file(real / f, root / f);
  auto line_of = [](const std::string& out, const std::string& path) {
    std::size_t at = out.find(" " + path + " ");
    if (at == std::string::npos) return std::string();
    std::size_t begin = out.rfind('\n', at) + 1;
    return out.substr(begin, out.find('\n', at) - begin);
  };

  CliResult r = run_cli({"scenes", "--scene-root", root.string()});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(line_of(r.out, "cornell_box/CornellBox-Original.obj").find("present "), std::string::npos) << r.out;
  EXPECT_NE(line_of(r.out, "cornell_box/CornellBox-Original.obj").find("public domain"), std::string::npos) << r.out;
  EXPECT_NE(line_of(r.out, "cornell_box/CornellBox-Original.mtl").find("present "), std::string::npos) << r.out;
  for (const char* f : {"dragon/dragon_100k.obj", "sibenik/sibenik_75k_geom.obj", "breakfast_room/breakfast_room.mtl"})
    EXPECT_NE(line_of(r.out, f).find("missing "), std::string::npos) << f << "\n" << r.out;
  EXPECT_NE(r.out.find("scene files: 2 present, 15 missing, 0 different"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Real scenes: how to obtain them"), std::string::npos) << r.out;
  EXPECT_EQ(run_cli({"scenes", "--scene-root", root.string(), "--verify"}).code, 1);

  {  // One byte changed: different, with both checksums' first 12 hex digits.
    std::fstream f(root / "cornell_box/CornellBox-Original.obj", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(0);
    f.put('X');
  }
  r = run_cli({"scenes", "--scene-root", root.string()});
  EXPECT_EQ(r.code, 0) << r.err;
  const std::string line = line_of(r.out, "cornell_box/CornellBox-Original.obj");
  EXPECT_NE(line.find("different "), std::string::npos) << r.out;
  EXPECT_NE(line.find("expected cc69982c8793, found "), std::string::npos) << line;
  EXPECT_NE(r.out.find("not comparable"), std::string::npos) << r.out;
  EXPECT_NE(line_of(r.out, "cornell_box/CornellBox-Original.mtl").find("present "), std::string::npos) << r.out;

  // The exit status is documented in the help text.
  CliResult help = run_cli({"scenes", "--help"});
  EXPECT_NE(help.out.find("Exit status"), std::string::npos) << help.out;
  EXPECT_NE(help.out.find("--verify"), std::string::npos) << help.out;
}

// encodebench --versus pairs every encoder's encode with the reference's in the same rounds and
// prints the paired ratio with its interval; the reference's own row has none, and the keys checked
// against the host twin are still each encoder's own (the reference writes to buffers of its own).
TEST(CliEncodebench, VersusPrintsAPairedRatioPerEncoder) {
  CliResult r = run_cli({"encodebench", "--scene", "cornell", "--batch", "primary", "--encoders", "origin,hcc,mlhcc",
                         "--bits", "32", "--resolution", "64x64", "--reps", "6", "--warmup", "0", "--max-time", "0",
                         "--versus", "hcc"});
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("x hcc"), std::string::npos) << r.out;
  std::map<std::string, std::vector<std::string>> rows;  // encoder -> the words of its row
  std::istringstream lines(r.out);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line);
    std::vector<std::string> w;
    for (std::string x; words >> x;) w.push_back(x);
    if (w.size() > 2 && w[1] == "32") rows[w[0]] = w;
  }
  ASSERT_EQ(rows.size(), 3u) << r.out;
  // Columns: encoder bits ms [lo, hi] MRays/s %trace [lo, hi] then the ratio [lo, hi], distinct, host==, rounds.
  for (const char* e : {"origin", "mlhcc"}) {
    const auto& w = rows[e];
    ASSERT_EQ(w.size(), 15u) << r.out;
    const double x = std::stod(w[9]), lo = std::stod(w[10].substr(1)), hi = std::stod(w[11]);
    EXPECT_GT(x, 0.0) << e;
    EXPECT_LE(lo, x) << e;
    EXPECT_LE(x, hi) << e;
    EXPECT_EQ(w[13], "yes") << e << ": its keys are not the host twin's";
  }
  ASSERT_EQ(rows["hcc"].size(), 13u) << r.out;
  EXPECT_EQ(rows["hcc"][9], "-") << r.out;
  expect_refused({"encodebench", "--scene", "cornell", "--versus", "nope"}, {"unknown encoder 'nope'", "hcc"});
}

namespace {

// Expects exactly exit code `code` and one line on stderr that starts with "raysort: error: " and
// contains every one of `parts` (issue 44: one scheme for every error, the parser's included).
void expect_exit(std::vector<std::string> args, int code, const std::vector<std::string>& parts,
                 const std::vector<std::string>& env = {}) {
  CliResult r = run_cli(args, env);
  std::string cmd;
  for (auto& a : args) cmd += a + " ";
  EXPECT_EQ(r.code, code) << cmd << "\n" << r.err;
  EXPECT_EQ(r.err.rfind("raysort: error: ", 0), 0u) << cmd << ": no 'raysort: error: ' prefix in " << r.err;
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << cmd << ": not one line:\n" << r.err;
  EXPECT_EQ(r.err.find("internal error"), std::string::npos) << cmd << ": " << r.err;
  for (const auto& p : parts) EXPECT_NE(r.err.find(p), std::string::npos) << cmd << ": no '" << p << "' in " << r.err;
}

}  // namespace

// Issue 44, item 10: a numeric option out of its range, NaN or infinite is refused where it is
// parsed, naming the option, the value and the range; none is silently replaced by its default
// (a run given --lambda inf stored null in meta.json and never resumed). `--shard-plan 1` keeps the
// old behaviour (the value accepted) quick: it prints a plan and exits 0.
TEST(CliNumbers, OutOfRangeNonFiniteAndMalformedNumbersAreRefusedWhereParsed) {
  const std::vector<std::string> run = {"run", "--scenes", "cornell", "--shard-plan", "1"};
  auto with = [](std::vector<std::string> base, std::vector<std::string> more) {
    base.insert(base.end(), more.begin(), more.end());
    return base;
  };
  expect_exit(with(run, {"--lambda", "-1"}), 1, {"--lambda -1 is not valid", "finite number", "0 or more"});
  expect_exit(with(run, {"--lambda", "nan"}), 1, {"--lambda nan is not valid", "finite number"});
  expect_exit(with(run, {"--lambda", "inf"}), 1, {"--lambda inf is not valid", "finite number"});
  expect_exit(with(run, {"--twopoint-length", "-1"}), 1, {"--twopoint-length -1 is not valid"});
  expect_exit(with(run, {"--direction-bits", "-7"}), 1, {"--direction-bits -7 is not valid", "whole number from 0 to"});
  expect_exit(with(run, {"--traffic-blend", "nan"}), 1, {"--traffic-blend nan is not valid", "from 0 to 1"});
  expect_exit(with(run, {"--timeout", "inf"}), 1, {"--timeout inf is not valid"});
  expect_exit(with(run, {"--max-noise", "0"}), 1, {"--max-noise 0 is not valid", "above 0"});
  expect_exit(with(run, {"--seed", "4294967296"}), 1, {"--seed 4294967296 is not valid", "from 0 to 4294967295"});
  expect_exit(with(run, {"--bits", "32,x"}), 1, {"--bits x is not valid", "whole number from 1 to 64"});
  // Item 16: counts have an upper bound.
  expect_exit(with(run, {"--reps", "4000000000"}), 1, {"--reps 4000000000 is not valid", "from 1 to 100000"});
  expect_exit(with(run, {"--warmup", "4000000000"}), 1, {"--warmup 4000000000 is not valid"});
  // encodebench measured nothing (exit 0, an empty table) for key lengths no encoder has.
  const std::vector<std::string> enc = {"encodebench", "--scene", "cornell", "--resolution", "16x16", "--encoders",
                                        "hcc-traffic", "--reps", "1", "--warmup", "0", "--max-time", "0"};
  expect_exit(with(enc, {"--bits", "65"}), 1, {"--bits 65 is not valid", "whole number from 1 to 64"});
  expect_exit(with(enc, {"--bits", "0"}), 1, {"--bits 0 is not valid"});
  expect_exit(with(enc, {"--traffic-blend", "nan"}), 1, {"--traffic-blend nan is not valid", "from 0 to 1"});
  expect_exit({"sortcheck", "--sizes", "-1"}, 1, {"--sizes -1 is not valid"});
  const std::string render_out = raysort::testing::temp_path("render-nan");
  expect_exit({"render", "--scene", "cornell", "--exposure", "nan", "--host", "--resolution", "8x8", "--out", render_out},
              1, {"--exposure nan is not valid"});
}

// Issue 41: `run` and `encodebench` make their encoder knobs from the same rows
// (encode/encoder_params.h) and check encoders and key lengths with the same function
// (validate_encoders), so encodebench refuses what run refuses, with run's message, before any work.
// encodebench measured nothing and exited 0 (an empty table) for a key length an encoder cannot
// take, e.g. `--encoders hcc-region --region-bits 8 --bits 8`.
TEST(CliEncodebench, RefusesWhatRunRefusesWithRunsMessage) {
  std::vector<std::vector<std::string>> cases = {
      {"--encoders", "hcc-region", "--region-bits", "9"},
      {"--encoders", "hcc-region", "--region-bits", "8", "--bits", "8"},
      {"--encoders", "hcc-dir", "--direction-bits", "16", "--bits", "16"},
      {"--encoders", "mlhcc-cost", "--cost-bits", "16", "--bits", "32"},
      {"--encoders", "mlhcc", "--bits", "31"},
  };
  // Every knob past its range, as each row states it.
  for (const raysort::EncoderParam& row : raysort::encoder_params())
    cases.push_back({"--encoders", "hcc", std::string(row.flag),
                     std::isinf(row.hi) ? "-1" : fmt::format("{:g}", row.whole() ? row.hi + 1 : row.hi * 2 + 1)});
  for (const auto& extra : cases) {
    std::vector<std::string> run = {"run", "--scenes", "cornell", "--shard-plan", "1"};
    std::vector<std::string> bench = {"encodebench", "--scene", "cornell", "--resolution", "16x16", "--reps", "1",
                                      "--warmup", "0", "--max-time", "0"};
    run.insert(run.end(), extra.begin(), extra.end());
    bench.insert(bench.end(), extra.begin(), extra.end());
    const CliResult by_run = run_cli(run), by_bench = run_cli(bench);
    std::string what;
    for (const auto& a : extra) what += a + " ";
    EXPECT_EQ(by_run.code, 1) << what << by_run.out << by_run.err;
    EXPECT_EQ(by_bench.code, 1) << what << by_bench.out << by_bench.err;
    EXPECT_EQ(by_bench.err, by_run.err) << what;
    EXPECT_EQ(by_bench.out, "") << what << ": encodebench printed a table";
  }
}

// Item 17: the parser's own errors (CLI11's 104-114 before) exit 1 with the prefix and a usage
// hint, like every other bad input; an unknown command is named; help and version still exit 0.
TEST(CliExitCodes, ParserErrorsAreBadInputWithThePrefix) {
  expect_exit({"run", "--spp", "-1"}, 1, {"--spp -1 is not valid"});
  expect_exit({"run", "--scenes", "cornell", "--out", "a", "--out", "b"}, 1, {"--out", "raysort run --help"});
  expect_exit({"run", "--no-such-option"}, 1, {"--no-such-option", "raysort run --help"});
  expect_exit({"frobnicate"}, 1, {"unknown command 'frobnicate'", "run", "encodebench", "raysort --help"});
  expect_exit({}, 1, {"raysort --help"});
  for (const std::vector<std::string>& ok : {std::vector<std::string>{"--help"}, {"run", "--help"}, {"--version"}}) {
    CliResult r = run_cli(ok);
    EXPECT_EQ(r.code, 0) << ok.back() << r.err;
    EXPECT_FALSE(r.out.empty()) << ok.back();
  }
  // Resolutions: no wrap-around of negative or overflowing numbers.
  expect_exit({"run", "--scenes", "cornell", "--resolution", "-48x27", "--shard-plan", "1"}, 1,
              {"--resolution '-48x27'", "WIDTHxHEIGHT"});
  expect_exit({"run", "--scenes", "cornell", "--resolution", "4294967344x27", "--shard-plan", "1"}, 1,
              {"--resolution '4294967344x27'"});
  expect_exit({"trace", "--scene", "cornell", "--resolution", "48x-27"}, 1, {"--resolution '48x-27'"});
  expect_exit({"run", "--scenes", "cornell", "--shard-plan", "4294967295"}, 1, {"--shard-plan 4294967295 is not valid"});
}

// Item 13: no OpenCL driver, or a device index past the list, is a one-line error with the fix.
TEST(CliDevices, NoDriverAndHugeIndexAreClearErrors) {
  const fs::path empty = raysort::testing::temp_path("no-icd");
  fs::create_directories(empty);
  expect_exit({"devices"}, 1, {"no OpenCL", "pocl-opencl-icd"}, {"OCL_ICD_VENDORS=" + empty.string()});
  expect_exit({"sortcheck", "--sizes", "1"}, 1, {"no OpenCL", "pocl-opencl-icd"},
              {"OCL_ICD_VENDORS=" + empty.string(), "RAYSORT_DEVICE="});
  expect_exit({"sortcheck", "--sizes", "1", "--device", "99999999999999999999"}, 1,
              {"--device 99999999999999999999", "no device with that index", "[0]"});
}

// Item 14: commands outside trace/run/render/encodebench estimate their memory too and refuse
// with exit 2 before allocating (the sort check's pairs, a scene description's host frame); a
// forced scan work-group over the device's limit is refused before a kernel is enqueued (it
// crashed the process at exit after the failed launch).
TEST(CliMemory, SortcheckAndScenesDescribeRefuseWhatDoesNotFit) {
  expect_exit({"sortcheck", "--sizes", "4294967295", "--bits", "64"}, 2, {"4294967295 pairs", "lower --sizes"});
  expect_exit({"scenes", "--describe", "cornell", "--resolution", "20000x20000"}, 2, {"20000x20000", "lower --resolution"});
  expect_exit({"sortcheck", "--scan-work-group", "8192", "--sizes", "1000"}, 1, {"8192", "work-group"});
}

// Item 12: report reads a meta.json whose matrix entries have the wrong JSON type as bad input
// naming the file and the key (compare and merge did; report ended in an internal error).
TEST(CliReport, BadlyTypedMatrixEntriesNameTheFileAndKey) {
  const fs::path golden = fs::path(RAYSORT_SOURCE_DIR) / "tests/golden/quick-tiny";
  const std::vector<std::pair<std::string, std::string>> edits = {
      {"spp", "\"eight\""}, {"scenes", "{\"a\": 1}"}, {"resolution", "48"}, {"shadow_rays", "\"two\""},
      // Written by `run --lambda inf` before issue 44 (a non-finite double is JSON null): reported
      // as damaged, as resume and sweep cannot read it either.
      {"had_lambda", "null"}};
  for (const auto& [key, value] : edits) {
    const fs::path dir = raysort::testing::temp_path("typed-" + key);
    fs::copy(golden, dir, fs::copy_options::recursive);
    std::ifstream in(dir / "meta.json");
    nlohmann::json meta = nlohmann::json::parse(in);
    in.close();
    meta["matrix"][key] = nlohmann::json::parse(value);
    std::ofstream(dir / "meta.json") << meta.dump(1);
    expect_exit({"report", dir.string()}, 1, {"meta.json", "matrix." + key});
    fs::remove_all(dir);
  }
}

// sortbench's GPU shape on this CPU: the reduce-then-scan passes and, beside them on the same keys,
// the Onesweep passes (issue 42, item 1), both checked against std::stable_sort.
TEST(Sortbench, GpuShapeTimesOnesweepBesideReduceThenScan) {
  const CliResult r = run_cli({"sortbench", "--gpu-shape", "--no-large", "--bits", "32", "--reps", "1", "--ref-reps", "1"});
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_NE(r.out.find("passes: ours reduce-then-scan; other passes: Onesweep"), std::string::npos) << r.out;
  std::size_t rows = 0;
  std::istringstream lines(r.out);
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("| 2073600 | 32 |", 0) != 0) continue;
    ++rows;
    std::vector<std::string> cells;
    std::istringstream row(line);
    for (std::string cell; std::getline(row, cell, '|');) cells.push_back(cell);
    ASSERT_GE(cells.size(), 21u) << line;
    // other passes Mkeys/s and ours/other time: measured, finite, positive
    for (int c : {18, 19}) {
      const double v = std::strtod(cells[c].c_str(), nullptr);
      EXPECT_TRUE(std::isfinite(v) && v > 0.0) << "column " << c << " is not a measured figure: " << line;
    }
    EXPECT_EQ(cells[20], " yes ") << line;  // ok
  }
  EXPECT_EQ(rows, 2u) << r.out;  // random and few-distinct keys
}

// run --sort-passes onesweep on a device whose sort has the CPU shape: one message that names the
// option and the fix, and no result folder; an unknown value lists the valid ones.
TEST(SortCli, OnesweepOnTheCpuShapeIsRefusedBeforeAnythingIsWritten) {
  const std::vector<std::string> run = {"run", "--preset", "quick", "--scenes", "cornell", "--batches", "primary",
                                        "--encoders", "hcc", "--reps", "1", "--warmup", "0", "--max-time", "0"};
  auto with = [&](const std::string& passes) {
    std::vector<std::string> args = run;
    args.insert(args.end(), {"--sort-passes", passes});
    return args;
  };
  expect_refused(with("onesweep"), {"--sort-passes onesweep", "CPU shape", "use auto or reduce-then-scan"});
  expect_refused(with("fastest"), {"--sort-passes", "auto,reduce-then-scan,onesweep"});
}

// Found by fuzz/cli_fuzzer.cpp: CLI11 converts a flag's value with std::stoll and its out_of_range
// escaped as "internal error: stoll" (exit 3). It is bad input.
TEST(CliExitCodes, AFlagValueOutOfRangeIsBadInput) {
  const CliResult r = run_cli({"sortbench", "--no-large=99999999999999999999999"});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("raysort: error: a value on the command line is out of range"), std::string::npos) << r.err;
}
