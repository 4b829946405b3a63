#include "render/view.h"

#include <cmath>

#include "base/errors.h"
#include "render/frame_limits.h"

namespace fetchscope {

void CheckRenderFrame(const RenderOptions& options) {
  const FrameDims frame = FrameSize(options);  // too large for memory: refused before any work
  CheckFrameSize(options.width, options.height, static_cast<int>(options.cameras.size()),
                 frame.width, frame.height);
}

GpuChoice ResolveGpuChoice(const ViewSetup& view) {
  const GpuSpec& spec = view.gpu;
  if (spec.kind == GpuSpec::Kind::kAuto || view.backend == GlBackend::kOsmesa) {
    return GpuChoice{{}, "auto"};
  }
  EglDeviceList list;
  try {
    list = ListEglDevices();
  } catch (const RunError& e) {
    if (spec.soft) return GpuChoice{{}, "auto (" + spec.text + ", but " + e.what() + ")"};
    throw RunError(spec.source + " " + spec.text + " needs EGL: " + e.what());
  }
  return ChooseGpus(spec, list);
}

std::unique_ptr<GlContext> CreateViewContext(GlBackend backend, const GpuChoice& choice,
                                             int worker) {
  const int device = choice.devices.empty() ? -1 : choice.devices[worker % choice.devices.size()];
  auto gl = CreateGlContext(backend, device);
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
