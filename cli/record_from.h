// record --from RUN_DIR | TRAJECTORY_JSON | DATASET: re-rendering recorded episodes, the
// command-line part. The episodes are read and replayed by src/episode_source.h
// (TrajectorySource, EpisodeReplayer): the env reset as the run reset it, then the recorded
// actions. A recording is checked exactly (the first difference stops the run); a Minari dataset
// (dataset/minari_source.h) resets each episode with its seed or from its first observation, and
// how far the replay drifts from it is measured and reported per episode, never fatal.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "run/manifest.h"
#include "src/episode_source.h"

namespace fetchscope::cli {

/// Adds --from and --tolerance to record's `sub`.
void AddFromOption(CLI::App* sub, std::string* from, double* tolerance);

/// Throws UsageError when `sub` was given one of --env-id, --seed, --policy, --episodes,
/// --steps, --shard, --shard-count: with --from they come from the trajectory `from` (a Minari
/// dataset allows --env-id and --episodes).
void CheckFromFlags(const CLI::App& sub, const std::string& from, bool dataset = false);

/// What record --from reads the source with.
struct FromRequest {
  std::string from;         ///< --from
  std::string minari_root;  ///< --minari-root ("" default)
  int episodes = 0;         ///< --episodes where given, else 0
  std::string env_id;       ///< --env-id where given, else ""
  double tolerance = 1e-6;  ///< --tolerance
  std::string assets;       ///< --assets where given, else ""
  bool quiet = false;       ///< -q: print nothing
};

/// Reads --from: a recording (LoadTrajectorySource) or a Minari dataset (LoadMinariSource),
/// which is then replayed once without rendering to measure its divergence; prints what was
/// found and, per episode, the reset used and the divergence (unless quiet). Throws as those do.
TrajectorySource LoadFromSource(const CLI::App& sub, const FromRequest& request);

/// Takes env, seed, policy, steps, episodes and (unless given) assets for record --from from
/// `source`. Throws UsageError when `sub` was given a flag CheckFromFlags refuses.
void ApplyFromSource(const TrajectorySource& source, const CLI::App& sub, std::string* env_id,
                     std::string* seed, std::string* policy, int* steps, int* episodes,
                     std::string* assets);

/// One episode's divergence as record prints it, e.g. "episode 2: reset from its first
/// observation; diverges at step 17, observation[3] off by 0.0012 (tolerance 1e-06)".
std::string DescribeDivergence(int k, const EpisodeDivergence& d);

}  // namespace fetchscope::cli
