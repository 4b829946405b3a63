// The eight registered Fetch v4 environments and their task parameters.
#pragma once

#include <array>
#include <string>
#include <utility>
#include <vector>

namespace fetchscope {

/// The four Fetch tasks.
enum class Task { kReach, kPush, kPickAndPlace, kSlide };

/// Constructor parameters of one registered id (reference section 1).
struct EnvSpec {
  std::string id;                       ///< e.g. "FetchPushDense-v4"
  Task task;                            ///< which task class
  bool dense;                           ///< reward_type "dense" (else "sparse")
  std::string model_file;               ///< "push.xml": file name in the fetch/ folder
  bool has_object;                      ///< Push, PickAndPlace, Slide
  bool block_gripper;                   ///< Reach, Push, Slide
  double gripper_extra_height;          ///< m, added to the mocap target z at setup
  bool target_in_the_air;               ///< PickAndPlace: goal may be lifted
  std::array<double, 3> target_offset;  ///< m, added to goals (Slide: +0.4 in x)
  double obj_range;                     ///< m, half-width of the object xy draw
  double target_range;                  ///< m, half-width of the goal draw
  double distance_threshold;            ///< m, success radius
  /// joint name → qpos values written at setup, in this order
  std::vector<std::pair<std::string, std::vector<double>>> initial_qpos;
  int max_episode_steps = 50;  ///< TimeLimit truncation
  int n_substeps = 20;         ///< mj_step calls per env step
};

/// All eight v4 ids, in registration order (sparse before dense per task).
const std::vector<EnvSpec>& AllEnvSpecs();

/// Looks up an id; "auto" means FetchReachDense-v4. Throws UsageError listing the valid ids.
const EnvSpec& FindEnvSpec(const std::string& id);

/// "Reach", "Push", "PickAndPlace", "Slide".
std::string TaskName(Task task);

}  // namespace fetchscope
