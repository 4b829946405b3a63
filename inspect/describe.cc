#include "inspect/describe.h"

#include <cmath>
#include <cstdio>

#include "base/json_util.h"
#include "src/episode.h"
#include "src/observation_layout.h"
#include "src/trajectory.h"
#include "src/versions.h"

namespace fetchscope {
namespace {

// A Box as the chapter prints it (Gymnasium's `low.tolist()`/`high.tolist()`): one bound per
// element, infinities as the strict-JSON strings "-inf"/"inf".
nlohmann::json Box(int n, const std::string& dtype, double low, double high) {
  nlohmann::json lows = nlohmann::json::array(), highs = nlohmann::json::array();
  for (int i = 0; i < n; ++i) {
    lows.push_back(JsonDouble(low));
    highs.push_back(JsonDouble(high));
  }
  return {{"type", "Box"}, {"shape", {n}}, {"dtype", dtype}, {"low", lows}, {"high", highs}};
}

// "+0.1000": a signed width in metres, without "-0.0000".
std::string SignedMetres(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%+.4f", std::fabs(v) < 5e-5 ? 0.0 : v);
  return text;
}

constexpr int kGripSteps = 5;  // steps of a[3] = +-1 from reset that the gripper lines measure

// The change in finger width (the two finger joints of gripper_state) after kGripSteps steps of
// a[3] = `a3` (a[0..2] = 0) from reset with seed 0, on a fresh copy of `env`.
double FingerWidthChange(const FetchEnv& like, double a3) {
  FetchEnv env(like.spec(), like.assets());
  const FingerIndices fingers = FingerPositionIndices(like.spec().has_object);
  auto width = [&](const Observation& o) {
    return o.observation[fingers.right] + o.observation[fingers.left];
  };
  const double before = width(env.Reset(0));
  Observation after;
  Action action;
  action.value = {0, 0, 0, a3};
  for (int i = 0; i < kGripSteps; ++i) after = env.Step(action).obs;
  return width(after) - before;
}

}  // namespace

std::vector<std::string> GripperVersusChapter(const FetchEnv& env) {
  const std::string steps = std::to_string(kGripSteps);
  const double open = FingerWidthChange(env, +1);
  if (env.spec().block_gripper) {
    const double close = FingerWidthChange(env, -1);
    return {"a[3] is ignored in " + env.spec().id + " (the chapter says " + kChapterGripper +
            "): finger width " + SignedMetres(open) + " m after " + steps + " steps of a[3]=+1, " +
            SignedMetres(close) + " m after " + steps + " of a[3]=-1: a difference of " +
            SignedMetres(open - close) + " m"};
  }
  return {std::string(open > 0 ? "a[3] > 0 opens the fingers (the chapter says it closes them)"
                               : "a[3] > 0 does not open the fingers here") +
          ": finger width " + SignedMetres(open) + " m after " + steps + " steps of a[3]=+1"};
}

nlohmann::json DescribeJson(const FetchEnv& env) {
  const EnvSpec& s = env.spec();
  const mjModel* m = env.model();
  nlohmann::json obs_labels = nlohmann::json::array();
  int i = 0;
  for (const LayoutLabel& l : ObservationLabels(s.has_object)) {
    obs_labels.push_back(
        {{"index", i++}, {"name", l.name}, {"meaning", l.meaning}, {"unit", l.unit}});
  }
  nlohmann::json actions = nlohmann::json::array();
  i = 0;
  for (const LayoutLabel& l : ActionLabels(s.block_gripper)) {
    actions.push_back({{"index", i++}, {"name", l.name}, {"meaning", l.meaning}, {"unit", l.unit}});
  }
  const int obs_size = ObservationSize(s.has_object);
  nlohmann::json j;
  j["env_id"] = s.id;
  j["task"] = TaskName(s.task);
  j["reward_type"] = s.dense ? "dense" : "sparse";
  j["action_space"] = Box(4, "float32", -1.0, 1.0);
  j["action_space"]["labels"] = actions;
  j["action_space"]["clipping"] =
      "actions are clipped to [-1, 1] before use; larger commands saturate";
  // the chapter's layout: the three Boxes directly under observation_space (Gymnasium's Dict
  // space, keys sorted as Dict sorts them); our labels and meanings are extra keys in each Box
  j["observation_space"] = {{"achieved_goal", Box(3, "float64", -INFINITY, INFINITY)},
                            {"desired_goal", Box(3, "float64", -INFINITY, INFINITY)},
                            {"observation", Box(obs_size, "float64", -INFINITY, INFINITY)}};
  j["observation_space_type"] = "Dict";
  j["observation_space"]["observation"]["labels"] = obs_labels;
  j["observation_space"]["achieved_goal"]["meaning"] =
      s.has_object ? "object (site object0) position, m" : "gripper (site robot0:grip) position, m";
  j["observation_space"]["desired_goal"]["meaning"] = "the episode's goal position, m";
  j["reward"] = {
      {"distance", "d = || achieved_goal - desired_goal ||_2 (Euclidean, metres)"},
      {"sparse", "-1.0 if d > distance_threshold else -0.0 (float32)"},
      {"dense", "-d (float64)"},
      {"this_env", s.dense ? "dense" : "sparse"},
      {"is_success", "1.0 if d < distance_threshold else 0.0 (strict <; reward uses strict >)"},
      {"relabelling",
       "compute_reward(achieved_goal, desired_goal, info) depends only on the two "
       "goals (info is ignored), so any achieved goal can be paired with any goal "
       "after the fact: that is what makes hindsight experience replay work"}};
  j["distance_threshold"] = s.distance_threshold;
  j["max_episode_steps"] = s.max_episode_steps;
  j["n_substeps"] = s.n_substeps;
  j["timestep"] = m->opt.timestep;
  j["control_dt"] = env.dt();
  j["block_gripper"] = s.block_gripper;
  j["has_object"] = s.has_object;
  j["target_in_the_air"] = s.target_in_the_air;
  j["target_range"] = s.target_range;
  j["obj_range"] = s.obj_range;
  j["target_offset"] = JsonVector(s.target_offset.data(), 3);
  j["initial_gripper_xpos"] = JsonVector(env.initial_gripper_xpos().data(), 3);
  if (s.has_object) j["height_offset"] = env.height_offset();
  j["assets"] = AssetsJson(env.assets());
  j["model_file"] = env.model_path();
  j["versions"] = VersionsJson();
  j["answers"] = {
      {"observation_size", obs_size},
      {"action_index_3", s.block_gripper ? "nothing in this task: the gripper is blocked"
                                         : "the two finger position servos: > 0 opens, < 0 closes"},
      {"success_threshold_m", s.distance_threshold},
      {"why_relabelling_works", "the reward is a pure function of (achieved_goal, desired_goal)"}};
  // where the chapter says otherwise, each line with the measurement that decides it
  j["chapter_differences"] = GripperVersusChapter(env);
  return j;
}

}  // namespace fetchscope
