#include "inspect/anatomy_content.h"

#include <cstdio>
#include <string>

#include "base/number_format.h"
#include "src/observation_layout.h"

namespace fetchscope {
namespace {

// marker and label colours (labels: text on a dark box)
constexpr Rgb kRed{255, 80, 80}, kGreen{60, 235, 60}, kBlue{90, 150, 255}, kYellow{255, 220, 60},
    kOrange{255, 150, 30}, kCyan{60, 225, 255}, kMagenta{255, 100, 255}, kGoalRed{255, 110, 110};

// Where body `name` is in `env`'s current state; `fallback` when the model lacks it.
Vec3 BodyPosition(const FetchEnv& env, const char* name, const Vec3& fallback) {
  const int id = mj_name2id(env.model(), mjOBJ_BODY, name);
  const mjtNum* x = env.data()->xpos;
  return id < 0 ? fallback : Vec3{x[3 * id], x[3 * id + 1], x[3 * id + 2]};
}

// "obs[5]": observation component `name` ("object_pos.z") where the layout puts it.
std::string Obs(bool has_object, const char* name) {
  return "obs[" + std::to_string(ObservationIndex(has_object, name)) + "]";
}

// The first of three consecutive components from slice `slice` of `o`, as a point.
Vec3 Point3(const std::vector<double>& o, bool has_object, const char* slice) {
  const size_t i = static_cast<size_t>(FindObservationSlice(has_object, slice)->first);
  return {o[i], o[i + 1], o[i + 2]};
}

std::string Fixed(double v, int digits) {
  return PictureNumber(("%." + std::to_string(digits) + "f").c_str(), v);  // never "-0.00"
}

// The parts both panels have: grip_pos with the axes that a[0:3] move it along, the fingers with
// their width and the a[3] arrows, the goal and its success shell (`view_up`: the camera's up,
// so that the radius line ends on the shell's outline). `arrow_scale`: how many times 0.05 m
// (one unit of a[0:3]) the arrows are drawn.
CardContent CommonContent(const FetchEnv& env, const StepRecord& s, const Vec3& view_up,
                          int arrow_scale) {
  const EnvSpec& spec = env.spec();
  const bool obj = spec.has_object;
  const auto& o = s.obs.observation;
  const Vec3 grip = Point3(o, obj, "grip_pos");
  const Vec3 goal = s.obs.desired_goal;
  const Vec3 right = BodyPosition(env, "robot0:r_gripper_finger_link", grip);
  const Vec3 left = BodyPosition(env, "robot0:l_gripper_finger_link", grip);
  const double threshold = spec.distance_threshold;
  const double arrow = 0.05 * arrow_scale;
  const Vec3 ax = Add(grip, {arrow, 0, 0}), ay = Add(grip, {0, arrow, 0}),
             az = Add(grip, {0, 0, arrow});
  // the finger bracket hangs just below the finger tips (3.85 cm below the finger bodies'
  // origins); a[3] > 0 would move each finger outward along the line between them
  const Vec3 drop = {0, 0, -0.047};
  const Vec3 left_low = Add(left, drop), right_low = Add(right, drop);
  const Vec3 open = Unit(Add(left, right, -1.0));
  const Vec3 left_open = Add(left_low, open, 0.04), right_open = Add(right_low, open, -0.04);
  const Vec3 shell_edge = Add(goal, view_up, threshold);
  const FingerIndices fingers = FingerPositionIndices(obj);
  const double width = o[fingers.right] + o[fingers.left];

  CardContent c;
  c.spheres = {{goal, threshold, kGoalRed, 0.25f}};
  c.detail_markers = {
      {"finger r extension", CardMarkerKind::kLine, right, right_low, kYellow, true},
      {"finger l extension", CardMarkerKind::kLine, left, left_low, kYellow, true},
      {"finger width", CardMarkerKind::kBracket, right_low, left_low, kYellow},
      {"a[3] r", CardMarkerKind::kArrow, right_low, right_open, kMagenta},
      {"a[3] l", CardMarkerKind::kArrow, left_low, left_open, kMagenta},
  };
  // fingers in the upper half, their labels below them
  c.detail_at = Add(Mid(left, right), {0, 0, -0.075});
  c.detail_distance = 0.15;
  c.detail_across = open;
  c.detail_keep = {right, left, right_low, left_low};
  c.markers = {
      {"shell radius", CardMarkerKind::kLine, goal, shell_edge, kCardWhite},
      {"a[0] x", CardMarkerKind::kArrow, grip, ax, kRed},
      {"a[1] y", CardMarkerKind::kArrow, grip, ay, kGreen},
      {"a[2] z", CardMarkerKind::kArrow, grip, az, kBlue},
  };
  const std::string r = Obs(obj, "gripper_state.right"), l = Obs(obj, "gripper_state.left");
  c.labels = {
      {"grip_pos " + ObservationSliceText(obj, "grip_pos") + (obj ? "" : "\n= achieved_goal"),
       {grip},
       kCyan,
       200},
      {"x " + Obs(obj, "grip_pos.x") + " \xc2\xb7 a[0]", {ax}, kRed, 60, false},
      {"y " + Obs(obj, "grip_pos.y") + " \xc2\xb7 a[1]", {ay}, kGreen, -30, false},
      {"z " + Obs(obj, "grip_pos.z") + " \xc2\xb7 a[2]", {az}, kBlue, -30, false},

      {"desired_goal (goal)", {goal}, kGoalRed, 60},
      {"success shell\nr = " + Fixed(threshold, 2) + " m", {shell_edge}, kCardWhite, -45},
  };
  c.detail_labels = {
      {"finger width\n" + r + " r + " + l + " l\n= " + Fixed(width, 3) + " m" +
           (width < 0.0005 ? " (closed)" : ""),
       {Mid(left_low, right_low)},
       kYellow,
       90,
       false},
      {std::string("a[3] > 0 opens") + (spec.block_gripper ? "\n(blocked: ignored)" : ""),
       {right_open, left_open},
       kMagenta,
       90,
       false},
  };
  c.points = {grip, goal, ax, ay, az, left_low, right_low, shell_edge};
  c.action_note = "a[0:3]: the target moves 0.05 m per unit\nalong x, y, z (arrows: a = +1, x" +
                  std::to_string(arrow_scale) + ")";
  return c;
}

// "obs[5:8] grip_velp": the slice's indices and a name for it
std::string Named(bool has_object, const char* slice, const char* name) {
  return ObservationSliceText(has_object, slice) + " " + name;
}

CardContent ReachContent(const FetchEnv& env, const StepRecord& s, const Vec3& view_up) {
  CardContent c = CommonContent(env, s, view_up, 5);
  c.footer = Named(false, "grip_velp", "grip_velp") + "  " +
             Named(false, "gripper_vel", "finger vel") + "\n(velocities x dt: per step)";
  return c;
}

CardContent PushContent(const FetchEnv& env, const StepRecord& s, const Vec3& view_up) {
  CardContent c = CommonContent(env, s, view_up, 3);
  const auto& o = s.obs.observation;
  const Vec3 grip = Point3(o, true, "grip_pos");
  const Vec3 object = Point3(o, true, "object_pos");
  c.spheres.push_back({object, 0.036, kYellow, 0.3f});
  c.markers.insert(c.markers.begin(),
                   {"object_rel_pos", CardMarkerKind::kArrow, grip, object, kOrange});
  // after grip_pos and its axes
  c.labels.insert(
      c.labels.begin() + 4,
      {{"object_pos " + ObservationSliceText(true, "object_pos") + "\n= achieved_goal",
        {object},
        kYellow,
        135},
       {"object_rel_pos " + ObservationSliceText(true, "object_rel_pos") + "\n= object - grip",
        {Mid(grip, object)},
        kOrange,
        -135,
        false}});
  c.points.push_back(object);
  c.footer = Named(true, "object_rot", "object_rot") + "  " +
             Named(true, "object_velp", "object_velp") + "\n" +
             Named(true, "object_velr", "object_velr") + "  " +
             Named(true, "grip_velp", "grip_velp") + "\n" +
             Named(true, "gripper_vel", "finger vel") + "  (velocities x dt: per step)";
  return c;
}

}  // namespace

CardContent PanelContentFor(const FetchEnv& env, const StepRecord& reset, const Vec3& view_up) {
  return env.spec().has_object ? PushContent(env, reset, view_up)
                               : ReachContent(env, reset, view_up);
}

}  // namespace fetchscope
