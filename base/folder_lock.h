// An advisory lock on an output folder, so that two fetchscope processes never write one folder
// at once: flock(2) on the folder itself (no lock file is left in it), dropped by the kernel when
// the holder exits, however it exits, so even SIGKILL leaves no stale lock. A refusal names the
// holder's PID, read from /proc/locks.
#pragma once

#include <sys/types.h>

#include <filesystem>
#include <optional>
#include <string>

namespace fetchscope {

class FolderLock {
 public:
  enum class Kind {
    kExclusive,  ///< one writer: a record run, a dataset, a merged manifest
    kShared,     ///< the shards of one sharded run write one folder together
  };
  FolderLock() = default;
  /// Locks the existing folder `folder` without waiting. Throws UsageError when another process
  /// holds it ("`what` '<folder>' is being written by another fetchscope (PID N): ..."), and
  /// RunError when the folder cannot be opened.
  FolderLock(const std::filesystem::path& folder, Kind kind, const std::string& what);
  ~FolderLock();
  FolderLock(FolderLock&& other) noexcept;
  FolderLock& operator=(FolderLock&& other) noexcept;
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;

  /// A lock on a hidden lock file instead of a folder, for what has no folder of its own while it
  /// is written (a Minari dataset is written under a temporary name, then renamed): `file` is
  /// made, locked exclusively and removed again when the lock is released. Throws as above.
  static FolderLock OnLockFile(const std::filesystem::path& file, const std::string& what,
                               const std::string& shown);

  bool held() const { return fd_ >= 0; }

 private:
  int fd_ = -1;
  std::filesystem::path remove_;  // the lock file, removed on release
};

/// The PID of a process holding a flock on `path` (from /proc/locks, by device and inode), or
/// nullopt when none is listed or /proc/locks cannot be read.
std::optional<pid_t> FlockHolder(const std::filesystem::path& path);

}  // namespace fetchscope
