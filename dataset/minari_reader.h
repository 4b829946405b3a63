// Reads a Minari dataset of Fetch episodes (Minari 0.4/0.5 HDF5 storage, as DataCollector and
// create_dataset_from_buffers write it, or as MinariWriter writes it) into plain per-episode
// arrays. Every bad input is one RunError line that names the file and what is wrong.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "dataset/minari_format.h"

namespace fetchscope {

/// Where a dataset's two files are.
struct MinariLocation {
  std::filesystem::path hdf5;      ///< .../data/main_data.hdf5
  std::filesystem::path metadata;  ///< .../data/metadata.json
};

/// What metadata.json says, checked: a supported minari_version, data_format "hdf5", Fetch
/// spaces, and (when there is an env_spec) a Fetch v4 env id of the same observation width.
struct MinariMetadata {
  std::string dataset_id;                  ///< `dataset_id` (empty when absent)
  std::string minari_version;              ///< `minari_version`
  int64_t total_episodes = 0;              ///< `total_episodes`
  int64_t total_steps = 0;                 ///< `total_steps`
  int obs_dim = 0;                         ///< observation width: 10 or 25
  std::optional<std::string> env_id;       ///< env_spec's id, e.g. "FetchPush-v4"
  std::optional<int> max_episode_steps;    ///< env_spec's max_episode_steps
  std::optional<std::string> reward_type;  ///< env_spec's kwargs.reward_type
  std::string algorithm_name;              ///< `algorithm_name` (empty when absent)
  std::string code_permalink;              ///< `code_permalink` (empty when absent)
  /// env_spec's entry_point, e.g. "gymnasium_robotics.envs.fetch.push:MujocoFetchPushEnv"
  std::string entry_point;
};

/// A dataset read whole (or the episodes asked for).
struct MinariDataset {
  MinariLocation location;              ///< the files read
  MinariMetadata metadata;              ///< their metadata
  std::vector<MinariEpisode> episodes;  ///< in the order asked for (default: all, by id)
};

/// Finds a dataset given as a main_data.hdf5 file, a dataset folder (holding data/), its data/
/// folder, or an id under `root`. Throws UsageError when it is none of these.
MinariLocation LocateMinariDataset(const std::string& what, const std::filesystem::path& root);

/// Parses and checks metadata.json's text; `label` (the file) starts every error line.
MinariMetadata ParseMinariMetadata(const std::string& text, const std::string& label);

/// Reads the episodes `indices` (all of them when empty) of an open main_data.hdf5 (a file
/// path, or the bytes of one when `image` is given). Checks every array's presence, type,
/// width and length (T+1 observation rows, T of the rest).
std::vector<MinariEpisode> ReadMinariEpisodes(const std::string& label,
                                              const MinariMetadata& metadata,
                                              const std::vector<int64_t>& indices,
                                              const std::string* image = nullptr);

/// LocateMinariDataset + ParseMinariMetadata + ReadMinariEpisodes; also checks the steps
/// add up to `total_steps` when every episode is read.
MinariDataset ReadMinariDataset(const std::string& what, const std::filesystem::path& root,
                                const std::vector<int64_t>& indices = {});

/// The ids of the datasets under `root` (folders holding data/metadata.json, as Minari's
/// `list_local_datasets` finds them; hidden folders skipped), sorted.
std::vector<std::string> ListLocalMinariIds(const std::filesystem::path& root);

}  // namespace fetchscope
