// random-episodes, once cli/random_episodes.cc has resolved its options into a
// RandomEpisodesJob: the seeded random policy's episodes on the episode scheduler
// (run/episode_scheduler.h), one metrics row each, and the baseline metrics over them. The JSON
// is byte-identical whatever --jobs.
#pragma once

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <vector>

#include "run/episode_scheduler.h"
#include "src/assets.h"
#include "src/env_spec.h"

namespace fetchscope {

/// random-episodes, resolved.
struct RandomEpisodesJob {
  const EnvSpec* spec = nullptr;           ///< the environment
  AssetSource assets;                      ///< resolved assets
  uint64_t seed = 0;                       ///< episode 0's reset seed (and the policy's)
  int episodes = 10;                       ///< episodes 0 .. episodes-1
  int jobs = 1;                            ///< workers (ResolveJobs)
  WorkerMode mode = WorkerMode::kProcess;  ///< --worker-mode
  std::function<void()> on_episode;        ///< called as each episode is done (progress), if set
};

/// The baseline over the episodes: means over episodes, the population standard deviation
/// (numpy's np.std default, ddof=0) of the returns.
struct RandomMetrics {
  int signal = 0;  ///< SIGINT/SIGTERM stopped the run: nothing else is set
  nlohmann::json rows = nlohmann::json::array();  ///< each episode's row, in episode order
  double success_rate = 0;
  double mean_return = 0;
  double std_return = 0;
  double mean_length = 0;
  double mean_final_distance = 0;
  std::vector<double> final_distances;  ///< in episode order
};

/// Plays `job`'s episodes with the random policy and sums them up. Throws UsageError/RunError
/// as a worker fails.
RandomMetrics RunRandomEpisodesJob(const RandomEpisodesJob& job);

/// The metrics file: env, seed, policy, the metrics and rows, `loaded` (the assets the env
/// loaded) and the versions.
nlohmann::json RandomMetricsJson(const RandomEpisodesJob& job, const RandomMetrics& metrics,
                                 const AssetSource& loaded);

}  // namespace fetchscope
