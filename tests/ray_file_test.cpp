// Ray batches out and in (issue 45, item 2; docs/rays-format.md): the file keeps every bit of a
// batch, a batch exported and imported through the CLI gives the same keys, orders and hits as the
// generated one, and a bad file is refused in one line before anything is written.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <regex>

#include "bench/batch_file.h"
#include "bench/result_set.h"
#include "render/ray_file.h"
#include "scene/provenance.h"
#include "test_util.h"
#include "util/atomic_file.h"
#include "util/error.h"

namespace raysort {
namespace {

namespace fs = std::filesystem;
using testing::run_cli;
using testing::temp_path;

// Every ray field's bits, compared as integers (NaN payloads and -0 included).
void expect_same_bits(const std::vector<RsRay>& a, const std::vector<RsRay>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(std::bit_cast<std::uint32_t>(a[i].o[k]), std::bit_cast<std::uint32_t>(b[i].o[k])) << "ray " << i;
      ASSERT_EQ(std::bit_cast<std::uint32_t>(a[i].d[k]), std::bit_cast<std::uint32_t>(b[i].d[k])) << "ray " << i;
    }
    ASSERT_EQ(std::bit_cast<std::uint32_t>(a[i].tmin), std::bit_cast<std::uint32_t>(b[i].tmin)) << "ray " << i;
    ASSERT_EQ(std::bit_cast<std::uint32_t>(a[i].tmax), std::bit_cast<std::uint32_t>(b[i].tmax)) << "ray " << i;
  }
}

TEST(RayFile, KeepsEveryBitOfRaysAndHits) {
  RayFile f;
  f.batch_name = "shadow2";
  f.any_hit = true;
  f.scene_sha256 = sha256_bytes(std::string(62, 'a') + "0f");
  f.command = "raysort rays --scene x";
  const float odd[] = {-0.0f, std::numeric_limits<float>::denorm_min(), std::numeric_limits<float>::infinity(),
                       std::bit_cast<float>(0x7fc01234u), 1.0f / 3.0f, -3.0e38f, 7.0f, 1e-30f};
  for (int i = 0; i < 8; ++i) {
    RsRay r{};
    for (int k = 0; k < 3; ++k) r.o[k] = odd[(i + k) % 8], r.d[k] = odd[(i + k + 3) % 8];
    r.tmin = odd[(i + 6) % 8];
    r.tmax = odd[(i + 7) % 8];
    f.rays.push_back(r);
    f.hits.push_back(RsHit{odd[i], i == 3 ? RS_NO_HIT : static_cast<std::uint32_t>(i * 1000), 0.0f, 0.0f});
  }
  f.has_hits = true;
  const RayFile back = parse_ray_file(ray_file_bytes(f), "mem.rays");
  EXPECT_EQ(back.batch_name, f.batch_name);
  EXPECT_TRUE(back.any_hit);
  EXPECT_EQ(back.scene_sha256, f.scene_sha256);
  EXPECT_EQ(back.command, f.command);
  expect_same_bits(back.rays, f.rays);
  ASSERT_TRUE(back.has_hits);
  EXPECT_EQ(hits_hash(back.hits), hits_hash(f.hits));
  EXPECT_EQ(ray_file_hit_differences(back, f.hits), 0u);
  // The layout of docs/rays-format.md: origin, direction, tmin, tmax per ray, right after the texts.
  const std::string bytes = ray_file_bytes(f);
  const std::size_t rays_at = kRayFileHeaderBytes + f.batch_name.size() + f.command.size();
  EXPECT_EQ(bytes.size(), rays_at + 8 * (kRayFileRayBytes + kRayFileHitBytes));
  float tmin = 0;
  std::memcpy(&tmin, bytes.data() + rays_at + 24, 4);
  EXPECT_EQ(std::bit_cast<std::uint32_t>(tmin), std::bit_cast<std::uint32_t>(f.rays[0].tmin));
}

// The hits hash a command printed after batch `name`'s row (trace) or on its own line (rays).
std::string printed_hits_hash(const std::string& out, const std::string& name) {
  std::smatch m;
  const std::regex row("\\n" + name + " [^\\n]*\\n +hits hash ([0-9a-f]{16})");
  return std::regex_search(out, m, row) ? m[1].str() : "";
}

// encoder/bits -> (keys hash, order hash) of a result set's cells.
std::map<std::string, std::pair<std::string, std::string>> fingerprints(const std::string& dir) {
  std::map<std::string, std::pair<std::string, std::string>> out;
  for (const auto& c : ResultSet::load(dir).cells()) {
    EXPECT_EQ(c.status, "ok") << c.id() << ": " << c.error;
    out[c.encoder + "/" + std::to_string(c.bits)] = {c.keys_hash, c.order_hash};
  }
  return out;
}

const std::vector<std::string> kFrame = {"--scene", "cornell", "--resolution", "64x36", "--seed", "3"};
std::vector<std::string> with_frame(std::vector<std::string> args) {
  args.insert(args.begin() + 1, kFrame.begin(), kFrame.end());
  return args;
}

// (a) The CLI's round trip: the exported rays are the generated batch bit for bit, and trace, run
// and encodebench given the file find the same hits, keys and orders as on the generated batch.
TEST(RayFileCli, ExportedBatchReimportedGivesTheSameRaysKeysOrdersAndHits) {
  const std::string file = temp_path("cornell-bounce1.rays");
  const testing::CliResult exported = run_cli(with_frame({"rays", "--batch", "bounce1", "--hits", "--export", file}));
  ASSERT_EQ(exported.code, 0) << exported.err;
  SceneOptions opts;
  opts.frame = {64, 36, 0};
  const PreparedScene p = prepare_scene("cornell", opts);
  RayGenOptions gen;
  gen.seed = 3;
  const std::vector<ReferencedBatch> frame = generate_batches(p.scene, p.tris, p.bvh, gen);
  const auto bounce1 = std::find_if(frame.begin(), frame.end(), [](const auto& b) { return b.batch.name == "bounce1"; });
  ASSERT_NE(bounce1, frame.end());
  const RayFile f = read_ray_file(file);
  EXPECT_EQ(f.batch_name, "bounce1");
  expect_same_bits(f.rays, bounce1->batch.rays);
  EXPECT_EQ(ray_file_hit_differences(f, bounce1->reference_hits), 0u);

  const std::vector<std::string> quick = {"--reps", "2", "--warmup", "0", "--max-time", "0.2"};
  auto plus = [](std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
  };
  const testing::CliResult generated = run_cli(with_frame(plus({"trace"}, quick)));
  const testing::CliResult imported = run_cli(with_frame(plus({"trace", "--rays", file}, quick)));
  ASSERT_EQ(generated.code, 0) << generated.err;
  ASSERT_EQ(imported.code, 0) << imported.err;
  const std::string hash = printed_hits_hash(generated.out, "bounce1");
  EXPECT_FALSE(hash.empty()) << generated.out;
  EXPECT_EQ(printed_hits_hash(imported.out, "file:cornell-bounce1"), hash) << imported.out;
  EXPECT_NE(imported.out.find("; 0 rays differ from the file's hits"), std::string::npos) << imported.out;

  const std::vector<std::string> cells = {"--encoders", "hcc,origin", "--bits", "32", "--reps", "2", "--warmup", "0"};
  const std::string a = temp_path("generated"), b = temp_path("imported");
  const testing::CliResult run_a = run_cli(with_frame(plus({"run", "--batches", "bounce1", "--out", a}, cells)));
  const testing::CliResult run_b = run_cli(with_frame(plus({"run", "--rays", file, "--out", b}, cells)));
  ASSERT_EQ(run_a.code, 0) << run_a.err;
  ASSERT_EQ(run_b.code, 0) << run_b.err;
  const auto fa = fingerprints(a), fb = fingerprints(b);
  EXPECT_EQ(fa.size(), 3u);  // NoSort, hcc, origin
  EXPECT_EQ(fa, fb);
  for (const auto& c : ResultSet::load(b).cells()) EXPECT_EQ(c.batch, "file:cornell-bounce1");
  const nlohmann::json meta = ResultSet::load(b).meta();
  EXPECT_EQ(meta["ray_files"]["file:cornell-bounce1"]["sha256"], sha256_file(file)) << meta.dump(1);
  EXPECT_EQ(meta["ray_files"]["file:cornell-bounce1"]["batch"], "bounce1");

  const testing::CliResult bench =
      run_cli(with_frame({"encodebench", "--rays", file, "--encoders", "hcc", "--bits", "32", "--reps", "2", "--warmup", "0"}));
  ASSERT_EQ(bench.code, 0) << bench.err;
  EXPECT_NE(bench.out.find("batch file:cornell-bounce1: " + std::to_string(f.rays.size()) + " rays"), std::string::npos)
      << bench.out;
}

// (b) A truncated file, a bad magic or version, a count that does not match, another scene's batch
// and a file that is not there are each refused in one line naming the file and the fix, exit 1, before any output.
TEST(RayFileCli, RefusesABadFileInOneLine) {
  const std::string good = temp_path("good.rays");
  ASSERT_EQ(run_cli(with_frame({"rays", "--batch", "primary", "--export", good})).code, 0);
  const std::string bytes = read_file(good);
  const std::string other_scene = temp_path("other.rays");
  ASSERT_EQ(run_cli({"rays", "--scene", "detail-room", "--resolution", "16x9", "--batch", "primary", "--export", other_scene}).code, 0);
  std::string bad_magic = bytes, bad_version = bytes;
  bad_magic[0] = 'X';
  bad_version[8] = 9;
  struct Case {
    std::string name, contents, says;
  };
  const std::vector<Case> cases = {
      {"truncated", bytes.substr(0, bytes.size() - 5), "truncated"},
      {"magic", bad_magic, "bad magic"},
      {"version", bad_version, "format version 9"},
      {"count", bytes + std::string(32, '\0'), "the ray count does not match the file"},
      {"scene", read_file(other_scene), "was exported from another scene"},
      {"missing", "", "does not exist"},  // not written
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string file = temp_path(c.name + ".rays");
    if (c.name != "missing") write_file_atomically(file, c.contents);
    for (const std::string command : {"trace", "run", "encodebench"}) {
      SCOPED_TRACE(command);
      const std::string out = temp_path(c.name + "-" + command);
      fs::create_directories(out);
      write_file_atomically(out + "/keep.txt", "written before\n");
      std::vector<std::string> args = with_frame({command, "--rays", file});
      if (command == "run") args.insert(args.end(), {"--encoders", "origin", "--out", out});
      const testing::CliResult r = run_cli(args);
      EXPECT_EQ(r.code, 1) << r.err;
      EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
      EXPECT_NE(r.err.find("raysort: error: ray file " + file), std::string::npos) << r.err;
      EXPECT_NE(r.err.find(c.says), std::string::npos) << r.err;
      EXPECT_NE(r.err.find("raysort rays"), std::string::npos) << r.err;  // the fix
      EXPECT_EQ(read_file(out + "/keep.txt"), "written before\n");
      EXPECT_FALSE(fs::exists(out + "/meta.json"));
    }
  }
}

// A result set started on one ray file does not resume on another of the same name (meta.json
// "ray_files" sha256), as with an encoder file.
TEST(RayFileCli, ResumeWithAChangedRayFileIsRefused) {
  const std::string dir = temp_path("resume");
  fs::create_directories(dir);
  const std::string file = dir + "/cornell-primary.rays";
  ASSERT_EQ(run_cli(with_frame({"rays", "--batch", "primary", "--export", file})).code, 0);
  const std::string out = temp_path("resume-set");
  const std::vector<std::string> run = with_frame({"run", "--rays", file, "--encoders", "origin", "--reps", "2",
                                                   "--warmup", "0", "--out", out});
  ASSERT_EQ(run_cli(run).code, 0);
  const std::string meta = read_file(out + "/meta.json");
  std::vector<std::string> reseeded = with_frame({"rays", "--batch", "primary", "--export", file});
  reseeded[6] = "4";  // --seed 4: another batch under the same name
  ASSERT_EQ(run_cli(reseeded).code, 0);
  const testing::CliResult r = run_cli(run);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_NE(r.err.find("was started with another ray file (file:cornell-primary: sha256"), std::string::npos) << r.err;
  EXPECT_EQ(read_file(out + "/meta.json"), meta);
  // A set of the new file beside the old one: compare says they traced different ray files.
  const std::string other = temp_path("resume-other");
  std::vector<std::string> run_other = run;
  run_other.back() = other;
  ASSERT_EQ(run_cli(run_other).code, 0);
  const testing::CliResult cmp = run_cli({"compare", out, other});
  EXPECT_NE(cmp.err.find("raysort compare: ray files: file:cornell-primary: sha256"), std::string::npos) << cmp.err;
}

}  // namespace
}  // namespace raysort
