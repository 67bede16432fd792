// libFuzzer target for the PLY reader (issue 45): parse_ply on arbitrary bytes loads a mesh that
// passes fuzz/scene_checks.h or throws one line. Built by `make fuzz`.
#include <cstdint>
#include <string>

#include "scene_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  raysort::fuzz::expect_loaded_or_one_line_error([&] {
    raysort::IgnoredFeatures ignored;
    raysort::fuzz::check_mesh(raysort::parse_ply(bytes, "fuzz.ply", ignored), 1);
  });
  return 0;
}
