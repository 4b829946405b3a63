// Options and helpers shared by the subcommands that render (render, record, bench).
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <string>

#include "render/gpu_select.h"
#include "render/overlay.h"
#include "render/renderer.h"
#include "src/episode.h"
#include "src/fetch_env.h"

namespace fetchscope::cli {

/// --camera, --overlay, --width, --height, --backend, --gpu, --msaa.
struct ViewOptions {
  std::string camera = "default";                    ///< see ParseCameraList
  std::string overlay = "goal,achieved,hud,labels";  ///< see ParseOverlays
  int width = 480;                                   ///< pixels
  int height = 480;                                  ///< pixels
  std::string backend;                               ///< auto|egl|osmesa; empty: $MUJOCO_GL or auto
  std::string gpu;                        ///< see ParseGpuSpec; empty: from the environment
  std::string msaa = "auto";              ///< see ParseMsaa
  std::string readback = "auto";          ///< see ParseReadback
  std::string hud_position = "top-left";  ///< see ParseHudPosition
  double hud_opacity = 0.6;               ///< see CheckHudOpacity
};

/// The accepted --readback values, and RenderOptions::readback for one (UsageError otherwise).
inline constexpr const char* kReadbackValues[] = {"auto", "sync", "async"};
Readback ParseReadback(const std::string& value);

/// The accepted --msaa values, in the order the help and errors list them.
inline constexpr const char* kMsaaValues[] = {"auto", "0", "1", "2", "4", "8", "16"};

/// RenderOptions::msaa_samples for an --msaa value: "auto" (kMsaaAuto: the model's 4 on
/// hardware GL, 0 on a software rasterizer) or a sample count. Throws UsageError naming the
/// value and listing kMsaaValues.
int ParseMsaa(const std::string& value);

/// The renderer options for `view` on `model` (parses --camera, --overlay, --hud-position and
/// checks --hud-opacity). The frame is FrameSize(result): --width/--height size each tile.
RenderOptions MakeRenderOptions(const ViewOptions& view, const mjModel* model);

/// Adds the view options to `sub`.
void AddViewOptions(CLI::App* sub, ViewOptions* options);

/// The GPU request of `view` in effect (--gpu, else MUJOCO_EGL_DEVICE_ID, else
/// CUDA_VISIBLE_DEVICES, else auto) matched against this machine's EGL devices: the EGL indices
/// to render on, in worker order (empty: auto). Enumerates only when a device is named and the
/// backend may be EGL. Throws UsageError/RunError as ChooseGpus.
GpuChoice ResolveGpuChoice(const ViewOptions& view);

/// A GL context for `view` on `choice` (worker w renders on choice.devices[w % size]); its
/// info().selection says how the device was chosen.
std::unique_ptr<GlContext> CreateViewContext(const ViewOptions& view, const GpuChoice& choice,
                                             int worker = 0);

/// The overlay/HUD description of the env's current state after `record`.
FrameInfo MakeFrameInfo(const FetchEnv& env, const StepRecord& record);

/// Parses --layers: a comma list of rgb, depth, segmentation (spaces after the commas allowed),
/// each once, in the order given. UsageError names an empty, unknown (with "did you mean") or
/// repeated entry and what is accepted.
std::vector<Layer> ParseLayers(const std::string& list);

/// One object of a segmentation legend (render's and record's): its colour as "#rrggbb" and as
/// rgb, body, geoms, site (null for a body) and pixels.
nlohmann::json SegmentObjectJson(const SegmentObject& object);

}  // namespace fetchscope::cli
