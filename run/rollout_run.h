// A rollout, once cli/rollout.cc has parsed and resolved its options into a RolloutJob: the
// episodes played without rendering on the episode scheduler (run/episode_scheduler.h), each
// reported as its trajectory JSON entry, and handed in episode order to an EpisodeOutput (the
// Minari dataset of --minari) as they finish, so that writing overlaps the simulation. The
// JSON is byte-identical whatever --jobs.
#pragma once

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "render/gpu_select.h"
#include "run/episode_output.h"
#include "run/episode_scheduler.h"
#include "run/pixel_recorder.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/policy_spec.h"

namespace fetchscope {

/// A rollout, resolved: what the workers play and where the episodes go.
struct RolloutJob {
  const EnvSpec* spec = nullptr;                  ///< the environment
  AssetSource assets;                             ///< resolved assets
  uint64_t seed = 0;                              ///< episode 0's reset seed
  std::string seed_text;                          ///< the seed as given
  PolicySpec policy;                              ///< --policy, parsed
  const PolicyContext* policy_context = nullptr;  ///< each worker's policy is made with it
  int steps = 50;                                 ///< steps per episode
  std::vector<int> episodes;                      ///< the episodes to play, ascending
  int episodes_requested = 0;  ///< the run's episodes (a shard plays some of them; 0: all)
  int jobs = 1;                ///< workers (ResolveJobs)
  WorkerMode mode = WorkerMode::kProcess;  ///< --worker-mode
  EpisodeOutput* output = nullptr;         ///< where the episodes go (null: nowhere)
  bool contact_signals = false;  ///< --signals contacts: each step's contacts in the trajectory
  /// --obs-camera: the images (and states) each worker renders and stages for the output
  PixelPlan pixels;
  GlBackend backend = GlBackend::kAuto;  ///< the GL backend of the workers' images
  GpuChoice gpu;                         ///< their EGL devices
  int stop_after_success = -1;           ///< --stop-after-success K (-1: off)
  std::optional<LookConfig> look;        ///< --randomize: each episode's images' look
  std::optional<uint64_t> look_seed;     ///< --look-seed: the looks' seed instead of `seed`
  std::function<void()> on_episode;      ///< called as each episode is done (progress), if set
  /// the episodes' trajectory JSON is wanted (--json-out, or JSON on stdout); else the result
  /// keeps each episode's success alone, so that memory stays flat over a long dataset run
  bool keep_trajectories = true;
};

/// What a rollout made.
struct RolloutResult {
  nlohmann::json episodes = nlohmann::json::array();  ///< each one's trajectory JSON, in order
  int successes = 0;                                  ///< episodes ending in success
  std::string output;                                 ///< the output's final name ("" without one)
  int signal = 0;       ///< SIGINT/SIGTERM stopped the run: nothing was written
  std::string stopped;  ///< then what stopped it, e.g. "interrupted (SIGINT)"
};

/// The run `job`'s output describes (command "rollout").
OutputRun RolloutOutputRun(const RolloutJob& job);

/// Plays `job`'s episodes: begins its output (its destination checked before any episode),
/// schedules the episodes, adds each to the output in order, and finishes the output unless
/// a signal stopped the run (then the output is dropped). Throws UsageError/RunError as a
/// worker or the output fails.
RolloutResult RunRolloutJob(const RolloutJob& job);

}  // namespace fetchscope
