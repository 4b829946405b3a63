// Running episodes: a policy on an environment, step by step, into a trajectory episode
// (src/trajectory.h, which also writes them).
#pragma once

#include <cstdint>
#include <functional>
#include <optional>

#include "src/fetch_env.h"
#include "src/trajectory.h"

namespace fetchscope {

class Policy;  // src/policy.h

/// One row of an episode as it is played (the trajectory's step).
using StepRecord = TrajectoryStep;

/// A whole episode as it is played (the trajectory's episode).
using EpisodeRecord = TrajectoryEpisode;

/// Called after the reset (t = 0) and after every step; return false to stop the episode early
/// (e.g. on SIGINT).
using StepCallback = std::function<bool(const StepRecord&, const StepResult*)>;

/// Resets (with `seed` if given, else continuing the generator), runs `steps` steps of `policy`.
EpisodeRecord RunEpisode(FetchEnv& env, Policy& policy, int index, std::optional<uint64_t> seed,
                         int steps, const StepCallback& on_step = nullptr);

}  // namespace fetchscope
