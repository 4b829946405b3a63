#include "cli/render_common.h"

#include <cmath>
#include <vector>

#include "src/errors.h"

namespace fetchscope::cli {

void AddViewOptions(CLI::App* sub, ViewOptions* o) {
  sub->add_option("--camera", o->camera,
                  "default (Gymnasium's view), a camera named in the model (see list-cameras), "
                  "free:lookat=x,y,z,distance=d,azimuth=a,elevation=e, track (follows the "
                  "gripper), or several joined by commas to tile them")
      ->capture_default_str();
  sub->add_option("--overlay", o->overlay,
                  "Comma list of goal, achieved, hud, action, trail; or none")
      ->capture_default_str();
  sub->add_option("--width", o->width, "Frame width in pixels")->capture_default_str()->check(CLI::Range(1, 8192));
  sub->add_option("--height", o->height, "Frame height in pixels")->capture_default_str()->check(CLI::Range(1, 8192));
  sub->add_option("--backend", o->backend,
                  "auto (EGL, then OSMesa), egl or osmesa; default: $MUJOCO_GL, else auto");
  sub->add_option("--msaa", o->msaa,
                  "Multisample anti-aliasing samples: auto, 0, 1, 2, 4, 8 or 16. auto: the "
                  "model's 4 (as Gymnasium renders) on hardware GL, 0 on a software rasterizer "
                  "(llvmpipe, softpipe, swrast), where multisampling is about half the frame time")
      ->capture_default_str()
      ->check(CLI::IsMember(std::vector<std::string>(std::begin(kMsaaValues), std::end(kMsaaValues))));
  sub->add_option("--gpu", o->gpu, "EGL device index (default: $MUJOCO_EGL_DEVICE_ID, else the first)")
      ->check(CLI::Range(0, 4096));
}

int ParseMsaa(const std::string& value) {
  if (value == "auto") return kMsaaAuto;
  for (const char* accepted : kMsaaValues) {
    if (value == accepted) return std::stoi(value);
  }
  std::string list;
  for (const char* accepted : kMsaaValues) list += std::string(list.empty() ? "" : ", ") + accepted;
  throw UsageError("--msaa '" + value + "' is not accepted; use " + list);
}

RenderOptions MakeRenderOptions(const ViewOptions& view, const mjModel* model) {
  RenderOptions options;
  options.width = view.width;
  options.height = view.height;
  options.cameras = ParseCameraList(view.camera, model);
  options.overlays = ParseOverlays(view.overlay);
  options.msaa_samples = ParseMsaa(view.msaa);
  return options;
}

FrameInfo MakeFrameInfo(const FetchEnv& env, const StepRecord& record) {
  FrameInfo info;
  info.step = record.t;
  info.reward = record.reward ? *record.reward : NAN;
  const auto& a = record.obs.achieved_goal;
  const auto& g = record.obs.desired_goal;
  info.distance = GoalDistance(a, g);
  info.success = record.is_success;
  info.has_action = record.action.has_value();
  if (record.action) info.action = record.action->value;
  info.goal = g;
  info.achieved = a;
  info.distance_threshold = env.spec().distance_threshold;
  info.title = env.spec().id;
  return info;
}

}  // namespace fetchscope::cli
