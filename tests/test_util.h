#pragma once
// Helpers shared by the tests: the OpenCL device under test, and the scene-root policy for tests
// that need real scenes (skip with a message when the folder is absent, fail under CI=true).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>

#include "cl/runtime.h"
#include "scene/load.h"

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
