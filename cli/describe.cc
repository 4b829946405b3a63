// fetchscope describe: Gymnasium-style spaces plus what every index means.
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "base/json_util.h"
#include "cli/chapter.h"
#include "cli/command.h"
#include "cli/common.h"
#include "cli/resolve.h"
#include "src/episode.h"
#include "src/fetch_env.h"

namespace fetchscope::cli {
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
  const bool has_object = like.spec().has_object;
  const std::string right = ObservationSlice(has_object, "gripper_state");  // "obs[i:j]"
  const int first = std::atoi(right.c_str() + 4);
  auto width = [&](const Observation& o) {
    return o.observation[first] + o.observation[first + 1];
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

std::string ObservationSlice(bool has_object, const std::string& slice) {
  const std::vector<ObservationLabel> labels = ObservationLabels(has_object);
  int first = -1, last = -1;
  for (int i = 0; i < static_cast<int>(labels.size()); ++i) {
    const std::string name = labels[i].name;
    if (name.compare(0, slice.size() + 1, slice + ".") == 0) {
      if (first < 0) first = i;
      last = i;
    }
  }
  if (first < 0) return "";
  if (first == last) return "obs[" + std::to_string(first) + "]";
  return "obs[" + std::to_string(first) + ":" + std::to_string(last + 1) + "]";
}

nlohmann::json DescribeJson(const FetchEnv& env) {
  const EnvSpec& s = env.spec();
  const mjModel* m = env.model();
  nlohmann::json obs_labels = nlohmann::json::array();
  int i = 0;
  for (const ObservationLabel& l : ObservationLabels(s.has_object)) {
    obs_labels.push_back(
        {{"index", i++}, {"name", l.name}, {"meaning", l.meaning}, {"unit", l.unit}});
  }
  const std::string gripper_meaning =
      s.block_gripper
          ? "ignored: this task blocks the gripper (no finger actuators; the command is zeroed and "
            "both finger joints are forced to 0 after every step)"
          : "finger position servo target = current finger position + action[3] (not scaled by "
            "0.05; servo target clamped to [0, 0.2], joint range [0, 0.05]): action[3] > 0 OPENS "
            "the fingers, < 0 closes them; |action[3]| above about 0.05 already drives a finger to "
            "its limit";
  nlohmann::json actions = nlohmann::json::array(
      {{{"index", 0},
        {"name", "dx"},
        {"meaning",
         "displace the mocap target of the gripper by 0.05 m * action[0] along world x per step "
         "(position, not velocity; re-anchored on the gripper each step, so the gripper itself "
         "lags: probe-actions measures about 0.02-0.03 m per step at |a| = 1)"},
        {"unit", "0.05 m"}},
       {{"index", 1},
        {"name", "dy"},
        {"meaning", "displace the gripper target by 0.05 m * action[1] along world y per step"},
        {"unit", "0.05 m"}},
       {{"index", 2},
        {"name", "dz"},
        {"meaning", "displace the gripper target by 0.05 m * action[2] along world z per step"},
        {"unit", "0.05 m"}},
       {{"index", 3},
        {"name", "gripper"},
        {"meaning", gripper_meaning},
        {"unit", "m (finger target offset)"}}});
  const int obs_size = s.has_object ? 25 : 10;
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

int RunDescribe(const DescribeOptions& o) {
  const ResolvedEnv env = ResolveEnv(o.env, /*with_seed=*/false);
  const std::string path = JsonOutPath(o.json_out, "describe");
  CheckJsonOutReplaces(path, {{"env_id", env.spec->id}}, o.overwrite);
  FetchEnv fetch(*env.spec, env.assets);
  const nlohmann::json j = DescribeJson(fetch);
  if (o.json_out.empty()) {
    std::printf("%s\n", DumpJson(j).c_str());  // the JSON alone: its "chapter_differences" say it
  } else {
    WriteJson(path, j);
    std::printf("wrote %s\n", path.c_str());
    for (const auto& line : j["chapter_differences"]) {
      std::printf("differs from the chapter: %s\n", line.get<std::string>().c_str());
    }
  }
  return 0;
}

Command AddDescribe(CLI::App& app) {
  auto o = std::make_shared<DescribeOptions>();
  CLI::App* sub = app.add_subcommand(
      "describe", "Observation/action schema with a label per index, reward formulas, timing");
  AddEnvOptions(sub, &o->env, false);
  sub->add_option("--json-out", o->json_out,
                  "Write P (if it ends in .json), P/describe.json if P ends in /, else "
                  "P_describe.json; without it the JSON goes to stdout. Where the env differs "
                  "from the course chapter, a line says so with the measurement that decides it");
  sub->add_flag("--overwrite", o->overwrite, kJsonOverwriteHelp);
  return {sub, [o] { return RunDescribe(*o); }};
}

}  // namespace fetchscope::cli
