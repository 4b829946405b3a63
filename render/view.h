// What a command renders and how (--camera, --overlay, --width, --height, --backend, --gpu,
// --msaa, --readback, --hud-*), turned into a GL context, renderer options and the per-frame
// overlay description. cli/view_options.h adds these options to a command.
#pragma once

#include <mujoco/mujoco.h>

#include <memory>
#include <string>

#include "render/gl_context.h"
#include "render/gpu_select.h"
#include "render/overlay.h"
#include "render/renderer.h"
#include "src/episode.h"
#include "src/fetch_env.h"

namespace fetchscope {

/// --camera, --overlay, --width, --height, --backend, --gpu, --msaa, --readback, --hud-*.
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

/// The accepted --readback values, in the order the help and errors list them.
inline constexpr const char* kReadbackValues[] = {"auto", "sync", "async"};

/// RenderOptions::readback for a --readback value. Throws UsageError naming the value and
/// listing kReadbackValues.
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

}  // namespace fetchscope
