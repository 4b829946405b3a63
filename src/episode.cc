#include "src/episode.h"

#include "base/errors.h"
#include "base/json_util.h"

namespace fetchscope {

EpisodeRecord RunEpisode(FetchEnv& env, Policy& policy, int index, std::optional<uint64_t> seed,
                         int steps, const StepCallback& on_step) {
  EpisodeRecord episode;
  episode.index = index;
  StepRecord first;
  first.obs = env.Reset(seed);
  first.is_success = env.IsSuccess(first.obs.achieved_goal, first.obs.desired_goal);
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
    episode.episode_return += result.reward;
    episode.steps.push_back(std::move(record));
    if (t + 1 == steps) episode.complete = true;
    if (on_step && !on_step(episode.steps.back(), &result)) break;
  }
  return episode;
}

nlohmann::json AssetsJson(const AssetSource& assets) {
  return {{"kind", assets.kind},
          {"path", assets.root},
          {"sha256", assets.sha256},
          {"origin", assets.origin}};
}

nlohmann::json StepsJson(const EpisodeRecord& episode) {
  nlohmann::json steps = nlohmann::json::array();
  for (const StepRecord& s : episode.steps) {
    nlohmann::json row;
    row["t"] = s.t;
    row["observation"] = JsonVector(s.obs.observation.data(), s.obs.observation.size());
    row["achieved_goal"] = JsonVector(s.obs.achieved_goal.data(), 3);
    row["desired_goal"] = JsonVector(s.obs.desired_goal.data(), 3);
    row["action"] = s.action ? JsonVector(s.action->value.data(), 4) : nlohmann::json(nullptr);
    row["reward"] = s.reward ? JsonDouble(*s.reward) : nlohmann::json(nullptr);
    row["is_success"] = s.is_success;
    steps.push_back(std::move(row));
  }
  return steps;
}

nlohmann::json EpisodeJson(const EpisodeRecord& episode) {
  nlohmann::json steps = StepsJson(episode);
  std::string dtype = "none";
  if (episode.steps.size() > 1 && episode.steps[1].action) {
    dtype = episode.steps[1].action->is_float32 ? "float32" : "float64";
  }
  return {{"index", episode.index},
          {"length", static_cast<int>(episode.steps.size()) - 1},
          {"complete", episode.complete},
          {"return", JsonDouble(episode.episode_return)},
          {"is_success", !episode.steps.empty() && episode.steps.back().is_success},
          {"action_dtype", dtype},
          {"steps", std::move(steps)}};
}

nlohmann::json TrajectoryJson(const FetchEnv& env, uint64_t seed, const std::string& policy,
                              const std::vector<const EpisodeRecord*>& episodes) {
  nlohmann::json eps = nlohmann::json::array();
  for (const EpisodeRecord* e : episodes) eps.push_back(EpisodeJson(*e));
  return TrajectoryJson(env.spec(), env.assets(), seed, policy, std::move(eps));
}

nlohmann::json TrajectoryJson(const EnvSpec& spec, const AssetSource& assets, uint64_t seed,
                              const std::string& policy, nlohmann::json episodes) {
  return {{"env_id", spec.id},
          {"seed", seed},
          {"policy", policy},
          {"assets", AssetsJson(assets)},
          {"episodes", std::move(episodes)}};
}

}  // namespace fetchscope
