#include "util/output_name.h"

#include <fmt/format.h>

namespace raysort {

namespace {

bool is_unsafe_char(char c) {
  const auto u = static_cast<unsigned char>(c);
  return c == '/' || c == '\\' || u < 0x20 || u == 0x7f;
}

}  // namespace

std::string file_name_problem(std::string_view name) {
  if (name.empty()) return "is empty";
  for (char c : name) {
    if (c == '/' || c == '\\') return fmt::format("holds a '{}': it names output files, so it must be a name, not a path", c);
    if (is_unsafe_char(c)) return "holds a control character";
  }
  if (name.front() == '.') return "starts with '.' (it names output files, which would be hidden or outside the folder)";
  if (name.size() > kMaxFileNameBytes)
    return fmt::format("is {} bytes long; it names output files, so keep it to {} bytes", name.size(), kMaxFileNameBytes);
  return {};
}

std::string safe_file_name(std::string_view name, std::string_view fallback) {
  std::string out(name.substr(0, kMaxFileNameBytes));
  // Cut at a character boundary: drop UTF-8 continuation bytes (10xxxxxx) left of the cut, and the
  // lead byte they belong to, when the name was cut inside a character.
  if (name.size() > kMaxFileNameBytes) {
    std::size_t lead = out.size();
    while (lead > 0 && (static_cast<unsigned char>(out[lead - 1]) & 0xC0) == 0x80) --lead;
    if (lead > 0) {
      const auto b = static_cast<unsigned char>(out[lead - 1]);
      const std::size_t length = b >= 0xF0 ? 4 : b >= 0xE0 ? 3 : b >= 0xC0 ? 2 : 1;
      if (out.size() - (lead - 1) < length) out.resize(lead - 1);
    }
  }
  for (char& c : out)
    if (is_unsafe_char(c)) c = '_';
  if (!out.empty() && out.front() == '.') out.front() = '_';
  if (out.empty()) out = std::string(fallback);
  return out;
}

}  // namespace raysort
