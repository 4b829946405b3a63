// What serve serves: the run folders, trajectory files, Minari datasets and live envs named on its
// command line, and nothing else. A source is opened once, at start (a run's manifest, a file's or
// a dataset's rows); an episode's own rows are read when it is first viewed (EpisodeRows).
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "dataset/minari_source.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/episode_source.h"

namespace fetchscope::serve {

/// What kind of thing a source is.
enum class SourceKind {
  kRecording,  ///< a record run folder or a trajectory JSON file: replayed and checked exactly
  kDataset,    ///< a Minari dataset: replayed from each episode's start, its drift measured
  kLive,       ///< --env-id/--seed: a live env, reset and driven from the page
};

/// One episode of a source, as the page lists it (from the manifest or the rows, no replay).
struct ListedEpisode {
  int index = 0;                         ///< its index in the run or dataset
  int steps = 0;                         ///< steps after the reset
  bool complete = true;                  ///< false: cut short when recorded
  std::optional<bool> success;           ///< is_success at its last step, where known
  std::optional<double> episode_return;  ///< where known
};

/// A served source.
struct Source {
  SourceKind kind = SourceKind::kRecording;
  std::string given;  ///< as named on the command line
  std::string title;  ///< one line for the page: what it is
  const EnvSpec* spec = nullptr;
  AssetSource assets;
  uint64_t seed = 0;   ///< a recording's run seed (episode 0's reset); a live env's seed
  std::string policy;  ///< the policy that made it ("" for a live env)
  std::vector<ListedEpisode> episodes;  ///< in index order (a live env: none)
  /// a recording's episode files by index (a run folder), read when first viewed; empty when
  /// the rows are in `rows` (a trajectory file, a dataset)
  std::map<int, std::string> files;
  /// a trajectory file's or a dataset's rows (TrajectorySource::episodes), and for a dataset how
  /// each episode starts once ResolveStarts has run (EngineThread does, when first needed)
  std::shared_ptr<TrajectorySource> rows;
  bool starts_resolved = false;
};

/// Opens what the command line names: a record run folder (its manifest.json), a trajectory JSON
/// file (rollout's, an episode_NNN.json), or a Minari dataset (an id under `minari_root`, a
/// dataset folder, or its main_data.hdf5). Throws UsageError for what is none of these, RunError
/// (one line, naming the file) for what cannot be read.
Source OpenSource(const std::string& given, const std::filesystem::path& minari_root);

/// A live env source: `spec` on `assets`, reset with `seed`.
Source LiveSource(const EnvSpec& spec, const AssetSource& assets, uint64_t seed);

/// The rows of episode `index` of `source` (a run folder's file read now). Throws RunError naming
/// the file where it cannot be read or holds another episode.
TrajectoryEpisode EpisodeRows(const Source& source, int index);

/// The listed episode `index` of `source`, or nullptr.
const ListedEpisode* FindEpisode(const Source& source, int index);

/// The episode browser's columns of one episode: final_distance (achieved to desired goal at the
/// last step, m), first_success (the first step t >= 1 that succeeds; null if none),
/// object_displacement (m, the object's last position from its first; null without an object),
/// and where the steps carry contacts: grasped_at (the first step both fingers press the object)
/// and dropped_at (the first step after a grasp that neither holds it nor has it on the table).
nlohmann::json EpisodeColumns(const EnvSpec& spec, const std::vector<TrajectoryStep>& steps);

/// The page's view of the sources: per source its kind, title, env, seed, policy and episodes
/// ({"index", "steps", "complete", "success", "return"}), without rows.
nlohmann::json SourcesJson(const std::vector<Source>& sources);

}  // namespace fetchscope::serve
