// The layout of the Fetch observation vector and of the action, written once: every index's
// name, meaning and unit, and the named slices they form (reference section 5.3). FetchEnv::Observe
// (src/fetch_env.cc) builds the observation in this order; describe, probe-actions, the anatomy
// card, the episode viewer (and through the report's data, web/src/viewer.js) read it here rather
// than writing indices of their own.
//
// Reach (10): grip_pos 0:3, gripper_state 3:5, grip_velp 5:8, gripper_vel 8:10.
// Push, PickAndPlace, Slide (25): grip_pos 0:3, object_pos 3:6, object_rel_pos 6:9,
// gripper_state 9:11, object_rot 11:14, object_velp 14:17, object_velr 17:20, grip_velp 20:23,
// gripper_vel 23:25.
// An index is named "<slice>.<component>": "object_pos.x", "gripper_state.right". The layout
// depends only on whether the task has an object (EnvSpec::has_object).
//
// For messages about one flat index (e.g. where two trajectories diverge), use
// ObservationIndexText: ObservationIndexText(true, 11) is "observation[11] (object_rot.x, rad)";
// ObservationIndexName and ObservationIndexUnit give its parts. A value in its unit is written for
// people with FormatInDisplayUnit: metres as millimetres ("-0.0139 mm"), radians as they are.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace fetchscope {

/// One index of the observation (or of the action): what describe prints for it.
struct LayoutLabel {
  const char* name;     ///< e.g. "grip_pos.x": slice name, '.', component
  const char* meaning;  ///< one line
  const char* unit;     ///< "m", "m/step", "rad", "rad/step", ...
};

/// A named run of consecutive observation indices, [first, end).
struct ObservationSlice {
  std::string name;  ///< e.g. "grip_pos"
  int first = 0;     ///< its first index
  int end = 0;       ///< one past its last index
  /// Python slice notation as the course chapter writes it: "obs[0:3]", or "obs[3]" for one index.
  std::string Text() const;
};

/// The observation's length: 10 (Reach) or 25 (the object tasks).
int ObservationSize(bool has_object);

/// The layout an observation of `size` values has: false (Reach's 10), true (the object tasks'
/// 25), nullopt for any other length.
std::optional<bool> LayoutHasObject(size_t size);

/// The label of every observation index, in order (ObservationSize entries).
const std::vector<LayoutLabel>& ObservationLabels(bool has_object);

/// The slices in order; together they cover every index once.
std::vector<ObservationSlice> ObservationSlices(bool has_object);

/// The slice called `name` ("grip_pos", "object_rel_pos", ...); nullopt when the task has none.
std::optional<ObservationSlice> FindObservationSlice(bool has_object, std::string_view name);

/// FindObservationSlice(...)->Text(), "obs[0:3]"; "" when the task has no such slice.
std::string ObservationSliceText(bool has_object, std::string_view name);

/// The index of the component called `name` ("object_pos.z"); -1 when the task has none.
int ObservationIndex(bool has_object, std::string_view name);

/// The two finger joint positions (gripper_state): the right finger's index and the left's
/// (3, 4 on Reach; 9, 10 with an object). Their sum is the finger width, m.
struct FingerIndices {
  int right = 0;
  int left = 0;
};
FingerIndices FingerPositionIndices(bool has_object);

/// The finger width as the chapter writes it: "obs[3] + obs[4]" or "obs[9] + obs[10]".
std::string FingerWidthText(bool has_object);

/// The name of flat observation index `index`, "object_rot.x"; "" when it is past the end.
std::string ObservationIndexName(bool has_object, size_t index);

/// The unit of flat observation index `index` ("m", "rad", "m/step", "rad/step"); "" when it is
/// past the end.
std::string ObservationIndexUnit(bool has_object, size_t index);

/// One flat observation index for a message: "observation[11] (object_rot.x, rad)", or
/// "observation[30]" when it is past the end of the layout.
std::string ObservationIndexText(bool has_object, size_t index);

/// Value `index` of the goals (achieved_goal, desired_goal: a position, x y z, in m):
/// GoalIndexName("desired_goal", 1) is "desired_goal.y".
std::string GoalIndexName(std::string_view goal, size_t index);
inline constexpr const char* kGoalUnit = "m";

/// A value of `unit` in the unit people read it in: metres as millimetres ("m" -> "mm",
/// "m/step" -> "mm/step"), every other unit ("rad", "rad/step", "") as it is.
struct DisplayValue {
  double value = 0;
  std::string unit;
};
DisplayValue InDisplayUnit(double value, std::string_view unit);

/// InDisplayUnit written with 3 significant digits (no decimals from 100 up) and its unit:
/// "-0.0139 mm", "0.2 mm/step", "0.0642 rad"; the number alone when `unit` is "".
std::string FormatInDisplayUnit(double value, std::string_view unit);

/// The action's four components (dx, dy, dz, gripper), with what each does in a task that
/// blocks the gripper (`block_gripper`: Reach, Push, Slide) or not (PickAndPlace).
std::vector<LayoutLabel> ActionLabels(bool block_gripper);

/// The action index of the gripper command (a[3]); a[0:3] move the gripper along x, y, z.
inline constexpr int kActionGripper = 3;

}  // namespace fetchscope
