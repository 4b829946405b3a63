// Writes one Minari dataset (<root>/<id>/data/{main_data.hdf5, metadata.json}) with libhdf5, in
// the layout Minari 0.5's HDF5 storage writes (see docs/guide/datasets.md), so that
// minari.load_dataset(id) reads it with no other step.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "base/atomic_file.h"
#include "dataset/hdf5_handles.h"
#include "dataset/minari_format.h"
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
  std::string code_permalink;         ///< metadata `code_permalink`
  std::string description;            ///< metadata `description` (omitted when empty)
};

/// Checks the id and refuses an existing dataset unless `overwrite` (UsageError naming the
/// folder), without writing anything: a command calls it before a long run, MinariWriter again.
void CheckMinariDestination(const MinariWriteOptions& options);

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
  /// n). Throws RunError if the arrays disagree with T = rewards.size() or libhdf5 fails.
  void Add(const MinariEpisode& episode);

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

  MinariWriteOptions options_;
  std::filesystem::path final_path_;
  std::filesystem::path temp_path_;
  ParentFolders parents_;  // namespace folders created for it, removed again if not committed
  bool temp_exists_ = false;
  H5File file_;
  int obs_dim_ = 0;
  int64_t episodes_ = 0;
  int64_t steps_ = 0;
};

}  // namespace fetchscope
