// libFuzzer target for the OBJ path (issue 8): parse_obj on arbitrary bytes must load a mesh whose
// vertices are all finite and whose indices are all in range, or throw raysort::Error with one
// line. Anything else (a crash, a sanitizer report, another exception, a multi-line message) is a
// finding. Built by `make fuzz` (CMake option RAYSORT_FUZZ, clang).
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstdio>
#include <string>
#include <vector>

#include "scene/load.h"
#include "util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  std::vector<raysort::Material> materials{raysort::Material{}};
  try {
    // No .mtl files are read: the material folder does not exist.
    raysort::Mesh mesh = raysort::parse_obj(text, "fuzz.obj", "/nonexistent-raysort-fuzz-mtl", materials);
    for (const auto& p : mesh.positions)
      for (int k = 0; k < 3; ++k)
        if (!std::isfinite(p[k])) {
          std::fprintf(stderr, "non-finite vertex loaded\n");
          std::abort();
        }
    for (const auto& t : mesh.triangles)
      for (int k = 0; k < 3; ++k)
        if (t[k] >= mesh.positions.size()) {
          std::fprintf(stderr, "index out of range loaded\n");
          std::abort();
        }
    for (auto id : mesh.material)
      if (id < 0 || static_cast<std::size_t>(id) >= materials.size()) {
        std::fprintf(stderr, "material id out of range\n");
        std::abort();
      }
  } catch (const raysort::Error& e) {
    if (std::string(e.what()).find('\n') != std::string::npos) {
      std::fprintf(stderr, "multi-line error: %s\n", e.what());
      std::abort();
    }
  }
  return 0;
}
