// record --from RUN_DIR | TRAJECTORY_JSON | DATASET: re-rendering recorded episodes, the
// command-line part: its options and the flags it refuses (reading the source and measuring a
// dataset's divergence: run/record_from_source.h). The episodes are read and replayed by
// src/episode_source.h (TrajectorySource, EpisodeReplayer): the env reset as the run reset it, then
// the recorded actions. A recording is checked exactly (the first difference stops the run); a
// Minari dataset (dataset/minari_source.h) resets each episode with its seed or from its first
// observation, and how far the replay drifts from it is measured and reported per episode, never
// fatal.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "run/record_from_source.h"
#include "src/episode_source.h"

namespace fetchscope::cli {

/// Adds --from and --tolerance to record's `sub`.
void AddFromOption(CLI::App* sub, std::string* from, double* tolerance);

/// Throws UsageError when `sub` was given one of --env-id, --seed, --policy, --episodes,
/// --steps, --shard, --shard-count: with --from they come from the trajectory `from` (a Minari
/// dataset allows --env-id and --episodes).
void CheckFromFlags(const CLI::App& sub, const std::string& from, bool dataset = false);

/// record --from's options as given ("" / 0: not given).
struct FromOptions {
  std::string from;         ///< --from
  std::string minari_root;  ///< --minari-root
  int episodes = 0;         ///< --episodes
  std::string env_id;       ///< --env-id
  double tolerance = 1e-6;  ///< --tolerance
  std::string assets;       ///< --assets
  bool quiet = false;       ///< -q
};

/// Reads --from after checking `sub`'s flags against it (CheckFromFlags): the options resolved
/// (the datasets root, --assets) into a FromRequest for LoadRecordFromSource
/// (run/record_from_source.h). Throws as those do.
TrajectorySource LoadFromSource(const CLI::App& sub, const FromOptions& options);

/// Takes env, seed, policy, steps, episodes and (unless given) assets for record --from from
/// `source`. Throws UsageError when `sub` was given a flag CheckFromFlags refuses.
void ApplyFromSource(const TrajectorySource& source, const CLI::App& sub, std::string* env_id,
                     std::string* seed, std::string* policy, int* steps, int* episodes,
                     std::string* assets);

}  // namespace fetchscope::cli
