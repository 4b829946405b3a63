#include "dataset/minari_replay.h"

#include <cmath>

#include "base/errors.h"

namespace fetchscope {
namespace {

// compares one row; keeps the first value beyond the tolerance and the largest difference
void Compare(const char* name, const double* recorded, const double* replayed, int n, int t,
             double tolerance, MinariDivergence& d) {
  for (int i = 0; i < n; ++i) {
    const double diff = replayed[i] - recorded[i];
    const double size = std::isnan(diff) ? HUGE_VAL : std::fabs(diff);
    d.max_difference = std::max(d.max_difference, size);
    if (d.first_step < 0 && size > tolerance) {
      d.first_step = t;
      d.where = std::string(name) + "[" + std::to_string(i) + "]";
      d.difference = diff;
    }
  }
}

void CompareRow(const MinariEpisode& e, int t, const Observation& obs, double tolerance,
                MinariDivergence& d) {
  if (static_cast<int>(obs.observation.size()) != e.obs_dim) {
    throw RunError("the dataset's observations have " + std::to_string(e.obs_dim) +
                   " values, the env's " + std::to_string(obs.observation.size()));
  }
  Compare("observation", &e.observation[t * e.obs_dim], obs.observation.data(), e.obs_dim, t,
          tolerance, d);
  Compare("achieved_goal", &e.achieved_goal[t * 3], obs.achieved_goal.data(), 3, t, tolerance, d);
  Compare("desired_goal", &e.desired_goal[t * 3], obs.desired_goal.data(), 3, t, tolerance, d);
}

}  // namespace

MinariDivergence ReplayMinariEpisode(FetchEnv& env, const MinariEpisode& e, double tolerance) {
  MinariDivergence d;
  d.reset = e.seed ? "seed" : "continued";
  CompareRow(e, 0, env.Reset(e.seed), tolerance, d);
  for (int t = 1; t <= e.steps(); ++t) {
    Action action;
    action.is_float32 = true;
    for (int i = 0; i < 4; ++i) action.value[i] = e.actions[(t - 1) * 4 + i];
    CompareRow(e, t, env.Step(action).obs, tolerance, d);
  }
  return d;
}

}  // namespace fetchscope
