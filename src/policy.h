// Action sources: random (Gymnasium's Box.sample), zero, replay:FILE, scripted, exec:CMD.
// `--policy` is parsed once, at the command line's edge, into a typed PolicySpec
// (src/policy_spec.h, a light header); every layer below gets the type, and each worker builds
// its policy from it (MakePolicy, here) without reading a file.
#pragma once

#include <memory>
#include <string>

#include "src/action.h"
#include "src/env_spec.h"
#include "src/fetch_env.h"
#include "src/policy_spec.h"

namespace fetchscope {

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

/// Builds the policy `spec` names (std::visit over its cases); touches no file: a replay's
/// actions come from the spec. Throws RunError where a replay file holds too few rows or
/// lacks an episode the run plays.
std::unique_ptr<Policy> MakePolicy(const PolicySpec& spec, const EnvSpec& env,
                                   const PolicyContext& context);

}  // namespace fetchscope
