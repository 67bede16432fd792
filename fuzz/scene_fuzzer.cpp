// libFuzzer target for the scene parser (issue 8): parse_scene_toml on arbitrary text must give a
// scene or throw raysort::Error; anything else (a crash, a sanitizer report, another exception) is
// a finding. OBJ references resolve under a scene root that does not exist, so no file is read.
// Scenes are capped at 65,536 triangles (SceneOptions::max_triangles; bigger ones end in the
// ResourceError the cap is tested by): the parser and every generator still run, at sizes that
// keep an execution in milliseconds instead of the seconds a 524 K-triangle terrain takes under
// the sanitizers, so the fuzzer reaches millions of executions.
// Built by `make fuzz` (CMake option RAYSORT_FUZZ, clang).
#include <cstdint>
#include <string>

#include "scene/load.h"
#include "util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  raysort::SceneOptions opts;
  opts.scene_root = "/nonexistent-raysort-fuzz-root";
  opts.max_triangles = 1 << 16;
  try {
    raysort::Scene scene = raysort::parse_scene_toml(text, "fuzz.toml", opts);
    (void)scene.triangle_count();
  } catch (const raysort::Error&) {
  }
  return 0;
}
