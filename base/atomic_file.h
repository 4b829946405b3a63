// Output files that appear whole or not at all: written under a temporary name beside the final
// one, then renamed into place, so an interrupted or failed run never leaves a half-written file.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

namespace fetchscope {

/// Creates the missing folders above a file about to be written (mkdir -p of its folder part), so
/// every output path (`--json-out`, `-o`, `--out`) may name folders that do not exist yet. Unless
/// Keep() is called, destruction removes again the folders it created, deepest first and only
/// while empty, so a write that fails leaves no new empty folders behind. Movable, not copyable.
class ParentFolders {
 public:
  /// Throws RunError naming the folder if one cannot be created, e.g. "cannot create folder
  /// 'out/a': Not a directory" (a file is in the way) or "...: Permission denied".
  explicit ParentFolders(const std::string& file_path);
  ~ParentFolders();
  ParentFolders(const ParentFolders&) = delete;
  ParentFolders& operator=(const ParentFolders&) = delete;
  ParentFolders(ParentFolders&& other) noexcept;
  ParentFolders& operator=(ParentFolders&& other) noexcept;

  /// The file was written: keep the folders.
  void Keep() { created_.clear(); }

  /// The folders this object created, outermost first.
  const std::vector<std::string>& created() const { return created_; }

 private:
  void RemoveCreated() noexcept;

  std::vector<std::string> created_;
};

/// The temporary name a writer should use for `final_path`: "<dir>/.<name>.tmp-<pid>-<n>", with
/// n a process-wide counter, so concurrent writers (threads, processes, Slurm tasks sharing a
/// folder) never collide. For writers that open files themselves (e.g. FFmpeg's avio), which then
/// rename it with CommitTempFile().
std::string TempPathFor(const std::string& final_path);

/// Renames a finished temporary file onto `final_path` (atomic on POSIX file systems). On failure
/// the temporary is removed and RunError names the final path.
void CommitTempFile(const std::string& temp_path, const std::string& final_path);

/// A file being written atomically. The constructor creates missing parent folders (see
/// ParentFolders; removed again if the file is never committed) and the temporary file; Commit()
/// checks every write succeeded and renames it to the final path; destruction without Commit() (an
/// error, an interrupt) removes the temporary. Not thread-safe; movable, not copyable.
class AtomicFile {
 public:
  /// Creates TempPathFor(final_path). Throws RunError naming the folder if it cannot, e.g.
  /// "cannot write to folder 'out': Permission denied".
  explicit AtomicFile(const std::string& final_path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  AtomicFile(AtomicFile&& other) noexcept;
  AtomicFile& operator=(AtomicFile&& other) noexcept;

  /// The open temporary file, for C writers (libpng's png_init_io). Null after Commit().
  std::FILE* file() const { return file_; }

  /// Appends bytes. Errors are not thrown here: they stick to the FILE and Commit() reports them.
  void Write(std::string_view bytes);

  /// Flushes, checks for write errors (a full disk: "writing 'out/a.json' failed: No space left on
  /// device") and renames the temporary to the final path. Throws RunError and removes the
  /// temporary on failure. The data is not fsync'ed: this guards against partial files from
  /// failed or interrupted runs, not against power loss.
  void Commit();

  /// The path the file will have after Commit().
  const std::string& final_path() const { return final_path_; }

  /// The temporary path being written.
  const std::string& temp_path() const { return temp_path_; }

 private:
  void Discard() noexcept;

  std::string final_path_;
  ParentFolders parents_;  // created before the temporary, removed after it if not committed
  std::string temp_path_;
  std::FILE* file_ = nullptr;  // open until Commit() or destruction
  bool pending_ = false;       // the temporary exists and is ours to remove
  int write_errno_ = 0;        // first failure seen by Write()
};

/// Writes `contents` to `path` through an AtomicFile. Throws RunError on failure.
void WriteFileAtomically(const std::string& path, std::string_view contents);

/// Creates the output folder `folder` (a command's --out) and its parents. A path that cannot
/// be one (a file in the way, below a file, not writable) is a UsageError, a full disk a
/// RunError (ThrowPathError), each "cannot create output folder 'FOLDER': REASON".
void CreateOutputFolder(const std::string& folder);

}  // namespace fetchscope
