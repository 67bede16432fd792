#pragma once
// Files compiled into the binary at build time (cmake/embed.cmake): the OpenCL sources in cl/,
// the scene files in scenes/ and the GPU profiles in gpu/profiles/, so `raysort` runs from any directory.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace raysort {

struct EmbeddedFile {
  std::string_view path;      // relative to the source tree, e.g. "cl/trace.cl"
  std::string_view contents;
};

const std::vector<EmbeddedFile>& embedded_files();

// The embedded file at `path` ("cl/trace.cl"), if there is one.
std::optional<std::string_view> find_embedded(std::string_view path);

}  // namespace raysort
