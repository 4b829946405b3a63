// Options and helpers shared by the subcommands that render (render, record, bench).
#pragma once

#include <CLI/CLI.hpp>

#include <string>

#include "render/overlay.h"
#include "render/renderer.h"
#include "src/episode.h"
#include "src/fetch_env.h"

namespace fetchscope::cli {

/// --camera, --overlay, --width, --height, --backend, --gpu.
struct ViewOptions {
  std::string camera = "default";                 ///< see ParseCameraList
  std::string overlay = "goal,achieved,hud";      ///< see ParseOverlays
  int width = 480;                                ///< pixels
  int height = 480;                               ///< pixels
  std::string backend;                            ///< auto|egl|osmesa; empty: $MUJOCO_GL or auto
  int gpu = -1;                                   ///< EGL device index; -1: $MUJOCO_EGL_DEVICE_ID or first
  int msaa = -1;                                  ///< multisample count; -1: the model's (4)
};

/// The renderer options for `view` on `model` (parses --camera and --overlay).
RenderOptions MakeRenderOptions(const ViewOptions& view, const mjModel* model);

/// Adds the view options to `sub`.
void AddViewOptions(CLI::App* sub, ViewOptions* options);

/// The overlay/HUD description of the env's current state after `record`.
FrameInfo MakeFrameInfo(const FetchEnv& env, const StepRecord& record);

}  // namespace fetchscope::cli
