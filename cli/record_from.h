// record --from RUN_DIR_OR_TRAJECTORY_JSON: re-rendering recorded episodes. The episodes are
// replayed (the env reset as the run reset it, then the recorded actions) and every replayed
// observation is checked against the recorded one, so one rollout gives any number of views.
// Also the replay that the hindsight overlay renders from (run the episode, then render it).
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "base/errors.h"
#include "src/episode.h"
#include "src/fetch_env.h"

namespace fetchscope::cli {

/// One recorded episode.
struct RecordedEpisode {
  int index = 0;                  ///< episode number within its run
  std::string file;               ///< the JSON file it came from (for messages)
  std::vector<StepRecord> steps;  ///< steps[0] is the reset; actions with their dtype
  /// false when the recording was cut short (SIGINT/SIGTERM): a re-render stays incomplete
  bool complete = true;
};

/// What --from names: the run's env, seed, policy and assets, and its episodes by index.
struct TrajectorySource {
  std::string path;                         ///< as given
  std::string env_id;                       ///< trajectory env_id
  uint64_t seed = 0;                        ///< trajectory seed (episode 0's reset)
  std::string policy;                       ///< the policy that made it (for the manifest)
  nlohmann::json assets;                    ///< trajectory assets {kind, path, sha256, origin}
  std::map<int, RecordedEpisode> episodes;  ///< by index
  int max_steps = 0;                        ///< the longest episode's steps
};

/// Reads a trajectory JSON file, or every episode_NNN.json of a run folder. Throws UsageError
/// for a path that is neither, RunError naming the file (and episode and step) for content
/// that is not a fetchscope trajectory or mixes env ids or seeds.
TrajectorySource LoadTrajectorySource(const std::string& path);

/// The --assets value that reproduces `source`: "bundled" for bundled assets, else the
/// recorded folder.
std::string SourceAssets(const TrajectorySource& source);

/// Replays recorded episodes on one environment: episode k starts from the reset the run made
/// (episode 0's reset seeded with `seed`, the others continuing the generator: the resets in
/// between are replayed, as EpisodeSequence does), then steps the recorded actions.
class EpisodeReplayer {
 public:
  EpisodeReplayer(FetchEnv& env, uint64_t seed) : env_(env), seed_(seed) {}
  /// Replays episode `k` with the actions of `recorded` (steps 1..), calling `on_step` as
  /// RunEpisode does. With `check` set, each replayed observation, reward and success flag must
  /// equal the recorded ones exactly; the first that does not throws ReplayMismatch naming
  /// `check` (the file), the episode, the step, the value and the difference. The result is
  /// complete only when `recorded_complete` and every recorded step was replayed (`on_step`
  /// may stop it early).
  EpisodeRecord Replay(int k, const std::vector<StepRecord>& recorded, bool recorded_complete,
                       const std::string& check, const StepCallback& on_step);

 private:
  FetchEnv& env_;
  uint64_t seed_;
  int next_ = 0;  // the episode whose reset the generator stands before
};

/// The message of a replayed step that differs from the recording (see EpisodeReplayer); one
/// line, which record prints alone.
struct ReplayMismatch : RunError {
  using RunError::RunError;
};

/// Where replay and recording differ first in one step, or "" when they agree: e.g.
/// "observation[3] recorded 1.3, replayed 1.2 (difference replayed - recorded -0.1)".
std::string FirstDifference(const StepRecord& replayed, const StepRecord& recorded);

/// Replays every episode of `source` on `env` (no rendering) and checks each step as
/// EpisodeReplayer does: an edited recording stops the run before anything is written. Throws
/// ReplayMismatch.
void VerifyRecording(FetchEnv& env, const TrajectorySource& source);

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
