#include "util/embedded.h"

namespace raysort {

std::optional<std::string_view> find_embedded(std::string_view path) {
  for (const auto& f : embedded_files())
    if (f.path == path) return f.contents;
  return std::nullopt;
}

}  // namespace raysort
