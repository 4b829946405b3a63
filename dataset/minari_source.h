// record --from DATASET: a Minari dataset as an episode source (src/episode_source.h), read by
// dataset/minari_reader.h and converted by dataset/minari_trajectory.h.
#pragma once

#include <filesystem>
#include <string>

#include "src/episode_source.h"

namespace fetchscope {

/// What record --from DATASET asks for.
struct MinariSourceRequest {
  std::string what;            ///< an id under `root`, a dataset folder, or its main_data.hdf5
  std::filesystem::path root;  ///< the datasets root (MinariRoot)
  int episodes = 0;            ///< --episodes: the first N episodes (by id); 0: all
  std::string env_id;          ///< --env-id ("" not given): needed where there is no env_spec
  double tolerance = 1e-6;     ///< --tolerance
};

/// A dataset read as an episode source, and what was found, as one line for the console.
struct MinariSource {
  TrajectorySource source;     ///< dataset = true, a start per episode
  std::string found;           ///< "Minari dataset ID (FILE): env ..., N episode(s), ..."
  bool env_from_spec = false;  ///< the env is the dataset's env_spec (not --env-id)
  /// env_spec names Gymnasium-Robotics' own env and fetchscope did not write the dataset
  /// (its code_permalink): it was made on the genuine assets
  bool genuine_env = false;
};

/// Reads the dataset. Throws RunError (one line naming the file and what is wrong: the reader's)
/// and UsageError for an --env-id that conflicts with env_spec (naming both), a dataset with no
/// env_spec and no --env-id, or --episodes beyond the dataset's episodes.
MinariSource LoadMinariSource(const MinariSourceRequest& request);

/// True when `path` is a record run folder (holding episode_NNN.json, or no dataset either) or
/// a file other than an .hdf5 one (a trajectory JSON; a FIFO or a device too, which
/// LoadTrajectorySource refuses): what LoadTrajectorySource reads.
/// Anything else is taken as a Minari dataset.
bool IsTrajectoryPath(const std::string& path);

}  // namespace fetchscope
