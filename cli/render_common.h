// Options and helpers shared by the subcommands that render (render, record, bench).
#pragma once

#include <CLI/CLI.hpp>

#include <string>

#include "render/overlay.h"
#include "render/renderer.h"
#include "src/episode.h"
#include "src/fetch_env.h"

namespace fetchscope::cli {

/// --camera, --overlay, --width, --height, --backend, --gpu, --msaa.
struct ViewOptions {
  std::string camera = "default";                 ///< see ParseCameraList
  std::string overlay = "goal,achieved,hud";      ///< see ParseOverlays
  int width = 480;                                ///< pixels
  int height = 480;                               ///< pixels
  std::string backend;                            ///< auto|egl|osmesa; empty: $MUJOCO_GL or auto
  int gpu = -1;                                   ///< EGL device index; -1: $MUJOCO_EGL_DEVICE_ID or first
  std::string msaa = "auto";                      ///< see ParseMsaa
};

/// The accepted --msaa values, in the order the help and errors list them.
inline constexpr const char* kMsaaValues[] = {"auto", "0", "1", "2", "4", "8", "16"};

/// RenderOptions::msaa_samples for an --msaa value: "auto" (kMsaaAuto: the model's 4 on
/// hardware GL, 0 on a software rasterizer) or a sample count. Throws UsageError naming the
/// value and listing kMsaaValues.
int ParseMsaa(const std::string& value);

/// The renderer options for `view` on `model` (parses --camera and --overlay).
RenderOptions MakeRenderOptions(const ViewOptions& view, const mjModel* model);

/// Adds the view options to `sub`.
void AddViewOptions(CLI::App* sub, ViewOptions* options);

/// The overlay/HUD description of the env's current state after `record`.
FrameInfo MakeFrameInfo(const FetchEnv& env, const StepRecord& record);

}  // namespace fetchscope::cli
