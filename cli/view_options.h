// The view options (--camera, --overlay, --width, --height, --backend, --gpu, --msaa,
// --readback, --hud-*), --format and --layers as the user typed them, and their parsers: the
// command line turns them into typed values here, once, in the parent (render/view.h's
// ViewSetup, rows of encode/video_format.h's table, render/renderer.h's Layer); run/, encode/
// and dataset/ never see the text.
#pragma once

#include <mujoco/mujoco.h>

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "encode/video_format.h"
#include "render/overlay.h"
#include "render/renderer.h"
#include "render/view.h"

namespace fetchscope::cli {

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

/// Adds --camera, --overlay, --width, --height, --hud-position, --hud-opacity, --backend,
/// --msaa, --readback and --gpu to `sub`, bound to `options`.
void AddViewOptions(CLI::App* sub, ViewOptions* options);

/// Parses --hud-position: top-left, top-right, bottom-left or bottom-right. Throws UsageError
/// naming the value and listing the accepted ones.
HudPosition ParseHudPosition(const std::string& text);

/// Checks --hud-opacity (0 = no box behind the text, 1 = opaque); throws UsageError naming
/// the value and the accepted range when it is outside [0, 1] or not a number.
double CheckHudOpacity(double opacity);

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

/// The renderer options of `view` on `model`: the cameras parsed and checked against the
/// model's, the overlays, msaa, readback, HUD position and opacity, the frame size checked.
/// The frame is FrameSize(result): --width/--height size each tile. Throws UsageError naming
/// the bad value.
RenderOptions ResolveRenderOptions(const ViewOptions& view, const mjModel* model);

/// The backend (ResolveGlBackend: --backend, else $MUJOCO_GL, else auto) and the GPU request in
/// effect (EffectiveGpuSpec: --gpu, else the environment) of `view`, its render options left at
/// their defaults: for a command that sets its own (anatomy). Throws UsageError naming the value.
ViewSetup ResolveGlView(const ViewOptions& view);

/// ResolveRenderOptions, then ResolveGlView: everything a worker needs to render, typed.
ViewSetup ResolveView(const ViewOptions& view, const mjModel* model);

/// Parses a --format list ("mp4", "webm,gif", "mp4, gif"): rows of VideoFormats(), in the order
/// given, each once, at least one. Throws UsageError naming a bad or repeated entry and what is
/// accepted.
std::vector<const VideoFormat*> ParseVideoFormats(const std::string& list);

/// Parses --layers: a comma list of rgb, depth, segmentation (spaces after the commas allowed),
/// each once, in the order given. UsageError names an empty, unknown (with "did you mean") or
/// repeated entry and what is accepted.
std::vector<Layer> ParseLayers(const std::string& list, const std::string& option = "--layers");

/// record's --layers: the layers beyond rgb, in the order given (rgb is always recorded: the
/// episode video, sheet and report need it). Throws as ParseLayers.
std::vector<Layer> ParseRecordLayers(const std::string& list);

}  // namespace fetchscope::cli
