// Hindsight experience replay's `future` relabelling, as the reference implementations
// (OpenAI baselines her_sampler, Stable-Baselines3 HerReplayBuffer) sample it, for the
// `hindsight` overlay and the per-episode counts in record's manifest.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

namespace fetchscope {

/// Relabelled goals per transition (HER's replay_k).
inline constexpr int kHindsightK = 4;

/// One relabelled goal of a transition.
struct HindsightGoal {
  int future = 0;                ///< the step whose achieved goal it is, in [t + 1, T]
  std::array<double, 3> goal{};  ///< achieved_goal at `future`
  double reward = 0;             ///< compute_reward(achieved_goal_{t+1}, goal)
  bool success = false;          ///< distance(achieved_goal_{t+1}, goal) < threshold
};

/// The relabelling of one episode.
struct HindsightEpisode {
  /// transitions[t] (t = 0 .. T-1: from step t to step t+1) holds its kHindsightK goals.
  std::vector<std::vector<HindsightGoal>> transitions;
  int relabelled_successes = 0;  ///< relabelled goals that count as success (of k * T)
  int original_successes = 0;    ///< transitions whose own reward counts as success (of T)
};

/// The seed of episode `episode`'s relabelling in a run seeded `run_seed`: a fixed mix of the
/// two (SplitMix64), so an episode samples the same goals whatever worker records it.
uint64_t HindsightSeed(uint64_t run_seed, int episode);

/// Samples the `future` relabelling of an episode whose achieved goals after reset and after
/// each step are `achieved` (T + 1 entries) and whose desired goal is `desired`: for each
/// transition t, k times, future = t + 1 + floor(u (T - t)) with u uniform in [0, 1) (numpy's
/// Generator.random() of NumpyGenerator(seed)), as baselines' her_sampler computes future_t.
/// `reward` is compute_reward(achieved, goal) and `success` is_success(achieved, goal).
HindsightEpisode SampleHindsight(
    const std::vector<std::array<double, 3>>& achieved, const std::array<double, 3>& desired,
    uint64_t seed, int k,
    const std::function<double(const std::array<double, 3>&, const std::array<double, 3>&)>& reward,
    const std::function<bool(const std::array<double, 3>&, const std::array<double, 3>&)>& success);

}  // namespace fetchscope
