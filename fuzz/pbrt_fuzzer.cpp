// libFuzzer target for the pbrt-v4 loader (issue 45): parse_pbrt on arbitrary text loads a scene
// that passes fuzz/scene_checks.h or throws one line. Include/Import and plymesh files are looked
// for in a folder that does not exist. Built by `make fuzz`.
#include <cstdint>
#include <string>

#include "scene_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  raysort::fuzz::expect_loaded_or_one_line_error([&] {
    raysort::fuzz::check_scene(raysort::parse_pbrt(text, "fuzz.pbrt", "/nonexistent-raysort-fuzz-dir").scene);
  });
  return 0;
}
