#include "cli/render_common.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <vector>

#include "base/errors.h"
#include "base/suggest.h"

namespace fetchscope::cli {

void AddViewOptions(CLI::App* sub, ViewOptions* o) {
  sub->add_option("--camera", o->camera,
                  "default (Gymnasium's view), a camera named in the model (see list-cameras), "
                  "free:lookat=x,y,z,distance=d,azimuth=a,elevation=e, track (follows the "
                  "gripper), or several joined by commas to tile them")
      ->capture_default_str();
  sub->add_option("--overlay", o->overlay,
                  "Comma list of goal, achieved, hud, action, trail, labels (camera names on "
                  "tiled views; on by default), hindsight (record only: the goals HER's future "
                  "strategy relabels each transition with, green = relabelled success, red = "
                  "failure); or all, or none. Spaces after the commas are fine")
      ->capture_default_str();
  sub->add_option("--width", o->width,
                  "Width in pixels of each camera's view: N tiled cameras make a frame N views "
                  "wide (a near-square grid from 4 on)")
      ->capture_default_str()
      ->check(CLI::Range(1, 8192));
  sub->add_option("--height", o->height, "Height in pixels of each camera's view")
      ->capture_default_str()
      ->check(CLI::Range(1, 8192));
  sub->add_option("--hud-position", o->hud_position,
                  "Corner of the HUD: top-left, top-right, bottom-left or bottom-right (within "
                  "the tile at that corner). The HUD text grows with the view; views smaller "
                  "than 320x240 pixels get no HUD")
      ->capture_default_str();
  sub->add_option("--hud-opacity", o->hud_opacity,
                  "Opacity of the black box behind the HUD and tile labels: 0 (none) .. 1")
      ->capture_default_str();
  sub->add_option("--backend", o->backend,
                  "auto (EGL, then OSMesa), egl or osmesa; default: $MUJOCO_GL, else auto");
  sub->add_option("--msaa", o->msaa,
                  "Multisample anti-aliasing samples: auto, 0, 1, 2, 4, 8 or 16. auto: the "
                  "model's 4 (as Gymnasium renders) on hardware GL, 0 on a software rasterizer "
                  "(llvmpipe, softpipe, swrast), where multisampling is about half the frame time")
      ->capture_default_str()
      ->check(
          CLI::IsMember(std::vector<std::string>(std::begin(kMsaaValues), std::end(kMsaaValues))));
  sub->add_option("--readback", o->readback,
                  "How frames come back from the GPU: auto, sync or async. async reads through "
                  "pixel buffer objects, 3 frames in flight, so the GPU draws the next frame "
                  "while one comes back (same pixels); auto: async on hardware GL, sync on a "
                  "software rasterizer")
      ->capture_default_str()
      ->check(CLI::IsMember(
          std::vector<std::string>(std::begin(kReadbackValues), std::end(kReadbackValues))));
  sub->add_option("--gpu", o->gpu,
                  std::string("GPU(s) to render on: ") + kGpuForms +
                      ". Default: $MUJOCO_EGL_DEVICE_ID (EGL index), else cuda:0 when "
                      "$CUDA_VISIBLE_DEVICES is set, else the first GPU. Workers are spread "
                      "round-robin over the devices named")
      ->check([](const std::string& text) -> std::string {
        try {
          ParseGpuSpec(text);
        } catch (const UsageError& e) {
          return e.what();
        }
        return "";
      });
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
  return info;
}

std::vector<Layer> ParseLayers(const std::string& list) {
  const std::vector<std::string> names = {"rgb", "depth", "segmentation"};
  std::vector<Layer> layers;
  std::set<std::string> seen;
  for (const std::string& token : SplitCommaList(list)) {
    if (token.empty()) {
      throw UsageError("--layers '" + list +
                       "' has an empty entry; use a comma list of rgb, depth, segmentation");
    }
    if (std::find(names.begin(), names.end(), token) == names.end()) {
      throw UsageError("--layers: unknown layer '" + token + "'" + DidYouMean(token, names) +
                       "; use a comma list of rgb, depth, segmentation");
    }
    if (!seen.insert(token).second) {
      throw UsageError("--layers names '" + token + "' twice; each layer once");
    }
    layers.push_back(token == "rgb"     ? Layer::kRgb
                     : token == "depth" ? Layer::kDepth
                                        : Layer::kSegmentation);
  }
  return layers;
}

nlohmann::json SegmentObjectJson(const SegmentObject& o) {
  char hex[8];
  std::snprintf(hex, sizeof(hex), "#%02x%02x%02x", o.color[0], o.color[1], o.color[2]);
  return {{"color", hex},
          {"rgb", {o.color[0], o.color[1], o.color[2]}},
          {"body", o.body},
          {"geoms", o.geoms},
          {"site", o.site.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.site)},
          {"pixels", o.pixels}};
}

}  // namespace fetchscope::cli
