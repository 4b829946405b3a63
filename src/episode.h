// Running episodes and turning them into the trajectory JSON of PRODUCT.md.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "src/fetch_env.h"
#include "src/policy.h"

namespace fetchscope {

/// One row of a trajectory: t = 0 is the reset observation.
struct StepRecord {
  int t = 0;                     ///< steps since reset
  Observation obs;               ///< observation after this step
  std::optional<Action> action;  ///< what the policy gave (none at t = 0)
  std::optional<double> reward;  ///< none at t = 0
  bool is_success = false;       ///< distance < threshold
};

/// A whole episode.
struct EpisodeRecord {
  int index = 0;                  ///< episode number within the run
  std::vector<StepRecord> steps;  ///< steps[0] is the reset
  double episode_return = 0;      ///< sum of rewards
  /// false when the episode was ended early (SIGINT/SIGTERM, an interrupted policy) before
  /// all its steps: it is kept as far as it got and said so ("complete": false)
  bool complete = true;
};

/// Called after the reset (t = 0) and after every step; return false to stop the episode early
/// (e.g. on SIGINT).
using StepCallback = std::function<bool(const StepRecord&, const StepResult*)>;

/// Resets (with `seed` if given, else continuing the generator), runs `steps` steps of `policy`.
EpisodeRecord RunEpisode(FetchEnv& env, Policy& policy, int index, std::optional<uint64_t> seed,
                         int steps, const StepCallback& on_step = nullptr);

/// {"path": ..., "sha256": ..., "kind": ..., "origin": ...}
nlohmann::json AssetsJson(const AssetSource& assets);

/// The step rows of one episode (t, observation, achieved_goal, desired_goal, action, reward,
/// is_success), as in the trajectory JSON; golden state files hold the same rows.
nlohmann::json StepsJson(const EpisodeRecord& episode);

/// One episode as JSON: {"index", "length", "complete", "return", "is_success",
/// "action_dtype", "steps": [...]}.
nlohmann::json EpisodeJson(const EpisodeRecord& episode);

/// The trajectory file: env_id, seed, policy, assets, episodes.
nlohmann::json TrajectoryJson(const FetchEnv& env, uint64_t seed, const std::string& policy,
                              const std::vector<const EpisodeRecord*>& episodes);

/// The trajectory file from episodes already made into JSON (EpisodeJson), in order.
nlohmann::json TrajectoryJson(const EnvSpec& spec, const AssetSource& assets, uint64_t seed,
                              const std::string& policy, nlohmann::json episodes);

}  // namespace fetchscope
