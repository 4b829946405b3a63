#include "inspect/anatomy_content.h"

#include <cstdio>
#include <string>

#include "base/number_format.h"

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

std::string Fixed(double v, int digits) {
  return PictureNumber(("%." + std::to_string(digits) + "f").c_str(), v);  // never "-0.00"
}

// The parts both panels have: grip_pos with the axes that a[0:3] move it along, the fingers with
// their width and the a[3] arrows, the goal and its success shell (`view_up`: the camera's up,
// so that the radius line ends on the shell's outline). `arrow_scale`: how many times 0.05 m
// (one unit of a[0:3]) the arrows are drawn.
CardContent CommonContent(const FetchEnv& env, const StepRecord& s, const Vec3& view_up,
                          int arrow_scale, const ObservationSliceFn& slice) {
  const EnvSpec& spec = env.spec();
  const bool obj = spec.has_object;
  const auto& o = s.obs.observation;
  const Vec3 grip = {o[0], o[1], o[2]};
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
  const int r_index = obj ? 9 : 3;  // obs[r_index] r, obs[r_index + 1] l
  const double width = o[r_index] + o[r_index + 1];

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
  const std::string r = "obs[" + std::to_string(r_index) + "]",
                    l = "obs[" + std::to_string(r_index + 1) + "]";
  c.labels = {
      {"grip_pos " + slice(obj, "grip_pos") + (obj ? "" : "\n= achieved_goal"), {grip}, kCyan, 200},
      {"x obs[0] \xc2\xb7 a[0]", {ax}, kRed, 60, false},
      {"y obs[1] \xc2\xb7 a[1]", {ay}, kGreen, -30, false},
      {"z obs[2] \xc2\xb7 a[2]", {az}, kBlue, -30, false},

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

CardContent ReachContent(const FetchEnv& env, const StepRecord& s, const Vec3& view_up,
                         const ObservationSliceFn& slice) {
  CardContent c = CommonContent(env, s, view_up, 5, slice);
  c.footer = "obs[5:8] grip_velp  obs[8:10] finger vel\n(velocities x dt: per step)";
  return c;
}

CardContent PushContent(const FetchEnv& env, const StepRecord& s, const Vec3& view_up,
                        const ObservationSliceFn& slice) {
  CardContent c = CommonContent(env, s, view_up, 3, slice);
  const auto& o = s.obs.observation;
  const Vec3 grip = {o[0], o[1], o[2]};
  const Vec3 object = {o[3], o[4], o[5]};
  c.spheres.push_back({object, 0.036, kYellow, 0.3f});
  c.markers.insert(c.markers.begin(),
                   {"object_rel_pos", CardMarkerKind::kArrow, grip, object, kOrange});
  // after grip_pos and its axes
  c.labels.insert(
      c.labels.begin() + 4,
      {{"object_pos " + slice(true, "object_pos") + "\n= achieved_goal", {object}, kYellow, 135},
       {"object_rel_pos " + slice(true, "object_rel_pos") + "\n= object - grip",
        {Mid(grip, object)},
        kOrange,
        -135,
        false}});
  c.points.push_back(object);
  c.footer =
      "obs[11:14] object_rot  obs[14:17] object_velp\n"
      "obs[17:20] object_velr  obs[20:23] grip_velp\n"
      "obs[23:25] finger vel  (velocities x dt: per step)";
  return c;
}

}  // namespace

CardContent PanelContentFor(const FetchEnv& env, const StepRecord& reset, const Vec3& view_up,
                            const ObservationSliceFn& slice) {
  return env.spec().has_object ? PushContent(env, reset, view_up, slice)
                               : ReachContent(env, reset, view_up, slice);
}

}  // namespace fetchscope
