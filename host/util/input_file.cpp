#include "util/input_file.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "util/error.h"
#include "util/host_memory.h"

namespace raysort {

namespace {

// The kind of a non-regular file, for messages.
const char* file_type_name(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

std::string type_problem(const struct stat& st) {
  return fmt::format("is {}, not a regular file", file_type_name(st.st_mode));
}

std::string size_problem(std::uint64_t bytes, const InputKind& kind, bool at_least) {
  return fmt::format("is {}{}, over the {} bound for {}s; it is corrupt or the wrong file", at_least ? "over " : "",
                     format_bytes(bytes), format_bytes(kind.max_bytes), kind.what);
}

// Closes a descriptor on every path out.
struct Fd {
  int fd;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

void check_input_file(const std::string& path, const InputKind& kind) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0)
    throw Error(fmt::format("cannot open {} {}: {}", kind.what, path, std::strerror(errno)));
  if (!S_ISREG(st.st_mode)) throw Error(fmt::format("{} {} {}; {}", kind.what, path, type_problem(st), kind.fix));
  if (static_cast<std::uint64_t>(st.st_size) > kind.max_bytes)
    throw Error(fmt::format("{} {} {}", kind.what, path, size_problem(static_cast<std::uint64_t>(st.st_size), kind, false)));
}

std::string read_input_file(const std::string& path, const InputKind& kind,
                            const std::function<void(const char*, std::size_t)>& inspect) {
  // O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer, forever. The type is
  // checked on the open descriptor (fstat), so a file swapped for a FIFO after a stat cannot slip
  // through; a regular file ignores the flag.
  Fd f{::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC)};
  if (f.fd < 0) throw Error(fmt::format("cannot open {} {}: {}", kind.what, path, std::strerror(errno)));
  struct stat st {};
  if (::fstat(f.fd, &st) != 0) throw Error(fmt::format("cannot read {} {}: {}", kind.what, path, std::strerror(errno)));
  if (!S_ISREG(st.st_mode))
    throw Error(fmt::format("{} {} {}; {}", kind.what, path, type_problem(st), kind.fix));
  if (static_cast<std::uint64_t>(st.st_size) > kind.max_bytes)
    throw Error(fmt::format("{} {} {}", kind.what, path, size_problem(static_cast<std::uint64_t>(st.st_size), kind, false)));
  std::string text;
  // Room for the whole file up front, but not for more than 64 MiB of it: a large file that a content
  // check refuses early should not have cost its size first.
  text.reserve(static_cast<std::size_t>(std::min<std::uint64_t>(static_cast<std::uint64_t>(st.st_size), 64u << 20)));
  char chunk[1 << 16];
  for (;;) {
    const ssize_t n = ::read(f.fd, chunk, sizeof chunk);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw Error(fmt::format("cannot read {} {}: {}", kind.what, path, std::strerror(errno)));
    }
    if (n == 0) break;
    if (inspect) inspect(chunk, static_cast<std::size_t>(n));
    // A file can grow while it is read (or report a size of 0, as /proc files do): the bound holds
    // for what is read, not only for what stat said.
    if (text.size() + static_cast<std::size_t>(n) > kind.max_bytes)
      throw Error(fmt::format("{} {} {}", kind.what, path, size_problem(kind.max_bytes, kind, true)));
    text.append(chunk, static_cast<std::size_t>(n));
  }
  return text;
}

}  // namespace raysort
