#include "dataset/minari_trajectory.h"

#include <algorithm>

#include "base/errors.h"
#include "src/observation_layout.h"

namespace fetchscope {

MinariEpisode ToMinariEpisode(const EpisodeRecord& episode, std::optional<uint64_t> seed,
                              int obs_dim) {
  MinariEpisode m;
  m.id = episode.index;
  m.seed = seed;
  if (!episode.look.is_null()) m.look = episode.look.dump();
  m.obs_dim = obs_dim;
  const size_t rows = episode.steps.size();
  if (rows == 0) throw RunError("episode " + std::to_string(episode.index) + " has no reset");
  m.observation.reserve(rows * obs_dim);
  m.achieved_goal.reserve(rows * 3);
  m.desired_goal.reserve(rows * 3);
  m.actions.reserve((rows - 1) * 4);
  for (size_t i = 0; i < rows; ++i) {
    const StepRecord& s = episode.steps[i];
    if (static_cast<int>(s.obs.observation.size()) != obs_dim) {
      throw RunError("episode " + std::to_string(episode.index) + " step " + std::to_string(i) +
                     ": " + std::to_string(s.obs.observation.size()) +
                     " observation values, expected " + std::to_string(obs_dim));
    }
    m.observation.insert(m.observation.end(), s.obs.observation.begin(), s.obs.observation.end());
    m.achieved_goal.insert(m.achieved_goal.end(), s.obs.achieved_goal.begin(),
                           s.obs.achieved_goal.end());
    m.desired_goal.insert(m.desired_goal.end(), s.obs.desired_goal.begin(),
                          s.obs.desired_goal.end());
    m.is_success.push_back(s.is_success ? 1.0f : 0.0f);
    if (i == 0) continue;
    if (!s.action || !s.reward) {
      throw RunError("episode " + std::to_string(episode.index) + " step " + std::to_string(i) +
                     " has no action or reward");
    }
    for (double v : s.action->value) {
      m.actions.push_back(static_cast<float>(std::clamp(v, -1.0, 1.0)));
    }
    m.rewards.push_back(*s.reward);
  }
  m.terminations.assign(rows - 1, 0);
  m.truncations.assign(rows - 1, 0);
  if (rows > 1) m.truncations.back() = 1;
  return m;
}

TrajectoryEpisode FromMinariEpisode(const MinariEpisode& m, const EnvSpec& spec,
                                    const std::string& file) {
  TrajectoryEpisode e;
  e.index = static_cast<int>(m.id);
  e.seed = m.seed;
  e.file = file;
  if (!m.look.empty()) e.look = nlohmann::json::parse(m.look);  // checked JSON by the reader
  const int rows = m.steps() + 1;
  for (int t = 0; t < rows; ++t) {
    TrajectoryStep s;
    s.t = t;
    s.obs.observation.assign(m.observation.begin() + t * m.obs_dim,
                             m.observation.begin() + (t + 1) * m.obs_dim);
    for (int i = 0; i < 3; ++i) {
      s.obs.achieved_goal[i] = m.achieved_goal[t * 3 + i];
      s.obs.desired_goal[i] = m.desired_goal[t * 3 + i];
    }
    s.is_success = m.is_success.empty() ? GoalDistance(s.obs.achieved_goal, s.obs.desired_goal) <
                                              spec.distance_threshold
                                        : m.is_success[t] != 0.0f;
    if (t > 0) {
      Action a;
      a.is_float32 = true;  // the action space's dtype: Gymnasium scales them in float32
      for (int i = 0; i < 4; ++i) a.value[i] = m.actions[(t - 1) * 4 + i];
      s.action = a;
      s.reward = m.rewards[t - 1];
      e.episode_return += *s.reward;
    }
    e.steps.push_back(std::move(s));
  }
  return e;
}

EpisodeStart MinariEpisodeStart(const MinariEpisode& m, const EnvSpec& spec) {
  EpisodeStart start;
  start.seed = m.seed;
  for (int i = 0; i < 3; ++i) start.goal[i] = m.desired_goal[i];
  if (spec.has_object && m.obs_dim == ObservationSize(true)) {  // the first row's object pose
    const int position = FindObservationSlice(true, "object_pos")->first;
    const int euler = FindObservationSlice(true, "object_rot")->first;
    ObjectPose pose;
    for (int i = 0; i < 3; ++i) {
      pose.position[i] = m.observation[position + i];
      pose.euler[i] = m.observation[euler + i];
    }
    start.object = pose;
  }
  return start;
}

}  // namespace fetchscope
