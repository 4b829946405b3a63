#include "cli/view_options.h"

#include <algorithm>
#include <cstdio>
#include <iterator>
#include <set>
#include <string>
#include <vector>

#include "base/errors.h"
#include "base/suggest.h"
#include "render/camera.h"
#include "render/gl_context.h"
#include "render/gpu_select.h"
#include "render/overlay.h"

namespace fetchscope::cli {
namespace {

std::string FormatG(double value) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%g", value);
  return buf;
}

}  // namespace

HudPosition ParseHudPosition(const std::string& text) {
  if (text == "top-left") return HudPosition::kTopLeft;
  if (text == "top-right") return HudPosition::kTopRight;
  if (text == "bottom-left") return HudPosition::kBottomLeft;
  if (text == "bottom-right") return HudPosition::kBottomRight;
  throw UsageError("--hud-position '" + text +
                   "' is not known; accepted: top-left, top-right, bottom-left, bottom-right");
}

double CheckHudOpacity(double opacity) {
  if (!(opacity >= 0.0 && opacity <= 1.0)) {
    throw UsageError("--hud-opacity " + FormatG(opacity) +
                     " is out of range; accepted: 0 (no box) .. 1 (opaque box)");
  }
  return opacity;
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

RenderOptions ResolveRenderOptions(const ViewOptions& view, const mjModel* model) {
  RenderOptions options;
  options.width = view.width;
  options.height = view.height;
  options.cameras = ParseCameraList(view.camera, model);
  options.overlays = ParseOverlays(view.overlay);
  options.msaa_samples = ParseMsaa(view.msaa);
  options.readback = ParseReadback(view.readback);
  options.hud_position = ParseHudPosition(view.hud_position);
  options.hud_opacity = CheckHudOpacity(view.hud_opacity);
  CheckRenderFrame(options);
  return options;
}

ViewSetup ResolveGlView(const ViewOptions& view) {
  ViewSetup setup;
  setup.backend = ResolveGlBackend(view.backend);
  setup.gpu = EffectiveGpuSpec(view.gpu);
  return setup;
}

ViewSetup ResolveView(const ViewOptions& view, const mjModel* model) {
  const RenderOptions render = ResolveRenderOptions(view, model);
  ViewSetup setup = ResolveGlView(view);
  setup.render = render;
  return setup;
}

std::vector<const VideoFormat*> ParseVideoFormats(const std::string& list) {
  std::vector<std::string> known;
  for (const VideoFormat& format : VideoFormats()) known.emplace_back(format.name);
  std::vector<const VideoFormat*> formats;
  for (const std::string& entry : SplitCommaList(list)) {  // "mp4, gif" as "mp4,gif"
    const VideoFormat* row = FindVideoFormat(entry);
    if (row == nullptr) {
      throw UsageError("unknown --format '" + entry + "' in '" + list + "'" +
                       DidYouMean(entry, known) + ": accepted a comma list of " +
                       VideoFormatList());
    }
    if (std::find(formats.begin(), formats.end(), row) != formats.end()) {
      throw UsageError("--format '" + list + "' names " + entry + " twice: give each format once");
    }
    formats.push_back(row);
  }
  return formats;
}

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
                  "failure), ghost (record --from DATASET: the dataset's own achieved goal, a "
                  "translucent violet sphere; on with achieved); or all, or none. Spaces after "
                  "the commas are fine")
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
                  "Opacity of the black box behind the HUD and tile labels: 0 (none) .. 1; below "
                  "0.5 their text gets a black outline")
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

std::vector<Layer> ParseLayers(const std::string& list, const std::string& option) {
  const std::vector<std::string> names = {"rgb", "depth", "segmentation"};
  std::vector<Layer> layers;
  std::set<std::string> seen;
  for (const std::string& token : SplitCommaList(list)) {
    if (token.empty()) {
      throw UsageError(option + " '" + list +
                       "' has an empty entry; use a comma list of rgb, depth, segmentation");
    }
    if (std::find(names.begin(), names.end(), token) == names.end()) {
      throw UsageError(option + ": unknown layer '" + token + "'" + DidYouMean(token, names) +
                       "; use a comma list of rgb, depth, segmentation");
    }
    if (!seen.insert(token).second) {
      throw UsageError(option + " names '" + token + "' twice; each layer once");
    }
    layers.push_back(token == "rgb"     ? Layer::kRgb
                     : token == "depth" ? Layer::kDepth
                                        : Layer::kSegmentation);
  }
  return layers;
}

std::vector<Layer> ParseRecordLayers(const std::string& list) {
  std::vector<Layer> extra;
  for (Layer layer : ParseLayers(list)) {
    if (layer != Layer::kRgb) extra.push_back(layer);
  }
  return extra;
}

}  // namespace fetchscope::cli
