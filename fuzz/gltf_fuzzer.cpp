// libFuzzer target for the glTF loader (issue 45): tinygltf and our reader on arbitrary bytes (JSON
// .gltf, or .glb when they start with "glTF") load a scene that passes fuzz/scene_checks.h or throw
// one line. External buffers are looked for in a folder that does not exist. Built by `make fuzz`.
#include <cstdint>
#include <string>

#include "scene_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  raysort::fuzz::expect_loaded_or_one_line_error([&] {
    raysort::fuzz::check_scene(raysort::parse_gltf(bytes, "fuzz.gltf", "/nonexistent-raysort-fuzz-dir").scene);
  });
  return 0;
}
