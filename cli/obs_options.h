// --obs-camera, --obs-size, --obs-layers and --obs-overlay: the camera images a dataset stores
// per step (docs/guide/datasets.md, "Pixel datasets"), parsed into render/obs_view.h's ObsSetup.
#pragma once

#include <mujoco/mujoco.h>

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "render/obs_view.h"
#include "run/pixel_recorder.h"

namespace fetchscope::cli {

/// The options as typed.
struct ObsOptions {
  std::vector<std::string> cameras;  ///< --obs-camera, repeatable
  std::string size = "128x128";      ///< --obs-size
  std::string layers = "rgb";        ///< --obs-layers
  std::string overlay = "none";      ///< --obs-overlay
};

/// --robomimic and its options as typed.
struct RobomimicOptions {
  std::string file;           ///< --robomimic FILE.hdf5
  bool no_next_obs = false;   ///< --no-next-obs
  double valid_fraction = 0;  ///< --valid-fraction
};

/// --keep and --stop-after-success as typed.
struct EpisodeSelectionOptions {
  std::string keep = "all";     ///< --keep: all or successful
  int stop_after_success = -1;  ///< --stop-after-success K (-1: not given)
};

/// Adds --keep and --stop-after-success to `sub`.
void AddEpisodeSelectionOptions(CLI::App* sub, EpisodeSelectionOptions* options);

/// True for --keep successful; refuses another value than all or successful, and successful
/// without a dataset to write (`has_dataset`). Throws UsageError naming the value.
bool KeepSuccessful(const EpisodeSelectionOptions& options, bool has_dataset);

/// Adds --robomimic, --no-next-obs and --valid-fraction to `sub`.
void AddRobomimicOptions(CLI::App* sub, RobomimicOptions* options);

/// Refuses a --valid-fraction outside [0, 1) in one line naming it.
void CheckValidFraction(double fraction);

/// What the workers stage for the datasets asked for: `setup`'s images (rgb as PNG files for a
/// Minari dataset, as gzip chunks for a robomimic file) and, for robomimic, the MuJoCo state of
/// every step. Disabled (nothing staged) without images and without robomimic.
PixelPlan PlanPixels(const ObsSetup& setup, const mjModel* model, bool minari, bool robomimic);

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
/// was given), --obs-camera with neither a dataset to write (`has_dataset`) nor an exec: policy
/// to send the images to (`exec_policy`), --no-next-obs and --valid-fraction without
/// --robomimic, and a --valid-fraction outside [0, 1).
void CheckObsUse(const CLI::App* sub, const ObsOptions& options, bool has_dataset, bool exec_policy,
                 const RobomimicOptions& robomimic);

}  // namespace fetchscope::cli
