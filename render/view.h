// What a command renders and how, typed (ViewSetup: the renderer's options, the GL backend, the
// GPU request), turned into a GL context and the per-frame overlay description. The options'
// text (--camera, --overlay, --width, --height, --backend, --gpu, --msaa, --readback, --hud-*)
// is parsed into a ViewSetup by cli/view_options.h, once, in the parent.
#pragma once

#include <mujoco/mujoco.h>

#include <memory>

#include "render/gl_context.h"
#include "render/gpu_select.h"
#include "render/overlay.h"
#include "render/renderer.h"
#include "src/episode.h"
#include "src/fetch_env.h"

namespace fetchscope {

/// What a command renders and where, resolved once from its options by the command line
/// (cli/view_options.h): the renderer's options with the cameras already checked against the
/// model, the GL backend and the GPU request in effect. Workers read it; nothing here is text.
struct ViewSetup {
  RenderOptions render;                  ///< cameras, overlays, tile size, msaa, readback, HUD
  GlBackend backend = GlBackend::kAuto;  ///< the backend every context is made with
  GpuSpec gpu;                           ///< --gpu, else what the environment names (auto)
};

/// Checks that a whole frame of `options` fits in memory (FrameSize of its tiles); throws
/// UsageError otherwise, before any work.
void CheckRenderFrame(const RenderOptions& options);

/// The GPU request of `view` (view.gpu: --gpu, else MUJOCO_EGL_DEVICE_ID, else
/// CUDA_VISIBLE_DEVICES, else auto) matched against this machine's EGL devices: the EGL indices
/// to render on, in worker order (empty: auto). Enumerates only when a device is named and the
/// backend may be EGL. Throws UsageError/RunError as ChooseGpus.
GpuChoice ResolveGpuChoice(const ViewSetup& view);

/// A GL context on `backend` and `choice` (worker w renders on choice.devices[w % size]); its
/// info().selection says how the device was chosen.
std::unique_ptr<GlContext> CreateViewContext(GlBackend backend, const GpuChoice& choice,
                                             int worker = 0);

/// The overlay/HUD description of the env's current state after `record`.
FrameInfo MakeFrameInfo(const FetchEnv& env, const StepRecord& record);

}  // namespace fetchscope
