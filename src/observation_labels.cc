#include "src/observation_labels.h"

namespace fetchscope {

std::vector<ObservationLabel> ObservationLabels(bool has_object) {
  using Label = ObservationLabel;
  const std::vector<Label> grip = {
      {"grip_pos.x", "gripper (site robot0:grip) position x, world frame", "m"},
      {"grip_pos.y", "gripper position y, world frame", "m"},
      {"grip_pos.z", "gripper position z, world frame (0.02 m below gripper_link's origin)", "m"}};
  const std::vector<Label> fingers = {
      {"gripper_state.right", "right finger slide joint position (0 closed .. 0.05 open)", "m"},
      {"gripper_state.left", "left finger slide joint position (0 closed .. 0.05 open)", "m"}};
  const std::vector<Label> grip_vel = {
      {"grip_velp.x", "gripper linear velocity x times dt: displacement per env step", "m/step"},
      {"grip_velp.y", "gripper linear velocity y times dt", "m/step"},
      {"grip_velp.z", "gripper linear velocity z times dt", "m/step"}};
  const std::vector<Label> finger_vel = {
      {"gripper_vel.right", "right finger joint velocity times dt (not a linear velocity)",
       "m/step"},
      {"gripper_vel.left", "left finger joint velocity times dt", "m/step"}};
  std::vector<Label> out = grip;
  if (!has_object) {
    out.insert(out.end(), fingers.begin(), fingers.end());
    out.insert(out.end(), grip_vel.begin(), grip_vel.end());
    out.insert(out.end(), finger_vel.begin(), finger_vel.end());
    return out;
  }
  const std::vector<Label> object = {
      {"object_pos.x", "object (site object0) position x, world frame", "m"},
      {"object_pos.y", "object position y", "m"},
      {"object_pos.z", "object position z", "m"},
      {"object_rel_pos.x", "object minus gripper position x", "m"},
      {"object_rel_pos.y", "object minus gripper position y", "m"},
      {"object_rel_pos.z", "object minus gripper position z", "m"}};
  const std::vector<Label> rot = {
      {"object_rot.x", "object Euler angle x (rotations.mat2euler of the site matrix)", "rad"},
      {"object_rot.y", "object Euler angle y", "rad"},
      {"object_rot.z", "object Euler angle z", "rad"},
      {"object_velp.x", "object linear velocity minus gripper linear velocity x, times dt",
       "m/step"},
      {"object_velp.y", "object minus gripper linear velocity y, times dt", "m/step"},
      {"object_velp.z", "object minus gripper linear velocity z, times dt", "m/step"},
      {"object_velr.x", "object angular velocity x (world axes, absolute) times dt", "rad/step"},
      {"object_velr.y", "object angular velocity y times dt", "rad/step"},
      {"object_velr.z", "object angular velocity z times dt", "rad/step"}};
  out.insert(out.end(), object.begin(), object.end());
  out.insert(out.end(), fingers.begin(), fingers.end());
  out.insert(out.end(), rot.begin(), rot.end());
  out.insert(out.end(), grip_vel.begin(), grip_vel.end());
  out.insert(out.end(), finger_vel.begin(), finger_vel.end());
  return out;
}

const ObservationLabel* FindObservationLabel(bool has_object, int index) {
  static const std::vector<ObservationLabel> reach = ObservationLabels(false);
  static const std::vector<ObservationLabel> object = ObservationLabels(true);
  const std::vector<ObservationLabel>& labels = has_object ? object : reach;
  if (index < 0 || index >= static_cast<int>(labels.size())) return nullptr;
  return &labels[index];
}

}  // namespace fetchscope
