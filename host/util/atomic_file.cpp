#include "util/atomic_file.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "util/error.h"

namespace raysort {

namespace {

std::string temporary_file_name(const std::string& path, int pid, unsigned attempt) {
  return attempt == 0 ? fmt::format("{}.tmp.{}", path, pid) : fmt::format("{}.tmp.{}.{}", path, pid, attempt);
}

}  // namespace

bool is_temporary_file_of(const std::string& file_name, const std::string& target_name) {
  // TARGET.tmp.PID or TARGET.tmp.PID.N, digits only: nothing else is a leftover of this writer.
  const std::string prefix = target_name + ".tmp.";
  if (file_name.size() <= prefix.size() || file_name.compare(0, prefix.size(), prefix) != 0) return false;
  const std::string rest = file_name.substr(prefix.size());
  const std::size_t dot = rest.find('.');
  auto digits = [](const std::string& t) {
    return !t.empty() && t.size() <= 10 && t.find_first_not_of("0123456789") == std::string::npos;
  };
  return dot == std::string::npos ? digits(rest) : digits(rest.substr(0, dot)) && digits(rest.substr(dot + 1));
}

void write_file_atomically(const std::string& path, const std::string& contents) {
  // Exclusive create, never through a link: a file or link planted at the temporary name is left
  // alone (the next name is tried), so this never writes anything but its own new file.
  std::string tmp;
  int fd = -1;
  for (unsigned attempt = 0; fd < 0 && attempt < 64; ++attempt) {
    tmp = temporary_file_name(path, ::getpid(), attempt);
    fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd < 0 && errno != EEXIST) break;
  }
  if (fd < 0) throw Error(fmt::format("cannot write '{}': {}", tmp, std::strerror(errno)));
  const char* p = contents.data();
  std::size_t left = contents.size();
  while (left > 0) {
    ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      int e = errno;
      ::close(fd);
      ::unlink(tmp.c_str());
      throw Error(fmt::format("cannot write '{}': {}", tmp, std::strerror(e)));
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  ::fsync(fd);
  ::close(fd);
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    int e = errno;
    ::unlink(tmp.c_str());
    throw Error(fmt::format("cannot move '{}' into place: {}", path, std::strerror(e)));
  }
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(fmt::format("cannot read '{}': {}", path, std::strerror(errno)));
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace raysort
