#pragma once
// One writer per folder: an exclusive flock(2) on DIR/.raysort-lock, held while the object lives.
// The kernel releases it when the process ends however it ends (SIGKILL included), so a lock is
// never stale and nothing needs cleaning up; the file itself stays, holding the last holder's PID
// and command line, which a refused second writer names.
#include <memory>
#include <string>

namespace raysort {

class FolderLock {
 public:
  // Takes the lock at once or throws Error naming the holder ("pid 123: raysort run ...") and the
  // fix. `what` names the folder's role in the message ("result set").
  static std::shared_ptr<FolderLock> acquire(const std::string& dir, const std::string& command,
                                             const std::string& what);
  ~FolderLock();
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

  static constexpr const char* kFileName = ".raysort-lock";

 private:
  explicit FolderLock(int fd) : fd_(fd) {}
  int fd_ = -1;
};

}  // namespace raysort
