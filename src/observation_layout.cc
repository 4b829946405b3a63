#include "src/observation_layout.h"

#include <cmath>
#include <cstdio>
#include <iterator>
#include <utility>

namespace fetchscope {
namespace {

using Labels = std::vector<LayoutLabel>;

// The parts, as FetchEnv::Observe appends them (constant-initialised: safe to read from other
// files' static initialisers).
constexpr LayoutLabel kGrip[] = {
    {"grip_pos.x", "gripper (site robot0:grip) position x, world frame", "m"},
    {"grip_pos.y", "gripper position y, world frame", "m"},
    {"grip_pos.z", "gripper position z, world frame (0.02 m below gripper_link's origin)", "m"}};
constexpr LayoutLabel kFingers[] = {
    {"gripper_state.right", "right finger slide joint position (0 closed .. 0.05 open)", "m"},
    {"gripper_state.left", "left finger slide joint position (0 closed .. 0.05 open)", "m"}};
constexpr LayoutLabel kGripVel[] = {
    {"grip_velp.x", "gripper linear velocity x times dt: displacement per env step", "m/step"},
    {"grip_velp.y", "gripper linear velocity y times dt", "m/step"},
    {"grip_velp.z", "gripper linear velocity z times dt", "m/step"}};
constexpr LayoutLabel kFingerVel[] = {
    {"gripper_vel.right", "right finger joint velocity times dt (not a linear velocity)", "m/step"},
    {"gripper_vel.left", "left finger joint velocity times dt", "m/step"}};
constexpr LayoutLabel kObject[] = {
    {"object_pos.x", "object (site object0) position x, world frame", "m"},
    {"object_pos.y", "object position y", "m"},
    {"object_pos.z", "object position z", "m"},
    {"object_rel_pos.x", "object minus gripper position x", "m"},
    {"object_rel_pos.y", "object minus gripper position y", "m"},
    {"object_rel_pos.z", "object minus gripper position z", "m"}};
constexpr LayoutLabel kObjectMotion[] = {
    {"object_rot.x", "object Euler angle x (rotations.mat2euler of the site matrix)", "rad"},
    {"object_rot.y", "object Euler angle y", "rad"},
    {"object_rot.z", "object Euler angle z", "rad"},
    {"object_velp.x", "object linear velocity minus gripper linear velocity x, times dt", "m/step"},
    {"object_velp.y", "object minus gripper linear velocity y, times dt", "m/step"},
    {"object_velp.z", "object minus gripper linear velocity z, times dt", "m/step"},
    {"object_velr.x", "object angular velocity x (world axes, absolute) times dt", "rad/step"},
    {"object_velr.y", "object angular velocity y times dt", "rad/step"},
    {"object_velr.z", "object angular velocity z times dt", "rad/step"}};

template <size_t... N>
Labels Join(const LayoutLabel (&... parts)[N]) {
  Labels out;
  (out.insert(out.end(), std::begin(parts), std::end(parts)), ...);
  return out;
}

// "grip_pos" of "grip_pos.x"
std::string_view SliceOf(const char* name) {
  const std::string_view n(name);
  return n.substr(0, n.find('.'));
}

}  // namespace

std::string ObservationSlice::Text() const {
  if (end == first + 1) return "obs[" + std::to_string(first) + "]";
  return "obs[" + std::to_string(first) + ":" + std::to_string(end) + "]";
}

const std::vector<LayoutLabel>& ObservationLabels(bool has_object) {
  static const Labels reach = Join(kGrip, kFingers, kGripVel, kFingerVel);
  static const Labels object = Join(kGrip, kObject, kFingers, kObjectMotion, kGripVel, kFingerVel);
  return has_object ? object : reach;
}

int ObservationSize(bool has_object) {
  return static_cast<int>(ObservationLabels(has_object).size());
}

std::optional<bool> LayoutHasObject(size_t size) {
  for (const bool has_object : {false, true}) {
    if (size == static_cast<size_t>(ObservationSize(has_object))) return has_object;
  }
  return std::nullopt;
}

std::vector<ObservationSlice> ObservationSlices(bool has_object) {
  std::vector<ObservationSlice> out;
  const Labels& labels = ObservationLabels(has_object);
  for (int i = 0; i < static_cast<int>(labels.size()); ++i) {
    const std::string_view slice = SliceOf(labels[i].name);
    if (out.empty() || out.back().name != slice) out.push_back({std::string(slice), i, i});
    out.back().end = i + 1;
  }
  return out;
}

std::optional<ObservationSlice> FindObservationSlice(bool has_object, std::string_view name) {
  for (ObservationSlice& s : ObservationSlices(has_object)) {
    if (s.name == name) return std::move(s);
  }
  return std::nullopt;
}

std::string ObservationSliceText(bool has_object, std::string_view name) {
  const std::optional<ObservationSlice> s = FindObservationSlice(has_object, name);
  return s ? s->Text() : "";
}

int ObservationIndex(bool has_object, std::string_view name) {
  const Labels& labels = ObservationLabels(has_object);
  for (size_t i = 0; i < labels.size(); ++i) {
    if (name == labels[i].name) return static_cast<int>(i);
  }
  return -1;
}

FingerIndices FingerPositionIndices(bool has_object) {
  return {ObservationIndex(has_object, "gripper_state.right"),
          ObservationIndex(has_object, "gripper_state.left")};
}

std::string FingerWidthText(bool has_object) {
  const FingerIndices f = FingerPositionIndices(has_object);
  return "obs[" + std::to_string(f.right) + "] + obs[" + std::to_string(f.left) + "]";
}

std::string ObservationIndexName(bool has_object, size_t index) {
  const Labels& labels = ObservationLabels(has_object);
  return index < labels.size() ? labels[index].name : "";
}

std::string ObservationIndexUnit(bool has_object, size_t index) {
  const Labels& labels = ObservationLabels(has_object);
  return index < labels.size() ? labels[index].unit : "";
}

std::string ObservationIndexText(bool has_object, size_t index) {
  const std::string at = "observation[" + std::to_string(index) + "]";
  const Labels& labels = ObservationLabels(has_object);
  if (index >= labels.size()) return at;
  return at + " (" + labels[index].name + ", " + labels[index].unit + ")";
}

std::string GoalIndexName(std::string_view goal, size_t index) {
  return std::string(goal) + "." + "xyz"[index % 3];
}

DisplayValue InDisplayUnit(double value, std::string_view unit) {
  if (unit == "m" || unit == "m/step") return {value * 1000, "mm" + std::string(unit.substr(1))};
  return {value, std::string(unit)};
}

std::string FormatInDisplayUnit(double value, std::string_view unit) {
  const DisplayValue shown = InDisplayUnit(value, unit);
  char buf[48];
  std::snprintf(buf, sizeof(buf), std::fabs(shown.value) >= 100 ? "%.0f" : "%.3g", shown.value);
  return shown.unit.empty() ? buf : buf + (" " + shown.unit);
}

std::vector<LayoutLabel> ActionLabels(bool block_gripper) {
  const char* gripper =
      block_gripper
          ? "ignored: this task blocks the gripper (no finger actuators; the command is zeroed and "
            "both finger joints are forced to 0 after every step)"
          : "finger position servo target = current finger position + action[3] (not scaled by "
            "0.05; servo target clamped to [0, 0.2], joint range [0, 0.05]): action[3] > 0 OPENS "
            "the fingers, < 0 closes them; |action[3]| above about 0.05 already drives a finger to "
            "its limit";
  return {
      {"dx",
       "displace the mocap target of the gripper by 0.05 m * action[0] along world x per step "
       "(position, not velocity; re-anchored on the gripper each step, so the gripper itself "
       "lags: probe-actions measures about 0.02-0.03 m per step at |a| = 1)",
       "0.05 m"},
      {"dy", "displace the gripper target by 0.05 m * action[1] along world y per step", "0.05 m"},
      {"dz", "displace the gripper target by 0.05 m * action[2] along world z per step", "0.05 m"},
      {"gripper", gripper, "m (finger target offset)"}};
}

}  // namespace fetchscope
