#pragma once
// Small text helpers for the command line's lists.
#include <string>
#include <vector>

namespace raysort {

// "a,b,,a" -> {"a", "b"}: the items of a comma-separated list, empty items dropped, the first
// occurrence of a repeated item kept.
std::vector<std::string> split_list(const std::string& text);

}  // namespace raysort
