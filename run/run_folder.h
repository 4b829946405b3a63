// The output folder of one `record` run: never mixing two runs in it (refused, or replaced
// whole with --overwrite, or continued with --resume), and leaving nothing behind when the run
// fails.
//
// A run's files are the ones record and its report write (run/run_files.h names them all) and their
// hidden temporaries. Anything else in the folder is the user's and is never touched. A file under
// one of those names counts as fetchscope's only when it carries fetchscope's mark: a record
// manifest, a file a manifest there lists, a report with fetchscope's generator tag, or an episode
// file of an attempt killed before its manifest: beside a fetchscope trajectory of that episode,
// or a video whose tags say fetchscope recorded that episode, or beside such a video (a sheet, a
// layer, a trajectory cut short). Any other is the user's, and the folder is refused naming it,
// whatever the mode. A killed attempt's files are recorded again: by --resume (unsharded, only
// when they are of the same env, seed and policy) and --overwrite, and by a shard's plain rerun.
//
// Two processes never write one folder at once: the run holds an advisory lock on --out
// (base/folder_lock.h; shared among the shards of a sharded run) from before it looks at the
// folder to its end, and a second run is refused at once, naming the first one's PID.
//
// The folder is also refused when it is, holds or lies inside a source the run reads (record
// --from, a replay file), paths and symlinks resolved, and when nothing can be written in it; both
// before anything is rendered.
//
// --overwrite moves the earlier run's files aside into a hidden folder inside --out
// (.manifest.replaced-PID, or .manifest_shard_IIII_of_NNNN.replaced-PID for a shard) and deletes
// them only when the new run has its manifest (Commit); a run that fails puts them back. A
// record killed outright (SIGKILL) leaves that folder behind: the next run refuses the folder
// naming it, and the next --overwrite deletes it with the rest once it succeeds. The shards of one
// sharded run share a folder by design: a shard looks only at its own manifest and episodes, and at
// the other manifests to see that they are of the same run.
#pragma once

#include <filesystem>
#include <functional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "base/folder_lock.h"
#include "run/manifest.h"

namespace fetchscope {

/// What to do with a folder that already holds a run.
enum class ReuseMode {
  kRefuse,     ///< the default: refuse (UsageError, exit 2)
  kOverwrite,  ///< --overwrite: remove the earlier run's files, then record afresh
  kResume,     ///< --resume: keep its complete episodes, record the rest
};

/// What a run asks of its folder.
struct RunFolderRequest {
  std::string out;  ///< --out
  ReuseMode mode = ReuseMode::kRefuse;
  std::string manifest_name;      ///< this run's manifest (manifest.json or a shard's)
  bool sharded = false;           ///< other shards' files may be there
  std::function<bool(int)> owns;  ///< true for the episodes of this run (its shard)
  std::vector<int> episodes;      ///< this run's episodes, ascending
  /// What makes two manifests the same run (SameRun), stored in the manifest; --resume refuses a
  /// folder whose run differs in any of them.
  RunParameters parameters;
  /// What the run reads (record --from's folder or file, a replay: file): --out may neither be,
  /// hold nor lie inside one of them.
  std::vector<std::pair<std::string, std::string>> sources;  ///< {option, path}: {"--from", "run"}
  /// The run writes its report (index.html): a user's index.html is in the way.
  bool report = true;
};

/// The folder, prepared: conflicts checked, earlier files removed as asked, the folder made.
/// Until Commit(), destroying it removes what this run created: its files, and the folders
/// it made when they are empty again (so a failed run leaves nothing that was not there).
class RunFolder {
 public:
  /// Checks and prepares the folder. Throws UsageError (exit 2) for a folder holding another
  /// run (naming it and the way out), for --resume with a differing parameter (naming it), and
  /// RunError when the folder cannot be made.
  explicit RunFolder(const RunFolderRequest& request);
  ~RunFolder();
  RunFolder(const RunFolder&) = delete;
  RunFolder& operator=(const RunFolder&) = delete;

  /// The episodes still to record (all of them, unless resuming).
  const std::vector<int>& todo() const { return todo_; }
  /// --resume: the earlier manifest's entries of the complete episodes kept, by index.
  const std::vector<ManifestEpisode>& kept() const { return kept_; }
  /// This run's manifest entries and (--resume) the kept ones, in episode order: the whole run.
  std::vector<ManifestEpisode> WithKept(std::vector<ManifestEpisode> entries) const;
  /// The run ended as it should (done or interrupted, with its manifest): keep everything, and
  /// delete the earlier run that --overwrite set aside.
  void Commit();
  /// --overwrite set an earlier run's files aside (they come back unless Commit is called).
  bool replacing() const { return !set_aside_.empty(); }
  /// A line for the user about the folder, or "": --resume found nothing to resume.
  const std::string& notice() const { return notice_; }
  /// --resume of a run that is already whole (nothing to record, not interrupted): the caller
  /// summarises kept() and leaves the folder as it is.
  bool already_complete() const { return already_complete_; }

 private:
  // The files of --out that matter to this run, by name, each list sorted where it is read
  struct Listing {
    std::vector<std::string> run_files;  // this run's (or, unsharded, any run's) visible files
    std::vector<std::string> hidden;     // leftover temporaries of those
    std::vector<std::string> manifests;  // other manifests
  };
  bool Ours(const std::string& name) const;
  FolderLock::Kind LockKind() const;
  // Lists an existing --out, refusing a file in the way, a folder that cannot be listed or
  // written, and files under a run's names that fetchscope did not write.
  Listing ListFolder(const std::filesystem::path& out, const std::string& quoted) const;
  // Picks aside_ and notes (and, without --overwrite, refuses) a killed --overwrite's folder.
  void FindAside(const std::filesystem::path& out, const std::string& quoted);
  // Refuses the manifests of other runs (--overwrite: adds them to `run_files`).
  void CheckOtherManifests(const std::filesystem::path& out, const std::string& quoted,
                           const std::vector<std::string>& manifests,
                           std::vector<std::string>* run_files) const;
  // What --refuse, --overwrite or --resume does with the listing: the names to remove. False
  // when --resume found the run already whole (nothing to record, nothing to change).
  bool PlanRemovals(const std::filesystem::path& out, const std::string& quoted,
                    const Listing& listing, std::vector<std::string>* remove);
  bool PlanResume(const std::filesystem::path& out, const std::string& quoted,
                  const Listing& listing, std::vector<std::string>* remove);
  // Refuses --resume of a run with more episodes or other parameters.
  void CheckResumable(const std::string& quoted, RunParameters theirs) const;
  // Removes (or, --overwrite, sets aside) `remove`, makes --out and notes what is in it.
  void PrepareFolder(const std::filesystem::path& out, const std::string& quoted,
                     const std::vector<std::string>& remove);
  // Refuses files under a run's names that fetchscope did not write; drops from `run_files` a
  // user's index.html that a run without a report leaves alone.
  void RefuseForeignFiles(const std::filesystem::path& out, const std::string& quoted,
                          std::vector<std::string>* run_files,
                          const std::vector<std::string>& manifests) const;
  // --resume without this run's manifest: refuses episode files (of an attempt killed before
  // its manifest) that are of another env, seed or policy
  void CheckSameRunWithoutManifest(const std::filesystem::path& out, const std::string& quoted,
                                   const std::vector<std::string>& run_files) const;
  void Cleanup() noexcept;
  void Restore() noexcept;  // puts the files set aside back
  // --overwrite: moves `names` from `out` into aside_
  void SetAside(const std::filesystem::path& out, const std::vector<std::string>& names);

  RunFolderRequest request_;
  FolderLock lock_;  // held from the first look at the folder to the end of the run
  std::vector<std::filesystem::path> created_dirs_;  // deepest first
  std::set<std::string> before_;                     // names present before the run
  std::vector<int> todo_;
  std::vector<ManifestEpisode> kept_;
  std::filesystem::path aside_;  // --overwrite: where the earlier run's files wait
  std::vector<std::filesystem::path> stale_aside_;  // left by a killed --overwrite
  std::vector<std::string> set_aside_;              // their names (in --out and in aside_)
  std::string notice_;
  bool already_complete_ = false;
  bool committed_ = false;
};

/// Parses --overwrite/--resume into a mode; both at once is a UsageError.
ReuseMode ParseReuseMode(bool overwrite, bool resume);

}  // namespace fetchscope
