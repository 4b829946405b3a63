#include "base/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <utility>

#include "base/errors.h"
#include "base/kill_point.h"

namespace fetchscope {
namespace {

std::atomic<unsigned long> temp_counter{0};

// The folder part of a path ("" for a bare name) and the name part.
std::pair<std::string, std::string> SplitPath(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return {"", path};
  return {path.substr(0, slash + 1), path.substr(slash + 1)};
}

// The folder as shown in messages: without its trailing '/', "." for the current one.
std::string FolderForMessage(const std::string& folder) {
  if (folder.empty()) return ".";
  if (folder == "/") return folder;
  return folder.substr(0, folder.size() - 1);
}

std::string ErrnoText(int error) {
  return error != 0 ? std::strerror(error) : "input/output error";
}

// `final_path` itself, after checking that it names a file (for the member initialiser).
const std::string& CheckedFilePath(const std::string& final_path) {
  const std::string name = SplitPath(final_path).second;
  if (name.empty() || name == "." || name == "..") {
    throw RunError("cannot write '" + final_path + "': it names a folder, not a file");
  }
  return final_path;
}

}  // namespace

ParentFolders::ParentFolders(const std::string& file_path) {
  namespace fs = std::filesystem;
  const fs::path folder = fs::path(file_path).parent_path();
  // A concurrent writer (another Slurm task on the same datasets root) may remove an empty folder
  // it made while this one is creating the folders below it: mkdir then fails with ENOENT, and
  // the missing folders are looked for again (a few times; a real ENOENT ends it).
  for (int attempt = 0;; ++attempt) {
    // the missing folders, innermost first; an error while looking (a file in the way, no
    // permission) shows up below when the folder cannot be created
    std::vector<fs::path> missing;
    for (fs::path p = folder; !p.empty(); p = p.parent_path()) {
      std::error_code ec;
      if (fs::exists(p, ec)) break;
      missing.push_back(p);
      if (p == p.parent_path()) break;  // the root
    }
    bool vanished = false;
    for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
      if (::mkdir(it->c_str(), 0777) == 0) {
        created_.push_back(it->string());
        continue;
      }
      if (errno == EEXIST && fs::is_directory(*it)) continue;  // made by a concurrent writer
      if (errno == ENOENT && attempt < 8) {  // a folder above went meanwhile: look again
        vanished = true;
        break;
      }
      const int error = errno == EEXIST ? ENOTDIR : errno;
      RemoveCreated();
      ThrowPathError("cannot create folder '" + it->string() + "': " + std::strerror(error), error);
    }
    if (!vanished) return;
  }
}

ParentFolders::~ParentFolders() { RemoveCreated(); }

ParentFolders::ParentFolders(ParentFolders&& other) noexcept
    : created_(std::exchange(other.created_, {})) {}

ParentFolders& ParentFolders::operator=(ParentFolders&& other) noexcept {
  if (this != &other) {
    RemoveCreated();
    created_ = std::exchange(other.created_, {});
  }
  return *this;
}

void ParentFolders::RemoveCreated() noexcept {
  // deepest first; rmdir leaves a folder that someone else has put a file in since
  for (auto it = created_.rbegin(); it != created_.rend(); ++it) ::rmdir(it->c_str());
  created_.clear();
}

std::string TempPathFor(const std::string& final_path) {
  const auto [folder, name] = SplitPath(final_path);
  return folder + "." + name + ".tmp-" + std::to_string(::getpid()) + "-" +
         std::to_string(temp_counter.fetch_add(1));
}

void CommitTempFile(const std::string& temp_path, const std::string& final_path) {
  KillPoint("file written, not renamed");
  if (std::rename(temp_path.c_str(), final_path.c_str()) != 0) {
    const int error = errno;
    std::remove(temp_path.c_str());
    throw RunError("cannot write '" + final_path + "': " + std::strerror(error));
  }
  KillPoint("file renamed");
}

AtomicFile::AtomicFile(const std::string& final_path)
    : final_path_(CheckedFilePath(final_path)), parents_(final_path) {
  const auto [folder, name] = SplitPath(final_path);
  // O_EXCL: never write into someone else's file (a stale temp left by a reused pid is skipped)
  for (int attempt = 0; attempt < 100; ++attempt) {
    temp_path_ = TempPathFor(final_path);
    const int fd = ::open(temp_path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0 && errno == EEXIST) continue;
    if (fd < 0) {
      const int error = errno;
      ThrowPathError(
          "cannot write to folder '" + FolderForMessage(folder) + "': " + std::strerror(error),
          error);
    }
    pending_ = true;
    file_ = ::fdopen(fd, "wb");
    if (file_ == nullptr) {
      const int error = errno;
      ::close(fd);
      Discard();
      throw RunError("cannot write '" + final_path + "': " + std::strerror(error));
    }
    return;
  }
  throw RunError("cannot write to folder '" + FolderForMessage(folder) +
                 "': too many stale temporary files named '." + name + ".tmp-*'");
}

AtomicFile::~AtomicFile() { Discard(); }

AtomicFile::AtomicFile(AtomicFile&& other) noexcept
    : final_path_(std::move(other.final_path_)),
      parents_(std::move(other.parents_)),
      temp_path_(std::move(other.temp_path_)),
      file_(std::exchange(other.file_, nullptr)),
      pending_(std::exchange(other.pending_, false)),
      write_errno_(other.write_errno_) {}

AtomicFile& AtomicFile::operator=(AtomicFile&& other) noexcept {
  if (this != &other) {
    Discard();
    final_path_ = std::move(other.final_path_);
    parents_ = std::move(other.parents_);
    temp_path_ = std::move(other.temp_path_);
    file_ = std::exchange(other.file_, nullptr);
    pending_ = std::exchange(other.pending_, false);
    write_errno_ = other.write_errno_;
  }
  return *this;
}

void AtomicFile::Write(std::string_view bytes) {
  if (file_ == nullptr || bytes.empty()) return;
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size() && write_errno_ == 0) {
    write_errno_ = errno;
  }
}

void AtomicFile::Commit() {
  if (file_ == nullptr) throw RunError("cannot write '" + final_path_ + "': already committed");
  // errno right after the failing call: a full disk shows up here, at the latest in fclose
  int error = write_errno_;
  if (std::fflush(file_) != 0 && error == 0) error = errno;
  if (std::ferror(file_) && error == 0) error = EIO;  // a C writer's fwrite failed earlier
  std::FILE* file = std::exchange(file_, nullptr);
  if (std::fclose(file) != 0 && error == 0) error = errno;
  if (error != 0) {
    Discard();
    throw RunError("writing '" + final_path_ + "' failed: " + ErrnoText(error));
  }
  pending_ = false;
  CommitTempFile(temp_path_, final_path_);
  parents_.Keep();
}

void AtomicFile::Discard() noexcept {
  if (file_ != nullptr) std::fclose(std::exchange(file_, nullptr));
  if (pending_) ::unlink(temp_path_.c_str());
  pending_ = false;
}

void WriteFileAtomically(const std::string& path, std::string_view contents) {
  AtomicFile file(path);
  file.Write(contents);
  file.Commit();
}

void CreateOutputFolder(const std::string& folder) {
  std::error_code ec, ignored;
  std::filesystem::create_directories(folder, ec);
  if (std::filesystem::is_directory(folder, ignored)) return;
  const std::string message = "cannot create output folder '" + folder + "': ";
  if (!ec) throw UsageError(message + "a file is in the way");
  ThrowPathError(message + ec.message(), ec.value());
}

}  // namespace fetchscope
