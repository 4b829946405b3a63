#include "src/scripted_policy.h"

#include <algorithm>
#include <cmath>

#include "src/observation_layout.h"
#include "src/policy.h"

namespace fetchscope {
namespace {

using Vec3 = std::array<double, 3>;

constexpr double kStep = 0.05;  // m of mocap displacement per unit action

Vec3 Sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double NormXY(const Vec3& v) { return std::hypot(v[0], v[1]); }
double Norm(const Vec3& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

// An action that moves the gripper towards `target` at most `speed` (in action units).
Action Toward(const Vec3& grip, const Vec3& target, double gripper, double speed = 1.0) {
  Action a;
  Vec3 delta = Sub(target, grip);
  for (int i = 0; i < 3; ++i) a.value[i] = std::clamp(delta[i] / kStep, -speed, speed);
  a.value[3] = gripper;
  return a;
}

Vec3 At(const std::vector<double>& o, int i) { return {o[i], o[i + 1], o[i + 2]}; }

// Where the policies read the observation (src/observation_layout.h), looked up once.
struct Where {
  int reach_grip = FindObservationSlice(false, "grip_pos")->first;
  int grip = FindObservationSlice(true, "grip_pos")->first;
  int object = FindObservationSlice(true, "object_pos")->first;
  FingerIndices fingers = FingerPositionIndices(true);
};
const Where& Layout() {
  static const Where where;
  return where;
}

class ScriptedReach : public Policy {
 public:
  Action Act(const Observation& obs, int) override {
    return Toward(At(obs.observation, Layout().reach_grip), obs.desired_goal, 0.0);
  }
  std::string name() const override { return "scripted"; }
};

// Push and Slide: line up behind the object on the goal line, then drive through it.
class ScriptedPush : public Policy {
 public:
  ScriptedPush(bool slide, double threshold) : slide_(slide), threshold_(threshold) {}
  void BeginEpisode(int, const Observation&) override {
    phase_ = kLineUp;
    released_ = false;
    last_grip_ = {0, 0, 0};
  }
  Action Act(const Observation& obs, int) override {
    const Vec3 grip = At(obs.observation, Layout().grip);
    const Vec3 object = At(obs.observation, Layout().object);
    const Vec3 goal = obs.desired_goal;
    // Push: once the block is in the goal (is_success), stop there instead of pushing on
    if (!slide_ && Norm(Sub(obs.achieved_goal, goal)) < threshold_) return Toward(grip, grip, 0.0);
    Vec3 to_goal = Sub(goal, object);
    to_goal[2] = 0;
    const double dist = NormXY(to_goal);
    if (dist < 1e-6) return Toward(grip, grip, 0.0);
    const Vec3 dir = {to_goal[0] / dist, to_goal[1] / dist, 0};
    const double table_z = object[2];  // push at the object's centre height
    const double behind = 0.045;       // gripper centre behind the object centre
    const Vec3 contact = {object[0] - dir[0] * behind, object[1] - dir[1] * behind, table_z};
    // lateral error of the gripper from the goal line through the object
    const Vec3 rel = Sub(grip, object);
    const double along = rel[0] * dir[0] + rel[1] * dir[1];
    const double lateral = std::abs(rel[0] * dir[1] - rel[1] * dir[0]);

    // the arm cannot always reach the exact spot (far side of the table): accept a gripper
    // that has stopped within 3 cm of it
    const bool stuck = NormXY(Sub(grip, last_grip_)) < 0.002 && NormXY(Sub(grip, contact)) < 0.03;
    last_grip_ = grip;
    if (phase_ == kLineUp) {
      const Vec3 above = {contact[0], contact[1], table_z + 0.055};
      if (NormXY(Sub(grip, contact)) > 0.012 && !stuck) {
        // travel high so the gripper never sweeps the object off its line
        if (grip[2] < table_z + 0.04 && NormXY(Sub(grip, contact)) > 0.03) {
          return Toward(grip, {grip[0], grip[1], table_z + 0.06}, 0.0);
        }
        return Toward(grip, above, 0.0);
      }
      if (grip[2] > table_z + 0.01) return Toward(grip, contact, 0.0);
      phase_ = kDrive;
    }
    if (phase_ == kDrive && (lateral > 0.03 || along > -0.01)) {
      phase_ = kLineUp;  // lost the object: line up again
      return Toward(grip, {grip[0], grip[1], table_z + 0.07}, 0.0);
    }
    if (slide_) {
      // drive the puck along the line until its own speed would carry it to the goal
      // (sliding distance v^2 / (2 mu g)), then stop dead and let it slide
      const std::vector<double>& o = obs.observation;
      const double vx = (o[14] + o[20]) / kDt, vy = (o[15] + o[21]) / kDt;
      const double puck_speed = std::hypot(vx, vy);
      const double glide = puck_speed * puck_speed / (2 * kSlideFriction * 9.81);
      if (released_ || glide >= dist) {
        released_ = true;
        return Toward(grip, grip, 0.0);
      }
      const double speed =
          std::clamp(std::sqrt(2 * kSlideFriction * 9.81 * dist) / (kStep / kDt) * 1.3, 0.3, 1.0);
      Action a;
      a.value = {dir[0] * speed, dir[1] * speed, (table_z - 0.01 - grip[2]) / kStep, 0.0};
      return a;
    }
    // push: aim the gripper at the spot behind the goal, slowing down near it
    const Vec3 target = {goal[0] - dir[0] * behind, goal[1] - dir[1] * behind, table_z};
    const double speed = std::clamp(dist / 0.1, 0.15, 0.6);
    return Toward(grip, target, 0.0, speed);
  }
  std::string name() const override { return "scripted"; }

 private:
  enum Phase { kLineUp, kDrive };
  static constexpr double kDt = 0.04;            // s per env step
  static constexpr double kSlideFriction = 0.1;  // puck-table sliding friction, calibrated
  bool released_ = false;
  bool slide_;
  double threshold_;  // the env's distance_threshold
  Phase phase_ = kLineUp;
  Vec3 last_grip_{};
};

// PickAndPlace: open above the block, descend, close, lift and carry to the goal.
class ScriptedPickAndPlace : public Policy {
 public:
  void BeginEpisode(int, const Observation& obs) override {
    phase_ = kAbove;
    close_steps_ = 0;
    lifted_ = false;
    rest_z_ = obs.achieved_goal[2];  // the block resting on the table
  }
  Action Act(const Observation& obs, int) override {
    const Vec3 grip = At(obs.observation, Layout().grip);
    const Vec3 object = At(obs.observation, Layout().object);
    const Vec3 goal = obs.desired_goal;
    const double opening =
        obs.observation[Layout().fingers.right] + obs.observation[Layout().fingers.left];
    switch (phase_) {
      case kAbove: {
        const Vec3 above = {object[0], object[1], object[2] + 0.08};
        if (Norm(Sub(grip, above)) > 0.01 || opening < 0.08) return Toward(grip, above, 1.0);
        phase_ = kDescend;
        [[fallthrough]];
      }
      case kDescend: {
        const Vec3 at = {object[0], object[1], object[2] - 0.005};
        if (Norm(Sub(grip, at)) > 0.008) return Toward(grip, at, 1.0, 0.6);
        phase_ = kClose;
        [[fallthrough]];
      }
      case kClose:
        if (close_steps_++ < 4)
          return Toward(grip, {object[0], object[1], object[2] - 0.005}, -1.0);
        phase_ = kCarry;
        [[fallthrough]];
      case kCarry: {
        // lost the block (it is no longer between the fingers): start over
        if (Norm(Sub(object, grip)) > 0.04) {
          phase_ = kAbove;
          close_steps_ = 0;
          lifted_ = false;
          return Toward(grip, {grip[0], grip[1], grip[2] + 0.05}, 1.0);
        }
        // Lift to a carry height, travel there, and come down onto a goal on the table only
        // near it: the height the block travels at depends on the distance left alone, so it
        // never alternates between lifting and descending. (The old rule re-lifted whenever
        // the block dipped below a fixed 0.44 m while heading for a goal on the table: a 3 cm
        // sawtooth from step 15 to 25.)
        const double carry_z = rest_z_ + kCarryClearance;
        const double far = NormXY(Sub(goal, object));
        if (!lifted_ && object[2] >= carry_z - 0.01) lifted_ = true;
        if (!lifted_ && far > 0.02) return Toward(grip, {grip[0], grip[1], carry_z + 0.01}, -1.0);
        Vec3 target = goal;
        if (goal[2] < carry_z) {
          // from carry height at 6 cm and farther down to the goal's height at 1 cm
          const double blend = std::clamp((far - 0.01) / 0.05, 0.0, 1.0);
          target[2] = goal[2] + blend * (carry_z - goal[2]);
        }
        return Toward(grip, target, -1.0);
      }
    }
    return Toward(grip, grip, 0.0);
  }
  std::string name() const override { return "scripted"; }

 private:
  enum Phase { kAbove, kDescend, kClose, kCarry };
  static constexpr double kCarryClearance = 0.03;  // m above the resting block
  Phase phase_ = kAbove;
  int close_steps_ = 0;
  bool lifted_ = false;  // the block has reached carry height since the grasp
  double rest_z_ = 0.425;
};

}  // namespace

std::unique_ptr<Policy> MakeScriptedPolicy(const EnvSpec& env) {
  switch (env.task) {
    case Task::kReach:
      return std::make_unique<ScriptedReach>();
    case Task::kPush:
      return std::make_unique<ScriptedPush>(false, env.distance_threshold);
    case Task::kSlide:
      return std::make_unique<ScriptedPush>(true, env.distance_threshold);
    case Task::kPickAndPlace:
      return std::make_unique<ScriptedPickAndPlace>();
  }
  return nullptr;
}

}  // namespace fetchscope
