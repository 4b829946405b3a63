#include "base/folder_lock.h"

#include <fcntl.h>
#include <pthread.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>

#include "base/errors.h"

namespace fetchscope {

std::optional<pid_t> FlockHolder(const std::filesystem::path& path) {
  struct stat st {};
  if (stat(path.c_str(), &st) != 0) return std::nullopt;
  // lines: "1: FLOCK  ADVISORY  WRITE 1234 fd:01:5678 0 EOF" (MAJ:MIN in hex, inode in decimal);
  // a waiting lock's line has "->" before its type, and is not the holder
  std::ifstream locks("/proc/locks");
  std::string line;
  while (std::getline(locks, line)) {
    std::istringstream in(line);
    std::string number, type, mode, access, device;
    long pid = 0;
    in >> number >> type;
    if (type == "->") continue;
    in >> mode >> access >> pid >> device;
    if (type != "FLOCK" || !in) continue;
    unsigned dev_major = 0, dev_minor = 0;
    unsigned long long inode = 0;
    if (std::sscanf(device.c_str(), "%x:%x:%llu", &dev_major, &dev_minor, &inode) != 3) continue;
    if (inode == st.st_ino && dev_major == major(st.st_dev) && dev_minor == minor(st.st_dev) &&
        pid > 0) {
      return static_cast<pid_t>(pid);
    }
  }
  return std::nullopt;
}

namespace {

// The descriptors of the locks this process holds. A forked child (a worker process) closes its
// copies at once: a flock belongs to the open file description, so a child that kept one would
// keep the folder locked after its parent died (SIGKILL), and the --resume run that follows
// would be refused. Closing the child's copy leaves the parent's lock as it is.
constexpr int kMaxHeld = 16;
std::atomic<int> held_fds[kMaxHeld];

void CloseHeldInChild() {
  for (std::atomic<int>& slot : held_fds) {
    const int fd = slot.exchange(-1);
    if (fd >= 0) close(fd);
  }
}

void Remember(int fd) {
  static const bool registered = [] {
    for (std::atomic<int>& slot : held_fds) slot.store(-1);
    pthread_atfork(nullptr, nullptr, CloseHeldInChild);
    return true;
  }();
  (void)registered;
  for (std::atomic<int>& slot : held_fds) {
    int expected = -1;
    if (slot.compare_exchange_strong(expected, fd)) return;
  }
}

void Forget(int fd) {
  for (std::atomic<int>& slot : held_fds) {
    int expected = fd;
    if (slot.compare_exchange_strong(expected, -1)) return;
  }
}

// flock without waiting; true when taken, false when another process holds it
bool TryFlock(int fd, int op, const std::filesystem::path& path) {
  int rc;
  do {
    rc = flock(fd, op | LOCK_NB);
  } while (rc != 0 && errno == EINTR);
  if (rc == 0) return true;
  const int error = errno;
  if (error != EWOULDBLOCK) {
    close(fd);
    throw RunError("cannot lock '" + path.string() + "': " + std::strerror(error));
  }
  return false;
}

[[noreturn]] void ThrowHeld(const std::filesystem::path& locked, const std::string& what,
                            const std::string& shown, const std::string& other) {
  const std::optional<pid_t> holder = FlockHolder(locked);
  throw UsageError(what + " '" + shown + "' is being written by another fetchscope (" +
                   (holder ? "PID " + std::to_string(*holder) : std::string("its PID unknown")) +
                   "): wait for it to finish, or choose another " + other);
}

}  // namespace

FolderLock::FolderLock(const std::filesystem::path& folder, Kind kind, const std::string& what) {
  fd_ = open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd_ < 0) {
    throw RunError("cannot open folder '" + folder.string() +
                   "' to lock it: " + std::strerror(errno));
  }
  if (TryFlock(fd_, kind == Kind::kShared ? LOCK_SH : LOCK_EX, folder)) {
    Remember(fd_);
    return;
  }
  close(fd_);
  fd_ = -1;
  ThrowHeld(folder, what, folder.string(), "folder");
}

FolderLock FolderLock::OnLockFile(const std::filesystem::path& file, const std::string& what,
                                  const std::string& shown) {
  // the holder removes the file while it still holds the lock: a process that locked the
  // removed file finds another file (or none) at the name, and tries again
  for (int attempt = 0; attempt < 100; ++attempt) {
    const int fd = open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0 && errno == ENOENT && attempt < 8) {
      // its folder went meanwhile (another writer removed the empty folder it had made): again
      std::error_code ec;
      std::filesystem::create_directories(file.parent_path(), ec);
      continue;
    }
    if (fd < 0) {
      throw RunError("cannot make lock file '" + file.string() + "': " + std::strerror(errno));
    }
    if (!TryFlock(fd, LOCK_EX, file)) {
      close(fd);
      ThrowHeld(file, what, shown, "id");
    }
    struct stat by_fd {
    }, by_name{};
    if (fstat(fd, &by_fd) == 0 && stat(file.c_str(), &by_name) == 0 &&
        by_fd.st_ino == by_name.st_ino && by_fd.st_dev == by_name.st_dev) {
      FolderLock lock;
      lock.fd_ = fd;
      lock.remove_ = file;
      Remember(fd);
      return lock;
    }
    close(fd);
  }
  throw RunError("cannot lock '" + file.string() + "': it keeps being replaced");
}

FolderLock::~FolderLock() {
  if (fd_ < 0) return;
  if (!remove_.empty()) unlink(remove_.c_str());  // while still held: see OnLockFile
  Forget(fd_);
  close(fd_);  // closing the last descriptor drops the lock
}

FolderLock::FolderLock(FolderLock&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), remove_(std::move(other.remove_)) {
  other.remove_.clear();
}

FolderLock& FolderLock::operator=(FolderLock&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) {
      if (!remove_.empty()) unlink(remove_.c_str());
      Forget(fd_);
      close(fd_);
    }
    fd_ = std::exchange(other.fd_, -1);
    remove_ = std::move(other.remove_);
    other.remove_.clear();
  }
  return *this;
}

}  // namespace fetchscope
