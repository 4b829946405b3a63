// Writes one Minari dataset (<root>/<id>/data/{main_data.hdf5, metadata.json}) with libhdf5, in
// the layout Minari 0.5's HDF5 storage writes (see docs/guide/datasets.md), so that
// minari.load_dataset(id) reads it with no other step.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "base/atomic_file.h"
#include "base/errors.h"
#include "base/folder_lock.h"
#include "dataset/hdf5_handles.h"
#include "dataset/minari_format.h"
#include "dataset/pixel_obs.h"
#include "src/env_spec.h"

namespace fetchscope {

/// What a dataset is and where it goes.
struct MinariWriteOptions {
  std::string dataset_id;             ///< e.g. "fetchscope/FetchPush/scripted-v0"
  std::filesystem::path root;         ///< the datasets root (MinariRoot())
  bool overwrite = false;             ///< replace an existing dataset of that id
  const EnvSpec* spec = nullptr;      ///< the env the episodes come from (required)
  std::string algorithm_name;         ///< metadata `algorithm_name`: the policy
  std::string author = "fetchscope";  ///< metadata `author` (a one-element list)
  std::string author_email;           ///< metadata `author_email` (a one-element list; omitted
                                      ///< when empty)
  /// env_spec `max_episode_steps`: the TimeLimit the episodes were run with (0: the spec's 50)
  int max_episode_steps = 0;
  std::string code_permalink;  ///< metadata `code_permalink`
  std::string description;     ///< metadata `description` (omitted when empty)
  /// camera images per step (docs/guide/datasets.md, "Pixel datasets"); null: state only
  const PixelLayout* pixels = nullptr;
};

/// Checks the id, refuses an existing dataset unless `overwrite` (UsageError naming the
/// folder), and checks that the dataset's folder can be written (RunError naming the folder),
/// leaving nothing behind: a command calls it before a long run, MinariWriter again.
void CheckMinariDestination(const MinariWriteOptions& options);

/// A write stopped by SIGINT/SIGTERM (StopSignal(), where a command installed the handlers):
/// nothing of the new dataset is left, an old one of the same id is untouched.
struct MinariInterrupted : RunError {
  MinariInterrupted(int sig, const std::string& what) : RunError(what), signal(sig) {}
  int signal;  ///< SIGINT or SIGTERM
};

/// Removes the temporary folders of dataset writes that were killed (`.<name>.tmp-<pid>-<n>`
/// beside `final_path`, whose process no longer runs on this machine and which nothing has
/// written to for a minute). Returns the folders removed. MinariWriter calls it.
std::vector<std::filesystem::path> RemoveStaleMinariTemps(const std::filesystem::path& final_path);

/// One dataset being written. It is written under a hidden temporary folder beside the final
/// one (`.<name>.tmp-<pid>-<n>`, which Minari's listing skips) and renamed into place by
/// Commit(), so it appears complete or not at all; destruction without Commit() removes it.
/// The HDF5 file stores no timestamps, so the same episodes give the same bytes.
class MinariWriter {
 public:
  /// Checks the id, refuses an existing dataset unless `overwrite` (UsageError naming the
  /// folder), and creates the temporary folder and HDF5 file (RunError if it cannot).
  explicit MinariWriter(const MinariWriteOptions& options);
  ~MinariWriter();
  MinariWriter(const MinariWriter&) = delete;
  MinariWriter& operator=(const MinariWriter&) = delete;

  /// Appends episode_<n> (n = episodes added so far; `episode.id` is ignored and written as
  /// n). With options.pixels, `staged` holds its images (T+1 per camera and layer), stored
  /// under observations/images|depth|segmentation/NAME and, for a moving camera, its poses
  /// under infos/camera_pose/NAME. Throws RunError if the arrays disagree with
  /// T = rewards.size(), images are missing, or libhdf5 fails.
  void Add(const MinariEpisode& episode, const StagedEpisode* staged = nullptr);

  /// Appends episode_<n> as a copy of group `episode` of the open HDF5 file `source` (another
  /// dataset of the same layout: a shard), its `id` rewritten to n; `steps` its total_steps.
  /// Throws RunError naming `label` (the source) where libhdf5 cannot.
  void AddCopy(hid_t source, const std::string& episode, int64_t steps, const std::string& label);

  /// Stores `selection` (which of the run's episodes these are) as metadata.json's "selection".
  void SetSelection(const nlohmann::json& selection) { selection_ = selection; }

  /// Closes the file, writes metadata.json and renames the dataset into place (replacing the
  /// old one when `overwrite`; the old one is removed after the swap). Also writes Minari's
  /// `namespace_metadata.json` ({}) into namespace folders that have none. Returns the final
  /// dataset folder.
  std::filesystem::path Commit();

  /// <root>/<id>: the folder the dataset will have.
  const std::filesystem::path& final_path() const { return final_path_; }

  int64_t total_episodes() const { return episodes_; }  ///< episodes added
  int64_t total_steps() const { return steps_; }        ///< steps added

 private:
  std::string MetadataJson(double dataset_size_mb) const;
  std::string ObservationSpaceJson() const;
  void AddPixels(hid_t observations, hid_t infos, const StagedEpisode& staged, hsize_t rows);

  MinariWriteOptions options_;
  std::filesystem::path final_path_;
  std::filesystem::path temp_path_;
  ParentFolders parents_;  // namespace folders created for it, removed again if not committed
  // .NAME.lock beside the dataset: one writer per id at a time (released before parents_ goes)
  FolderLock lock_;
  bool temp_exists_ = false;
  H5File file_;
  int obs_dim_ = 0;
  std::optional<PixelLayout> pixels_;
  nlohmann::json selection_;  // null: every episode of the run  // options.pixels, its geometry
                              // from the first episode
  int64_t episodes_ = 0;
  int64_t steps_ = 0;
};

}  // namespace fetchscope
