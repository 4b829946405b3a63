// record --from RUN_DIR_OR_TRAJECTORY_JSON: re-rendering recorded episodes, the command-line
// part. The episodes are read and replayed by src/episode_source.h (TrajectorySource,
// EpisodeReplayer): the env reset as the run reset it, then the recorded actions, every
// replayed observation checked against the recorded one, so one rollout gives any number of
// views.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "src/episode_source.h"

namespace fetchscope::cli {

/// Adds --from to record's `sub`.
void AddFromOption(CLI::App* sub, std::string* from);

/// Throws UsageError when `sub` was given one of --env-id, --seed, --policy, --episodes,
/// --steps, --shard, --shard-count: with --from they come from the trajectory `from`.
void CheckFromFlags(const CLI::App& sub, const std::string& from);

/// Takes env, seed, policy, steps, episodes and (unless given) assets for record --from from
/// `source`. Throws UsageError when `sub` was given one of --env-id, --seed, --policy,
/// --episodes, --steps, --shard, --shard-count (they come from the trajectory).
void ApplyFromSource(const TrajectorySource& source, const CLI::App& sub, std::string* env_id,
                     std::string* seed, std::string* policy, int* steps, int* episodes,
                     std::string* assets);

}  // namespace fetchscope::cli
