#include "src/episode.h"

#include "base/errors.h"
#include "src/policy.h"

namespace fetchscope {

EpisodeRecord RunEpisode(FetchEnv& env, Policy& policy, int index, std::optional<uint64_t> seed,
                         int steps, const StepCallback& on_step) {
  EpisodeRecord episode;
  episode.index = index;
  episode.seed = seed;
  StepRecord first;
  first.obs = env.Reset(seed);
  first.is_success = env.IsSuccess(first.obs.achieved_goal, first.obs.desired_goal);
  first.contacts = env.Contacts();
  episode.steps.push_back(first);
  policy.BeginEpisode(index, first.obs);
  episode.complete = steps == 0;
  if (on_step && !on_step(episode.steps.back(), nullptr)) return episode;
  for (int t = 0; t < steps; ++t) {
    Action action;
    try {
      action = policy.Act(episode.steps.back().obs, t);
    } catch (const PolicyInterrupted&) {
      return episode;  // the stop came while the policy was answering: the episode ends here
    }
    const StepResult result = env.Step(action);
    StepRecord record;
    record.t = t + 1;
    record.obs = result.obs;
    record.action = action;
    record.reward = result.reward;
    record.is_success = result.is_success;
    record.past_time_limit = record.t > env.spec().max_episode_steps;
    record.contacts = env.Contacts();
    episode.episode_return += result.reward;
    episode.steps.push_back(std::move(record));
    if (t + 1 == steps) episode.complete = true;
    if (on_step && !on_step(episode.steps.back(), &result)) break;
  }
  return episode;
}

}  // namespace fetchscope
