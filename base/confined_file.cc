#include "base/confined_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "base/errors.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;

// "a FIFO" for a file mode that is not a regular file's
std::string KindOf(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a plain file";
}

std::string KindOf(fs::file_type type) {
  switch (type) {
    case fs::file_type::directory:
      return "a folder";
    case fs::file_type::fifo:
      return "a FIFO";
    case fs::file_type::character:
      return "a character device";
    case fs::file_type::block:
      return "a block device";
    case fs::file_type::socket:
      return "a socket";
    default:
      return "not a plain file";
  }
}

// "256 MiB" for a whole number of MiB, else the bytes
std::string Bytes(uint64_t n) {
  if (n >= (uint64_t{1} << 20) && n % (uint64_t{1} << 20) == 0) {
    return std::to_string(n >> 20) + " MiB";
  }
  return std::to_string(n) + " bytes";
}

[[noreturn]] void RefuseKind(const fs::path& path, const std::string& kind) {
  throw UsageError(Quoted(path.string()) + " is " + kind +
                   ", not a regular file: fetchscope reads its inputs only from regular files");
}

[[noreturn]] void RefuseSize(const fs::path& path, const std::string& size, uint64_t max_bytes) {
  throw UsageError(Quoted(path.string()) + " " + size + ", more than the " + Bytes(max_bytes) +
                   " fetchscope reads from such a file: it is no file fetchscope wrote");
}

class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

// True when `inner` (resolved) lies below `outer` (resolved), component by component.
bool Below(const fs::path& outer, const fs::path& inner) {
  auto o = outer.begin(), i = inner.begin();
  for (; o != outer.end(); ++o, ++i) {
    if (o->empty() && std::next(o) == outer.end()) break;  // a trailing separator
    if (i == inner.end() || *o != *i) return false;
  }
  return i != inner.end();
}

}  // namespace

std::string ReadFileCapped(const fs::path& path, uint64_t max_bytes) {
  // what the path is, before opening it (opening a device may have effects of its own)
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!ec && fs::exists(status) && !fs::is_regular_file(status)) {
    RefuseKind(path, KindOf(status.type()));
  }
  // O_NONBLOCK: a FIFO swapped in since is opened without waiting for a writer, then refused
  const Fd fd(open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY));
  if (fd.get() < 0) {
    throw RunError("cannot read " + Quoted(path.string()) + ": " + std::strerror(errno));
  }
  struct stat st {};
  if (fstat(fd.get(), &st) != 0) {
    throw RunError("cannot read " + Quoted(path.string()) + ": " + std::strerror(errno));
  }
  if (!S_ISREG(st.st_mode)) RefuseKind(path, KindOf(st.st_mode));
  const uint64_t size = static_cast<uint64_t>(st.st_size);
  if (size > max_bytes) RefuseSize(path, "holds " + std::to_string(size) + " bytes", max_bytes);
  // read up to one byte past the cap, whatever the size said: a file that grows stops there
  std::string text;
  text.reserve(static_cast<size_t>(size));
  std::string piece(size_t{1} << 16, '\0');
  for (;;) {
    const ssize_t n = read(fd.get(), &piece[0], piece.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      throw RunError("cannot read " + Quoted(path.string()) + ": " + std::strerror(errno));
    }
    if (n == 0) break;
    if (text.size() + static_cast<size_t>(n) > max_bytes) {
      RefuseSize(path, "grew past that size while it was read", max_bytes);
    }
    text.append(piece.data(), static_cast<size_t>(n));
  }
  return text;
}

bool LiesInside(const fs::path& folder, const fs::path& path) {
  std::error_code ec;
  const fs::path root = fs::weakly_canonical(fs::absolute(folder, ec), ec);
  if (ec) return false;
  const fs::path resolved = fs::weakly_canonical(fs::absolute(path, ec), ec);
  return !ec && Below(root, resolved);
}

fs::path ResolveInside(const fs::path& folder, const std::string& entry,
                       const std::string& named_by) {
  const fs::path path = folder / entry;  // an absolute entry stands alone
  std::error_code ec_folder, ec_path;
  const fs::path root = fs::weakly_canonical(fs::absolute(folder, ec_folder), ec_folder);
  const fs::path resolved = fs::weakly_canonical(fs::absolute(path, ec_path), ec_path);
  if (ec_folder || ec_path) {
    throw UsageError(named_by + " " + Quoted(entry) + ", which cannot be resolved (" +
                     (ec_path ? ec_path : ec_folder).message() + "): a run's files must lie " +
                     "inside its folder " + Quoted(folder.string()));
  }
  if (!Below(root, resolved)) {
    throw UsageError(named_by + " " + Quoted(entry) + ", which lies outside the run folder " +
                     Quoted(folder.string()) +
                     " (symbolic links and '..' followed): a run's files must lie inside it");
  }
  return path;
}

void RequireRegularIfPresent(const fs::path& path, const std::string& entry,
                             const std::string& named_by) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec || !fs::exists(status) || fs::is_regular_file(status)) return;
  throw UsageError(named_by + " " + Quoted(entry) + ", which is " + KindOf(status.type()) +
                   ", not a regular file: a run's files are regular files");
}

std::string DescribeJsonError(const nlohmann::json::parse_error& e, size_t text_size) {
  if (e.byte >= text_size) {
    return "its JSON ends at byte " + std::to_string(text_size) + " before it is complete";
  }
  return "it is not valid JSON at byte " + std::to_string(e.byte) + " of " +
         std::to_string(text_size);
}

}  // namespace fetchscope
