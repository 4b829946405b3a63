// --obs-camera, --obs-size, --obs-layers and --obs-overlay: the camera images a dataset stores
// per step (docs/guide/datasets.md, "Pixel datasets"), parsed into render/obs_view.h's ObsSetup.
#pragma once

#include <mujoco/mujoco.h>

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "render/obs_view.h"

namespace fetchscope::cli {

/// The options as typed.
struct ObsOptions {
  std::vector<std::string> cameras;  ///< --obs-camera, repeatable
  std::string size = "128x128";      ///< --obs-size
  std::string layers = "rgb";        ///< --obs-layers
  std::string overlay = "none";      ///< --obs-overlay
};

/// Adds the four options to `sub`.
void AddObsOptions(CLI::App* sub, ObsOptions* options);

/// Parses one --obs-camera value, [NAME=]CAMERA: CAMERA is one --camera value (exactly one
/// camera); NAME (letters, digits, '_' and '-', not starting with '-') defaults to a model
/// camera's own name and is required for default, free and track cameras. Throws UsageError
/// naming the value and what is accepted.
ObsCamera ParseObsCamera(const std::string& value, const mjModel* model);

/// Parses --obs-size WxH, each side 1 to 4096. Throws UsageError naming the value.
void ParseObsSize(const std::string& text, int* width, int* height);

/// The whole setup on `model` (no cameras: disabled): every camera parsed, a NAME given twice
/// refused, the size and layers (rgb, depth, segmentation; stored in that order) checked, the
/// overlay parsed; `msaa_samples` as the command renders (kMsaaAuto for rollout).
ObsSetup ResolveObs(const ObsOptions& options, const mjModel* model, int msaa_samples);

/// Refuses --obs-size/--obs-layers/--obs-overlay given without --obs-camera (`sub` tells what
/// was given), and --obs-camera without a dataset to write (`has_dataset`).
void CheckObsUse(const CLI::App* sub, const ObsOptions& options, bool has_dataset);

}  // namespace fetchscope::cli
