#include "inspect/grasp_probe.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <string>

#include "render/view.h"
#include "src/observation_layout.h"

namespace fetchscope {
namespace {

using nlohmann::json;

std::array<double, 3> Slice3(const Observation& obs, const char* name) {
  const int at = FindObservationSlice(true, name)->first;
  return {obs.observation[at], obs.observation[at + 1], obs.observation[at + 2]};
}

double Distance(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                   (a[2] - b[2]) * (a[2] - b[2]));
}

// A step towards `target` (proportional, clipped to the unit box) with gripper command `grip`.
Action Towards(const std::array<double, 3>& grip_pos, const std::array<double, 3>& target,
               double grip) {
  Action a;
  for (int k = 0; k < 3; ++k) a.value[k] = std::clamp(10.0 * (target[k] - grip_pos[k]), -1.0, 1.0);
  a.value[3] = grip;
  return a;
}

}  // namespace

json GraspProbe(FetchEnv& env, uint64_t seed, Renderer* renderer, std::vector<SheetTile>* tiles) {
  const EnvSpec& spec = env.spec();
  if (!spec.has_object) {
    return {{"done", false}, {"why", spec.id + " has no object: there is nothing to grasp"}};
  }
  if (spec.block_gripper) {
    return {{"done", false},
            {"why", spec.id + " blocks the gripper (block_gripper): a[3] does not move the "
                              "fingers, so there is no grasp to probe; FetchPickAndPlace has one"}};
  }
  Observation obs = env.Reset(seed);
  int steps = 0;
  const auto step = [&](const Action& a) {
    obs = env.Step(a).obs;
    ++steps;
  };
  // 1. above the object, fingers open; 2. down to it; 3. close, holding the grip where it is
  int approach = 0, descend = 0;
  for (; approach < kGraspApproachSteps; ++approach) {
    std::array<double, 3> above = Slice3(obs, "object_pos");
    above[2] += 0.08;
    if (Distance(Slice3(obs, "grip_pos"), above) < 0.01) break;
    step(Towards(Slice3(obs, "grip_pos"), above, 1.0));
  }
  for (; descend < kGraspDescendSteps; ++descend) {
    const std::array<double, 3> object = Slice3(obs, "object_pos");
    if (Distance(Slice3(obs, "grip_pos"), object) < 0.008) break;
    step(Towards(Slice3(obs, "grip_pos"), object, 1.0));
  }
  const std::array<double, 3> hold = Slice3(obs, "grip_pos");
  for (int i = 0; i < kGraspCloseSteps; ++i) step(Towards(Slice3(obs, "grip_pos"), hold, -1.0));
  const ContactSignals closed = ReadContacts(env.model(), env.data(), env.contact_bodies());
  std::set<std::string> touching;
  for (const Contact& c : closed.contacts) {
    if (c.pair != ContactPair::kFingerObject) continue;
    touching.insert(c.body1 == "object0" ? c.body2 : c.body1);
  }
  const auto tile = [&](const char* label, const Action& a) {
    if (!renderer || !tiles) return;
    FrameInfo info;
    info.step = steps;
    info.has_action = true;
    info.action = a.value;
    info.goal = obs.desired_goal;
    info.achieved = obs.achieved_goal;
    info.distance_threshold = spec.distance_threshold;
    info.title = spec.id;
    SheetTile t;
    t.width = renderer->width();
    t.height = renderer->height();
    t.rgb.resize(static_cast<size_t>(t.width) * t.height * 3);
    renderer->Render(env.data(), info, t.rgb.data());
    t.label = label;
    tiles->push_back(std::move(t));
  };
  Action close;
  close.value = {0, 0, 0, -1};
  tile("grasp: closed above the object", close);
  // 4. +z with the fingers closed: does the object come along?
  const double grip_before = Slice3(obs, "grip_pos")[2];
  const double object_before = Slice3(obs, "object_pos")[2];
  Action lift;
  lift.value = {0, 0, 1, -1};
  for (int i = 0; i < kGraspLiftSteps; ++i) step(lift);
  tile("grasp: then +z", lift);
  const double grip_rise = Slice3(obs, "grip_pos")[2] - grip_before;
  const double object_rise = Slice3(obs, "object_pos")[2] - object_before;
  const bool lifts = object_rise > 0.01 && object_rise > 0.5 * grip_rise;
  char answer[320];
  std::snprintf(answer, sizeof(answer),
                "after closing above the object %s touch it (left %.0f N, right %.0f N%s); with "
                "+z the grip rose %.3f m and the object %.3f m: %s",
                touching.empty()       ? "no finger does"
                : touching.size() == 2 ? "both fingers"
                                       : "one finger only",
                closed.left_finger_force, closed.right_finger_force,
                closed.grasped() ? ", grasped" : "", grip_rise, object_rise,
                lifts ? "it lifts" : "it does not lift");
  json fingers = json::array();
  for (const std::string& f : touching) fingers.push_back(f);
  return {{"done", true},
          {"steps",
           {{"approach", approach},
            {"descend", descend},
            {"close", kGraspCloseSteps},
            {"lift", kGraspLiftSteps}}},
          {"after_close",
           {{"left_finger_force", closed.left_finger_force},
            {"right_finger_force", closed.right_finger_force},
            {"fingers_touching", fingers},
            {"grasped", closed.grasped()},
            {"object_on_table", closed.object_on_table}}},
          {"lift", {{"grip_rise", grip_rise}, {"object_rise", object_rise}, {"lifts", lifts}}},
          {"answer", answer}};
}

}  // namespace fetchscope
