// libFuzzer target for the ray batch file reader (issue 45, item 2; render/ray_file.h): on arbitrary
// bytes parse_ray_file either returns a batch whose bytes, written again, are the input exactly
// (the layout has one spelling: no padding, the size follows from the header), or throws one line.
// Built by `make fuzz`.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "render/ray_file.h"
#include "scene_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  raysort::fuzz::expect_loaded_or_one_line_error([&] {
    const raysort::RayFile f = raysort::parse_ray_file(bytes, "fuzz.rays");
    if ((f.has_hits && f.hits.size() != f.rays.size()) || (!f.has_hits && !f.hits.empty()) ||
        raysort::ray_file_bytes(f) != bytes) {
      std::fprintf(stderr, "parsed batch does not write back to its input (%zu rays)\n", f.rays.size());
      std::abort();
    }
  });
  return 0;
}
