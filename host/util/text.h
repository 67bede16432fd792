#pragma once
// Small text helpers for the command line's lists, and one parser for its list axes (issue 41): a
// comma-separated list of a few names, or a word for all of them (run --variant, --access,
// --baseline). Each axis is a table of its names; the parsing and the refusals are the same.
#include <algorithm>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "util/error.h"

namespace raysort {

// "a,b,,a" -> {"a", "b"}: the items of a comma-separated list, empty items dropped, the first
// occurrence of a repeated item kept.
std::vector<std::string> split_list(const std::string& text);

// The values a numeric option takes, as its refusal names them: "a whole number from 0 to 8" (whole),
// "a finite number from 0 to 1", "a finite number, 0 or more" (hi infinite), "a finite number above
// 0 and at most 100" (above_lo).
std::string number_range_text(double lo, double hi, bool whole, bool above_lo = false);

template <class T>
struct ListAxis {
  std::string_view option;                             // "--variant"
  std::string_view plural, singular;                   // "trace variants", "trace variant"
  std::vector<std::pair<std::string_view, T>> values;  // every name, in the axis's order
  std::vector<std::string_view> every{"all"};          // the words for every value; the first is the one named
};

// The values `list` names, each once, in the order given ("a,b,a" is a, b). Throws Error for a name
// the axis lacks ("--access 'x': the access modes are gather and permute (or all)") and for an
// empty list ("--access: name at least one access mode (gather, permute)").
template <class T>
std::vector<T> parse_list_axis(const ListAxis<T>& axis, const std::string& list) {
  std::vector<T> out;
  if (std::find(axis.every.begin(), axis.every.end(), list) != axis.every.end()) {
    for (const auto& [name, value] : axis.values) out.push_back(value);
    return out;
  }
  std::string names, listed;
  for (std::size_t i = 0; i < axis.values.size(); ++i) {
    names += std::string(i == 0 ? "" : i + 1 == axis.values.size() ? " and " : ", ") + std::string(axis.values[i].first);
    listed += std::string(i == 0 ? "" : ", ") + std::string(axis.values[i].first);
  }
  for (const std::string& item : split_list(list)) {
    const auto it = std::find_if(axis.values.begin(), axis.values.end(), [&](const auto& v) { return v.first == item; });
    if (it == axis.values.end())
      throw Error(std::string(axis.option) + " '" + item + "': the " + std::string(axis.plural) + " are " + names +
                  " (or " + std::string(axis.every.front()) + ")");
    if (std::find(out.begin(), out.end(), it->second) == out.end()) out.push_back(it->second);
  }
  if (out.empty())
    throw Error(std::string(axis.option) + ": name at least one " + std::string(axis.singular) + " (" + listed + ")");
  return out;
}

}  // namespace raysort
