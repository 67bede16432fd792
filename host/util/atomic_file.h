#pragma once
// Files are never half-written: write to a temporary file beside the target, flush it to disk,
// then rename over the target (atomic on POSIX file systems).
#include <string>

namespace raysort {

// The temporary file is created exclusively (O_EXCL, O_NOFOLLOW) as PATH.tmp.PID (or
// PATH.tmp.PID.N when that name is taken), so a planted file or link is never written through.
void write_file_atomically(const std::string& path, const std::string& contents);
// Whether `file_name` is a temporary name write_file_atomically makes for a target named
// `target_name` (both bare file names): the only files a writer may delete as its leftovers.
bool is_temporary_file_of(const std::string& file_name, const std::string& target_name);
std::string read_file(const std::string& path);  // throws Error naming the path

}  // namespace raysort
