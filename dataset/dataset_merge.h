// merge-datasets: the datasets the shards of one run wrote (rollout/record --shard I/N with
// --minari or --robomimic) joined into one, episodes in the run's order, each copied as it is
// (HDF5 objects copied whole: images, states and attributes bit for bit). Each shard's dataset
// records its shard and run in its `selection` (run/episode_output.h's SelectedEpisodes);
// shards of another run, a shard given twice or missing are refused.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace fetchscope {

/// What to merge and where.
struct DatasetMergeRequest {
  std::vector<std::string> shards;  ///< Minari ids, folders or main_data.hdf5 files; or .hdf5
                                    ///< robomimic files
  std::filesystem::path root;       ///< the Minari datasets root (ids are looked up under it)
  std::string minari_id;            ///< the merged Minari dataset's id, or
  std::filesystem::path robomimic;  ///< the merged robomimic file
  bool overwrite = false;           ///< replace an existing one
  double valid_fraction = 0;        ///< robomimic: mask/train and mask/valid of the merged file
};

/// What was merged.
struct DatasetMergeResult {
  std::string path;  ///< the merged dataset's folder or file
  int shards = 0;    ///< shards read
  int episodes = 0;  ///< episodes written
};

/// Merges Minari shard datasets into `request.minari_id`. Throws UsageError naming the shard and
/// what is wrong (no shard recorded, another run, a shard twice or missing, another layout).
DatasetMergeResult MergeMinariShards(const DatasetMergeRequest& request);

/// Merges robomimic shard files into `request.robomimic`, as MergeMinariShards.
DatasetMergeResult MergeRobomimicShards(const DatasetMergeRequest& request);

}  // namespace fetchscope
