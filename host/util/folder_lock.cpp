#include "util/folder_lock.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "util/atomic_file.h"
#include "util/error.h"

namespace raysort {

std::shared_ptr<FolderLock> FolderLock::acquire(const std::string& dir, const std::string& command,
                                                const std::string& what) {
  const std::string path = (std::filesystem::path(dir) / kFileName).string();
  // Never through a link (a planted .raysort-lock link would have its target truncated) and only
  // a regular file (a FIFO or device is not a lock).
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC, 0644);
  if (fd < 0 && errno == ELOOP)
    throw Error(fmt::format("{} is a symbolic link, not raysort's lock file; remove the link (raysort never writes "
                            "through one)",
                            path));
  if (fd < 0) throw Error(fmt::format("cannot open the lock file '{}': {}", path, std::strerror(errno)));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw Error(fmt::format("{} is not a regular file, so it is not raysort's lock file; remove it", path));
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int e = errno;
    std::string holder;
    try {
      holder = read_file(path);
    } catch (const Error&) {
    }
    while (!holder.empty() && (holder.back() == '\n' || holder.back() == '\r')) holder.pop_back();
    ::close(fd);
    if (e == EWOULDBLOCK)
      throw Error(fmt::format("{} is being written by another raysort ({}); one {} has one writer: wait for it to "
                              "end, or write to another folder",
                              dir, holder.empty() ? "holder unknown" : holder, what));
    throw Error(fmt::format("cannot lock '{}': {}", path, std::strerror(e)));
  }
  // Who holds it, for a refused second writer (written in place: the lock file is never renamed,
  // or a second writer could lock another inode).
  const std::string text = fmt::format("pid {}: {}\n", ::getpid(), command);
  if (::ftruncate(fd, 0) == 0) {
    ssize_t ignored = ::pwrite(fd, text.data(), text.size(), 0);
    (void)ignored;
  }
  return std::shared_ptr<FolderLock>(new FolderLock(fd));
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the flock
}

}  // namespace raysort
