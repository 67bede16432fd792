#pragma once
// Files are never half-written: write to a temporary file beside the target, flush it to disk,
// then rename over the target (atomic on POSIX file systems).
#include <string>

namespace raysort {

void write_file_atomically(const std::string& path, const std::string& contents);
std::string read_file(const std::string& path);  // throws Error naming the path

}  // namespace raysort
