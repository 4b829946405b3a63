// Action sources: random (Gymnasium's Box.sample), zero, replay:FILE, scripted, exec:CMD.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "src/action.h"
#include "src/env_spec.h"
#include "src/fetch_env.h"

namespace fetchscope {

struct Trajectory;

/// Chooses an action from the current observation.
class Policy {
 public:
  virtual ~Policy() = default;
  /// Called after each reset, with the episode index and the reset observation.
  virtual void BeginEpisode(int episode, const Observation& obs) {
    (void)episode;
    (void)obs;
  }
  /// The action for step t (0-based) given the latest observation.
  virtual Action Act(const Observation& obs, int t) = 0;
  /// The spec as given, e.g. "replay:run.csv".
  virtual std::string name() const = 0;
  /// Advances whatever this policy carries from one episode to the next as if an episode of
  /// `steps` steps had been played, without playing it, so that a worker starting at episode k
  /// acts exactly as a sequential run does at k. Random draws 4 numbers per step; the others
  /// start every episode afresh (replay indexes its rows by episode) and do nothing. An exec:
  /// child is not told: it sees only the episodes its own worker plays.
  virtual void SkipEpisode(int steps) { (void)steps; }
};

/// Options shared by policy construction.
struct PolicyContext {
  uint64_t seed = 0;             ///< action_space.seed(seed) for random
  int steps_per_episode = 50;    ///< replay checks it has enough rows
  int episodes = 1;              ///< replay checks it has enough rows
  double exec_timeout_s = 10.0;  ///< exec: seconds to wait for each answer
  /// True while the run is being stopped (SIGINT/SIGTERM): an exec: child that dies then is
  /// an interruption (PolicyInterrupted), not a failure. May be empty.
  std::function<bool()> stop_requested;
  /// --replay-dtype: "" (the file's own), "float32" or "float64". CSV and JSON lines are read
  /// in double precision and then, with float32, rounded to float32 and played on Gymnasium's
  /// float32 path; .npy and trajectory JSON carry their dtype (a different one is refused).
  std::string replay_dtype;
  /// The episodes the run plays (replay checks the file has them); empty: 0 .. episodes-1.
  std::vector<int> episode_indices;
  /// For replay:FILE.json: the trajectory already read (ReadReplayedEpisodes), so that the
  /// file is parsed once; null: MakePolicy reads it.
  std::shared_ptr<const Trajectory> replay_trajectory;
};

/// Builds a policy from `--policy`: random | zero | scripted | replay:FILE | exec:CMD.
/// Throws UsageError for an unknown name (listing the accepted ones), RunError for a bad file.
std::unique_ptr<Policy> MakePolicy(const std::string& spec, const EnvSpec& env,
                                   const PolicyContext& context);

/// --replay-dtype's help.
inline constexpr const char* kReplayDtypeHelp =
    "float32 or float64: the precision of a replay:FILE .csv or .jsonl's actions (default "
    "float64; float32 rounds each value to float32 and plays it on Gymnasium's float32 path, "
    "as a recorded random policy's actions). A .npy or trajectory .json carries its own";

/// The accepted policy names, for --help.
inline constexpr const char* kPolicyHelp =
    "random (seeded like action_space.seed + sample), zero, scripted, replay:FILE "
    "(.csv with 4 columns, .npy T x 4 float32/float64, .jsonl, or fetchscope's trajectory "
    ".json: all its episodes, in their recorded precision), exec:CMD (child process speaking "
    "JSON lines)";

}  // namespace fetchscope
