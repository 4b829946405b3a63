#include "src/env_spec.h"

#include "base/errors.h"
#include "base/suggest.h"

namespace fetchscope {
namespace {

std::vector<EnvSpec> MakeSpecs() {
  std::vector<EnvSpec> specs;
  auto add = [&specs](const std::string& name, Task task, const std::string& file, bool has_object,
                      bool block_gripper, double extra_height, bool in_air,
                      std::array<double, 3> offset, double obj_range, double target_range,
                      std::vector<std::pair<std::string, std::vector<double>>> qpos) {
    for (bool dense : {false, true}) {
      EnvSpec s;
      s.id = "Fetch" + name + (dense ? "Dense" : "") + "-v4";
      s.task = task;
      s.dense = dense;
      s.model_file = file;
      s.has_object = has_object;
      s.block_gripper = block_gripper;
      s.gripper_extra_height = extra_height;
      s.target_in_the_air = in_air;
      s.target_offset = offset;
      s.obj_range = obj_range;
      s.target_range = target_range;
      s.distance_threshold = 0.05;
      s.initial_qpos = qpos;
      specs.push_back(s);
    }
  };
  const std::vector<double> block{1.25, 0.53, 0.4, 1.0, 0.0, 0.0, 0.0};
  add("Reach", Task::kReach, "reach.xml", false, true, 0.2, true, {0, 0, 0}, 0.15, 0.15,
      {{"robot0:slide0", {0.4049}}, {"robot0:slide1", {0.48}}, {"robot0:slide2", {0.0}}});
  add("Push", Task::kPush, "push.xml", true, true, 0.0, false, {0, 0, 0}, 0.15, 0.15,
      {{"robot0:slide0", {0.405}},
       {"robot0:slide1", {0.48}},
       {"robot0:slide2", {0.0}},
       {"object0:joint", block}});
  add("PickAndPlace", Task::kPickAndPlace, "pick_and_place.xml", true, false, 0.2, true, {0, 0, 0},
      0.15, 0.15,
      {{"robot0:slide0", {0.405}},
       {"robot0:slide1", {0.48}},
       {"robot0:slide2", {0.0}},
       {"object0:joint", block}});
  add("Slide", Task::kSlide, "slide.xml", true, true, -0.02, false, {0.4, 0, 0}, 0.1, 0.3,
      {{"robot0:slide0", {0.05}},
       {"robot0:slide1", {0.48}},
       {"robot0:slide2", {0.0}},
       {"object0:joint", {1.7, 1.1, 0.41, 1.0, 0.0, 0.0, 0.0}}});
  return specs;
}

}  // namespace

const std::vector<EnvSpec>& AllEnvSpecs() {
  static const std::vector<EnvSpec> specs = MakeSpecs();
  return specs;
}

const EnvSpec& FindEnvSpec(const std::string& id) {
  const std::string wanted = (id == "auto") ? "FetchReachDense-v4" : id;
  std::string valid;
  std::vector<std::string> names = {"auto"};
  for (const EnvSpec& s : AllEnvSpecs()) {
    if (s.id == wanted) return s;
    valid += (valid.empty() ? "" : ", ") + s.id;
    names.push_back(s.id);
  }
  throw UsageError("unknown env id '" + id + "'" + DidYouMean(id, names) + ": use one of " + valid +
                   " (or auto)");
}

std::string TaskName(Task task) {
  switch (task) {
    case Task::kReach:
      return "Reach";
    case Task::kPush:
      return "Push";
    case Task::kPickAndPlace:
      return "PickAndPlace";
    case Task::kSlide:
      return "Slide";
  }
  return "?";
}

}  // namespace fetchscope
