#pragma once
// Output file names derived from inputs (issue 44): a scene's `name` (or a batch's) becomes part of
// the files `render` and `trace --disagreements` write, so a name like "../../x" or "/etc/x" would
// write outside the folder the user chose. Every output path built from such a name goes through
// safe_file_name; scene files are checked with file_name_problem where they are parsed, so a bad
// name is refused with its line rather than silently renamed.
#include <cstddef>
#include <string>
#include <string_view>

namespace raysort {

// The longest name kept: the suffixes added to it ("-cost.png", "__bounce12__mlhcc-cost__64.json")
// must still fit the 255 bytes most file systems allow for one component.
inline constexpr std::size_t kMaxFileNameBytes = 100;

// Why `name` cannot be used as is as one file-name component, or empty when it can: it is empty,
// holds a '/' or '\' (a path, not a name) or a control character, starts with '.' (".", "..", a
// hidden file), or is longer than kMaxFileNameBytes.
std::string file_name_problem(std::string_view name);

// `name` as one safe file-name component: '/', '\' and control characters become '_', a leading
// '.' becomes '_', the name is cut to kMaxFileNameBytes (at a UTF-8 character boundary), and an
// empty name becomes `fallback`. A name file_name_problem accepts is returned unchanged.
std::string safe_file_name(std::string_view name, std::string_view fallback = "scene");

}  // namespace raysort
