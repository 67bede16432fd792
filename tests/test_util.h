#pragma once
// Helpers shared by the tests: the OpenCL device under test, and the scene-root policy for tests
// that need real scenes (skip with a message when the folder is absent, fail under CI=true).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "bvh/prepared_scene.h"
#include "runtime/runtime.h"
#include "render/batches.h"
#include "scene/load.h"
#include "shared.h"

namespace raysort::testing {

// One runtime per test binary (program builds are slow on PoCL; reuse them).
inline Runtime& runtime() {
  static std::unique_ptr<Runtime> rt = std::make_unique<Runtime>(select_device(""));
  return *rt;
}

inline bool under_ci() {
  const char* ci = std::getenv("CI");
  return ci && std::string(ci) == "true";
}

// The real-scene root, or "" (after GTEST_SKIP or a failure) when it is absent.
inline std::string real_scene_root() { return resolve_scene_root({}); }

// The ray o + t·d for t in [tmin, tmax] (tests build rays by hand from numbers).
inline RsRay ray(float ox, float oy, float oz, float dx, float dy, float dz, float tmax = RS_T_FAR, float tmin = 0.0f) {
  RsRay r{};
  r.o[0] = ox, r.o[1] = oy, r.o[2] = oz, r.tmin = tmin;
  r.d[0] = dx, r.d[1] = dy, r.d[2] = dz, r.tmax = tmax;
  return r;
}

// A scene by name, its BVH and its ray batches at width × height (the setup of many tests).
struct SceneBatches {
  Scene scene;
  Scene::Flat tris;
  Bvh bvh;
  std::vector<ReferencedBatch> batches;
};
inline SceneBatches scene_batches(const std::string& name, std::uint32_t width, std::uint32_t height) {
  SceneOptions opts;
  opts.frame = {width, height, 0};
  PreparedScene p = prepare_scene(name, opts);
  SceneBatches s{std::move(p.scene), std::move(p.tris), std::move(p.bvh), {}};
  s.batches = generate_batches(s.scene, s.tris, s.bvh, {});
  return s;
}

// A unit quad in the z = 0 plane, [0,1]² (two triangles), plus a smaller one behind it at z = -1.
inline Scene two_quads() {
  Scene s;
  s.name = "two-quads";
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.25f, 0.25f, -1}, {0.75f, 0.25f, -1}, {0.75f, 0.75f, -1}, {0.25f, 0.75f, -1}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
  s.meshes.push_back(m);
  return s;
}

// One temporary folder per test process, <tmp>/raysort-tests-<pid>, removed when the process
// ends with every test passed (kept, for a look, when one failed): tests clean up after themselves.
inline const std::filesystem::path& temp_root() {
  struct Root {
    std::filesystem::path path = std::filesystem::temp_directory_path() / ("raysort-tests-" + std::to_string(::getpid()));
    Root() { std::filesystem::create_directories(path); }
    ~Root() {
      if (::getpid() != owner) return;  // a forked child exiting
      if (!::testing::UnitTest::GetInstance()->Failed()) {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
      }
    }
    pid_t owner = ::getpid();
  };
  static Root root;
  return root.path;
}
// A fresh (absent) path below temp_root().
inline std::string temp_path(const std::string& name) {
  std::filesystem::path p = temp_root() / name;
  std::filesystem::remove_all(p);
  return p.string();
}

// What the raysort binary printed and its exit code (128 + signal when killed by one).
struct CliResult {
  int code = -1;
  std::string out, err;
  double seconds = 0;                // wall time
  std::uint64_t peak_rss_bytes = 0;  // of the raysort process (wait4's rusage)
};

// Runs the raysort binary (RAYSORT_BINARY, set by CMake for every test) with `args`, and `env` as
// NAME=VALUE entries added to its environment, capturing stdout and stderr, its wall time and peak RSS.
inline CliResult run_cli(const std::vector<std::string>& args, const std::vector<std::string>& env = {}) {
  static int calls = 0;
  const std::string stem = (std::filesystem::temp_directory_path() /
                            ("raysort_test_" + std::to_string(::getpid()) + "_" + std::to_string(++calls)))
                               .string();
  const std::string out_file = stem + ".out", err_file = stem + ".err";
  const auto start = std::chrono::steady_clock::now();
  pid_t pid = fork();
  if (pid == 0) {
    for (const auto& e : env) ::putenv(const_cast<char*>(e.c_str()));
    std::string bin = RAYSORT_BINARY;
    std::vector<std::string> copy = args;
    std::vector<char*> argv{bin.data()};
    for (auto& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    int out = ::open(out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    int err = ::open(err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(out, 1);
    ::dup2(err, 2);
    ::execv(bin.c_str(), argv.data());
    _exit(127);
  }
  int status = 0;
  struct rusage usage {};
  ::wait4(pid, &status, 0, &usage);
  CliResult r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.peak_rss_bytes = static_cast<std::uint64_t>(usage.ru_maxrss) * 1024;
  auto slurp = [](const std::string& f) {
    std::ifstream in(f);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  r.out = slurp(out_file);
  r.err = slurp(err_file);
  std::filesystem::remove(out_file);
  std::filesystem::remove(err_file);
  return r;
}

}  // namespace raysort::testing

// Use at the top of a test that needs ../shared/scenes.
#define RAYSORT_REQUIRE_REAL_SCENES()                                                                      \
  do {                                                                                                     \
    std::string root_ = ::raysort::testing::real_scene_root();                                             \
    if (!std::filesystem::exists(root_ + "/SOURCES.md") && !std::filesystem::exists(root_ + "/sibenik")) { \
      if (::raysort::testing::under_ci()) FAIL() << "real scenes not found at '" << root_ << "' under CI"; \
      GTEST_SKIP() << "real scenes not found at '" << root_ << "' (set RAYSORT_SCENE_ROOT)";                \
    }                                                                                                      \
  } while (0)
