#include "util/text.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace raysort {

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = text.find(',', start);
    std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (!item.empty() && std::find(out.begin(), out.end(), item) == out.end()) out.push_back(std::move(item));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

std::string number_range_text(double lo, double hi, bool whole, bool above_lo) {
  // Whole numbers as integers (every bound an option has fits 64 bits exactly as a double).
  if (whole) return fmt::format("a whole number from {} to {}", static_cast<std::uint64_t>(lo), static_cast<std::uint64_t>(hi));
  if (std::isinf(hi)) return above_lo ? fmt::format("a finite number above {:g}", lo) : fmt::format("a finite number, {:g} or more", lo);
  return above_lo ? fmt::format("a finite number above {:g} and at most {:g}", lo, hi)
                  : fmt::format("a finite number from {:g} to {:g}", lo, hi);
}

}  // namespace raysort
