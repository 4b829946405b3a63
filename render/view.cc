#include "render/view.h"

#include <cmath>
#include <cstdlib>
#include <string>

#include "base/errors.h"
#include "render/frame_limits.h"

namespace fetchscope {

int ParseMsaa(const std::string& value) {
  if (value == "auto") return kMsaaAuto;
  for (const char* accepted : kMsaaValues) {
    if (value == accepted) return std::stoi(value);
  }
  std::string list;
  for (const char* accepted : kMsaaValues) list += std::string(list.empty() ? "" : ", ") + accepted;
  throw UsageError("--msaa '" + value + "' is not accepted; use " + list);
}

Readback ParseReadback(const std::string& value) {
  if (value == "auto") return Readback::kAuto;
  if (value == "sync") return Readback::kSync;
  if (value == "async") return Readback::kAsync;
  throw UsageError("--readback '" + value + "' is not accepted; use auto, sync or async");
}

RenderOptions MakeRenderOptions(const ViewOptions& view, const mjModel* model) {
  RenderOptions options;
  options.width = view.width;
  options.height = view.height;
  options.cameras = ParseCameraList(view.camera, model);
  options.overlays = ParseOverlays(view.overlay);
  options.msaa_samples = ParseMsaa(view.msaa);
  options.readback = ParseReadback(view.readback);
  options.hud_position = ParseHudPosition(view.hud_position);
  options.hud_opacity = CheckHudOpacity(view.hud_opacity);
  const FrameDims frame = FrameSize(options);  // too large for memory: refused before any work
  CheckFrameSize(view.width, view.height, static_cast<int>(options.cameras.size()), frame.width,
                 frame.height);
  return options;
}

GpuChoice ResolveGpuChoice(const ViewOptions& view) {
  const GpuSpec spec = EffectiveGpuSpec(view.gpu);
  std::string backend = view.backend;
  if (backend.empty()) {
    const char* env = std::getenv("MUJOCO_GL");
    backend = env && *env ? env : "auto";
  }
  if (spec.kind == GpuSpec::Kind::kAuto || backend == "osmesa") return GpuChoice{{}, "auto"};
  EglDeviceList list;
  try {
    list = ListEglDevices();
  } catch (const RunError& e) {
    if (spec.soft) return GpuChoice{{}, "auto (" + spec.text + ", but " + e.what() + ")"};
    throw RunError(spec.source + " " + spec.text + " needs EGL: " + e.what());
  }
  return ChooseGpus(spec, list);
}

std::unique_ptr<GlContext> CreateViewContext(const ViewOptions& view, const GpuChoice& choice,
                                             int worker) {
  const int device = choice.devices.empty() ? -1 : choice.devices[worker % choice.devices.size()];
  auto gl = CreateGlContext(view.backend, device);
  gl->set_selection(gl->info().backend == "egl" ? choice.reason : "osmesa (no device)");
  return gl;
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
  if (record.past_time_limit) info.past_time_limit = env.spec().max_episode_steps;
  return info;
}

}  // namespace fetchscope
