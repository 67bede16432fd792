// Encoders from files (issue 41, item 5; docs/encoders.md, "An encoder from a file"): a user's OpenCL C
// function, built at run time inside cl/encode_file.h. Its inputs reach it (the example's keys are
// the z-y-x Morton code; a file's HCC and PPC codes from the inputs it is given equal the built-in
// encoders'), run and encodebench take it and name it by file name and SHA-256, its keys are the
// same on a second launch and on PoCL's two devices, and bad files are refused in one line (or
// with the build log at the file's own lines) before any work.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench/encoder_files.h"
#include "encode/encode.h"
#include "encode/encoder_file.h"
#include "scene/provenance.h"
#include "test_util.h"

namespace fs = std::filesystem;
using namespace raysort;
using raysort::testing::CliResult;
using raysort::testing::run_cli;

namespace {

const std::string kExample = std::string(RAYSORT_SOURCE_DIR) + "/docs/examples/morton_zyx.cl";

std::string write_file(const std::string& path, const std::string& text) {
  fs::create_directories(fs::path(path).parent_path());
  std::ofstream(path) << text;
  return path;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// A tiny matrix: cornell at 16x9, primary and bounce1, one round per cell.
std::vector<std::string> tiny_run(const std::string& encoders, const std::string& out) {
  return {"run",     "--scenes", "cornell", "--batches", "primary,bounce1", "--resolution", "16x9", "--bits", "16,64",
          "--reps",  "1",        "--warmup", "0",        "--max-time",      "0",            "--encoders", encoders,
          "--out",   out};
}

std::vector<std::string> tiny_encodebench(const std::string& encoders) {
  return {"encodebench", "--scene", "cornell", "--batch", "bounce1", "--resolution", "16x9", "--bits", "16,32,64",
          "--reps",      "1",       "--warmup", "0",      "--max-time", "0",          "--encoders", encoders};
}

nlohmann::json read_json(const std::string& path) { return nlohmann::json::parse(read_text(path)); }

// The example's code on the host: Origin's Morton code with the x and z axes swapped.
std::uint64_t zyx_code(const RsEncodeFrame& frame, const RsRay& ray) {
  rs_u32 q[3];
  rs_quantize_point(&frame, rs_load3(ray.o), RS_ORIGIN_LEVELS, q);
  return (rs_morton3(q[2] >> 1, q[1] >> 1, q[0] >> 1) << 1) | (q[2] & 1u);
}

}  // namespace

// The example's kernel gets the ray and the frame: its keys are the z-y-x Morton code computed here,
// at 16, 32 and 64 bits, on every batch of cornell.
TEST(FileEncoder, ExampleKeysAreTheZyxMortonCode) {
  const Encoder e = load_encoder_file(kExample);
  EXPECT_EQ(encoder_name(e), "file:morton_zyx");
  EXPECT_FALSE(has_host_twin(e));
  EXPECT_EQ(load_encoder_file(kExample), e) << "the same file twice is one encoder";
  const auto s = raysort::testing::scene_batches("cornell", 32, 18);
  DeviceEncoder dev(raysort::testing::runtime(), s.bvh, s.bvh.bounds());
  for (const ReferencedBatch& b : s.batches)
    for (unsigned bits : {16u, 32u, 64u}) {
      const std::vector<std::uint64_t> keys = dev.run(e, bits, b.batch.rays).keys;
      ASSERT_EQ(keys.size(), b.batch.rays.size());
      std::size_t bad = 0;
      for (std::size_t i = 0; i < keys.size(); ++i)
        bad += keys[i] != rs_key_from_code(zyx_code(dev.scene().frame(), b.batch.rays[i]), bits);
      EXPECT_EQ(bad, 0u) << b.batch.name << " at " << bits << " bits";
    }
}

// The scene inputs reach the file: HCC's code from the cut it is given, and PPC's from the BVH, are
// the built-in HCC's and PPC's keys (their host twins), bit for bit.
TEST(FileEncoder, CutAndBvhInputsGiveHccAndPpcKeys) {
  const std::string dir = raysort::testing::temp_path("inputs");
  const std::string signature =
      "rs_u64 rs_file_code(const RsEncodeFrame* frame, RsRay ray, uint bits, const RsFileScene* scene) {\n";
  const Encoder hcc = load_encoder_file(write_file(
      dir + "/hcc_again.cl", signature + "  return rs_box_set_code(ray, scene->cut, scene->cut_boxes, bits, 0u);\n}\n"));
  const Encoder ppc = load_encoder_file(write_file(
      dir + "/ppc_again.cl", signature + "  return rs_prefix_path_code(scene->nodes, scene->triangles, ray, bits);\n}\n"));
  const auto s = raysort::testing::scene_batches("cornell", 32, 18);
  DeviceEncoder dev(raysort::testing::runtime(), s.bvh, s.bvh.bounds());
  for (const ReferencedBatch& b : s.batches)
    for (unsigned bits : {16u, 32u, 64u}) {
      EXPECT_EQ(dev.run(hcc, bits, b.batch.rays).keys, encode_on_host(Encoder::HCC, bits, dev.scene(), b.batch.rays))
          << b.batch.name << " at " << bits << " bits";
      EXPECT_EQ(dev.run(ppc, bits, b.batch.rays).keys, encode_on_host(Encoder::PPC, bits, dev.scene(), b.batch.rays))
          << b.batch.name << " at " << bits << " bits";
    }
}

// run and encodebench take the example; the set names it file:morton_zyx in its cell ids and records
// its path and SHA-256 in meta.json; the tables and encodebench say "no host twin".
TEST(FileEncoder, ExampleRunsAndTheSetNamesItBySha256) {
  const std::string out = raysort::testing::temp_path("example-set");
  const CliResult r = run_cli(tiny_run("origin,file:" + kExample, out));
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json meta = read_json(out + "/meta.json");
  EXPECT_EQ(meta["matrix"]["encoders"], nlohmann::json({"origin", "file:morton_zyx"}));
  ASSERT_TRUE(meta.contains("encoder_files") && meta["encoder_files"].contains("file:morton_zyx")) << meta.dump(1);
  const nlohmann::json& file = meta["encoder_files"]["file:morton_zyx"];
  EXPECT_EQ(file["path"], kExample);
  EXPECT_EQ(file["sha256"], sha256_file(kExample));
  EXPECT_EQ(file["host_twin"], false);
  for (const char* id : {"cornell__primary__file%3Amorton_zyx__16.json", "cornell__bounce1__file%3Amorton_zyx__64.json"})
    EXPECT_TRUE(fs::exists(out + "/cells/" + id)) << id;
  const std::string tables = read_text(out + "/tables.md");
  EXPECT_NE(tables.find("| file:morton_zyx | `" + kExample + "` | `" + sha256_file(kExample) + "` | no host twin |"),
            std::string::npos)
      << tables.substr(0, 3000);

  const CliResult bench = run_cli(tiny_encodebench("origin,file:" + kExample));
  ASSERT_EQ(bench.code, 0) << bench.err;
  std::size_t rows = 0;
  for (const std::string& line : lines_of(bench.out))
    if (line.rfind("file:morton_zyx ", 0) == 0) {
      ++rows;
      EXPECT_NE(line.find(" no host twin "), std::string::npos) << line;
    }
  EXPECT_EQ(rows, 3u) << bench.out;
  EXPECT_NE(bench.out.find(sha256_file(kExample)), std::string::npos) << bench.out;
}

// The same keys on PoCL's two devices (single-threaded basic and pthread): the cells' key hashes
// agree, as scripts/cross-impl.sh requires of the built-in encoders.
TEST(FileEncoder, KeysAreTheSameOnPoclBasicAndPthread) {
  const std::vector<std::string> env = {"POCL_DEVICES=basic pthread"};
  std::map<std::string, std::string> sets;
  for (const std::string device : {"basic", "pthread"}) {
    sets[device] = raysort::testing::temp_path("devices-" + device);
    std::vector<std::string> args = tiny_run("file:" + kExample, sets[device]);
    args.insert(args.end(), {"--device", device});
    const CliResult r = run_cli(args, env);
    if (device == "basic" && r.code != 0 && r.err.find("no device name contains") != std::string::npos)
      GTEST_SKIP() << "no PoCL basic device: " << r.err;
    ASSERT_EQ(r.code, 0) << device << ": " << r.err;
  }
  const CliResult cmp = run_cli({"compare", sets["basic"], sets["pthread"], "--metrics", "keys_hash,order_hash",
                                 "--fail-if", "keys_hash!=", "--fail-if", "order_hash!=", "--fail-if", "status!=",
                                 "--fail-if", "missing"});
  EXPECT_EQ(cmp.code, 0) << cmp.out << cmp.err;
  EXPECT_NE(cmp.out.find("file:morton_zyx"), std::string::npos) << cmp.out;
}

// Keys that change from one launch to the next (here a counter in the BVH copy the file is given)
// fail every cell of that encoder in run, and its rows in encodebench.
TEST(FileEncoder, KeysThatDifferOnASecondLaunchFailTheCells) {
  const std::string file = write_file(
      raysort::testing::temp_path("counter") + "/counter.cl",
      "rs_u64 rs_file_code(const RsEncodeFrame* frame, RsRay ray, uint bits, const RsFileScene* scene) {\n"
      "  return (rs_u64)atomic_inc((volatile __global uint*)&scene->nodes[0].first) << 48;\n"
      "}\n");
  const std::string out = raysort::testing::temp_path("counter-set");
  const CliResult r = run_cli(tiny_run("file:" + file, out));
  EXPECT_EQ(r.code, 1) << r.err;
  std::size_t failed = 0;
  for (const auto& entry : fs::directory_iterator(out + "/cells")) {
    const nlohmann::json cell = read_json(entry.path().string());
    if (cell["encoder"] != "file:counter") continue;
    ++failed;
    EXPECT_EQ(cell["status"], "failed");
    EXPECT_NE(cell["error"].get<std::string>().find("other keys on a second launch"), std::string::npos) << cell["error"];
  }
  EXPECT_EQ(failed, 4u);
  const CliResult bench = run_cli(tiny_encodebench("file:" + file));
  EXPECT_EQ(bench.code, 1);
  EXPECT_NE(bench.err.find("or, with no host twin, from a second launch"), std::string::npos) << bench.err;
}

// A file that does not compile: the OpenCL build log at the file's own line, before any work (no
// result folder), from run and encodebench alike; exit 1, bad input (docs/errors.md, "Exit codes").
TEST(FileEncoder, ACompileErrorShowsTheBuildLogAtTheFilesLine) {
  const std::string file = write_file(raysort::testing::temp_path("broken") + "/broken.cl",
                                      "/* line 1 */\n"
                                      "rs_u64 rs_file_code(const RsEncodeFrame* frame, RsRay ray, uint bits,\n"
                                      "                    const RsFileScene* scene) {\n"
                                      "  return rs_morton3(1u, 2u, 3u) +;\n"
                                      "}\n");
  const std::string out = raysort::testing::temp_path("broken-set");
  for (const std::vector<std::string>& args : {tiny_run("origin,file:" + file, out), tiny_encodebench("file:" + file)}) {
    const CliResult r = run_cli(args);
    EXPECT_EQ(r.code, 1) << args[0] << ": " << r.err;
    EXPECT_NE(r.err.find("raysort: error: encoder file " + file + " (file:broken) does not compile"), std::string::npos)
        << r.err;
    EXPECT_NE(r.err.find(file + ":4:"), std::string::npos) << args[0] << ": the log names the file's line 4\n" << r.err;
    EXPECT_EQ(r.out.find("broken"), std::string::npos) << "no table row: " << r.out;
  }
  EXPECT_FALSE(fs::exists(out)) << "refused before the result set was written";
}

// A file that cannot be an encoder is refused in one line naming it and the fix, before any work.
TEST(FileEncoder, AMissingUnreadableOrOddFileIsOneLine) {
  const std::string dir = raysort::testing::temp_path("odd-files");
  fs::create_directories(dir + "/folder.cl");
  ASSERT_EQ(::mkfifo((dir + "/pipe.cl").c_str(), 0600), 0);
  const std::string signature = "rs_u64 rs_file_code(const RsEncodeFrame* f, RsRay r, uint b, const RsFileScene* s);\n";
  write_file(dir + "/locked.cl", signature);
  ::chmod((dir + "/locked.cl").c_str(), 0);
  write_file(dir + "/empty.cl", "");
  write_file(dir + "/my enc.cl", signature);
  fs::resize_file(write_file(dir + "/huge.cl", signature), std::uintmax_t(17) << 20);
  write_file(dir + "/a/twin.cl", read_text(kExample));
  write_file(dir + "/b/twin.cl", read_text(kExample));
  struct Case {
    std::string encoders, says;
  };
  std::vector<Case> cases = {
      {"file:" + dir + "/missing.cl", "encoder file " + dir + "/missing.cl does not exist; give the path"},
      {"file:" + dir + "/folder.cl", "encoder file " + dir + "/folder.cl is a directory, not a regular file; give"},
      {"file:" + dir + "/pipe.cl", "encoder file " + dir + "/pipe.cl is a FIFO (named pipe), not a regular file; give"},
      {"file:" + dir + "/huge.cl", "encoder file " + dir + "/huge.cl is 17.0 MiB, over the 16.0 MiB bound"},
      {"file:" + dir + "/empty.cl", "encoder file " + dir + "/empty.cl does not define rs_file_code; define"},
      {"file:" + dir + "/my enc.cl", "its name 'my enc' names the encoder (file:my enc)"},
      {"file:", "--encoders file: names no file"},
      {"file:" + dir + "/a/twin.cl,file:" + dir + "/b/twin.cl", "would both be the encoder file:twin; rename one"}};
  if (::geteuid() != 0)  // root reads a file of mode 0 all the same
    cases.push_back({"file:" + dir + "/locked.cl", "cannot open encoder file " + dir + "/locked.cl: Permission denied; give"});
  const std::string out = raysort::testing::temp_path("odd-set");
  for (const Case& c : cases)
    for (const std::vector<std::string>& args : {tiny_run(c.encoders, out), tiny_encodebench(c.encoders)}) {
      const CliResult r = run_cli(args);
      EXPECT_EQ(r.code, 1) << c.encoders;
      const std::vector<std::string> lines = lines_of(r.err);
      ASSERT_EQ(lines.size(), 1u) << args[0] << " " << c.encoders << ": " << r.err;
      EXPECT_EQ(lines[0].rfind("raysort: error: ", 0), 0u) << lines[0];
      EXPECT_NE(lines[0].find(c.says), std::string::npos) << lines[0];
      EXPECT_FALSE(fs::exists(out)) << c.encoders;
    }
}

// A set resumes with the same file, and is refused, naming the encoder and both checksums, when the
// file changed; compare says the two sets ran different files.
TEST(FileEncoder, AResumeWithAChangedFileIsRefused) {
  const std::string file = write_file(raysort::testing::temp_path("resume") + "/mine.cl", read_text(kExample));
  const std::string out = raysort::testing::temp_path("resume-set"), other = raysort::testing::temp_path("resume-other");
  ASSERT_EQ(run_cli(tiny_run("file:" + file, out)).code, 0);
  const std::string before = sha256_file(file);
  const CliResult again = run_cli(tiny_run("file:" + file, out));
  EXPECT_EQ(again.code, 0) << again.err;
  EXPECT_NE(again.out.find("0 cells run, 6 already done"), std::string::npos) << again.out;

  std::ofstream(file, std::ios::app) << "/* edited */\n";
  const std::string after = sha256_file(file);
  const CliResult changed = run_cli(tiny_run("file:" + file, out));
  EXPECT_EQ(changed.code, 1);
  EXPECT_NE(changed.err.find(out + " was started with other encoder files (file:mine: sha256 " + before.substr(0, 12) +
                             " in A, " + after.substr(0, 12) + " in B)"),
            std::string::npos)
      << changed.err;
  EXPECT_EQ(read_json(out + "/meta.json")["encoder_files"]["file:mine"]["sha256"], before);

  ASSERT_EQ(run_cli(tiny_run("file:" + file, other)).code, 0);
  const CliResult cmp = run_cli({"compare", out, other});
  EXPECT_NE(cmp.err.find("raysort compare: encoder files: file:mine: sha256 " + before.substr(0, 12)), std::string::npos)
      << cmp.err;
}

TEST(FileEncoder, DifferencesOfRecordedFiles) {
  const nlohmann::json a = {{"encoder_files", {{"file:x", {{"path", "x.cl"}, {"sha256", "aa"}}}}}};
  const nlohmann::json b = {{"encoder_files", {{"file:x", {{"path", "y/x.cl"}, {"sha256", "aa"}}}}}};
  const nlohmann::json c = {{"encoder_files", {{"file:x", {{"path", "x.cl"}, {"sha256", "bb"}}}}}};
  EXPECT_TRUE(encoder_file_differences(a, b).empty()) << "a moved file with the same text is the same encoder";
  EXPECT_EQ(encoder_file_differences(a, c), std::vector<std::string>{"file:x: sha256 aa in A, bb in B"});
  EXPECT_EQ(encoder_file_differences(a, nlohmann::json::object()),
            std::vector<std::string>{"file:x: recorded in A only (sha256 aa)"});
  EXPECT_TRUE(encoder_file_differences(nlohmann::json::object(), nlohmann::json::object()).empty());
  const nlohmann::json odd = {{"encoder_files", {{"file:x", 3}}}};
  EXPECT_EQ(encoder_file_differences(a, odd), std::vector<std::string>{"file:x: sha256 aa in A, no checksum in B"});
}
