#include "util/fnv.h"

#include <fmt/format.h>

namespace raysort {

std::string fnv1a_hex(const void* data, std::size_t bytes) { return fmt::format("{:016x}", fnv1a_bytes(data, bytes)); }

}  // namespace raysort
