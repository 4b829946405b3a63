// Golden-image regression checks (`fetchscope golden check|update`): render the canonical scenes
// of golden/manifest.json (inspect/golden_scene.h) and compare them with (or write them as) the
// committed goldens. The state golden is compared first, so a failure names the layer that
// changed: the physics or model (state differs) or the renderer or camera (state equal, pixels
// differ).
#pragma once

#include <string>
#include <vector>

#include "render/gl_context.h"

namespace fetchscope {

/// What golden check and update run on.
struct GoldenOptions {
  /// folder holding manifest.json and the goldens; "": ./golden where it exists, else (check
  /// only) the goldens installed with the binary (ResolveGoldenDir)
  std::string golden_dir;
  std::string out = "out/golden";        ///< check: folder for the images of failed scenes
  GlBackend backend = GlBackend::kAuto;  ///< --backend, else $MUJOCO_GL, else auto (cli/)
  int gpu = -1;                          ///< EGL device index; -1: from the environment
  std::vector<std::string> only;         ///< only these scenes (empty: every scene)
  std::string genuine_assets;            ///< Gymnasium-Robotics envs/assets; empty: looked for
};

/// Compares every selected scene with its goldens and prints a table, worst first; a failed
/// scene leaves NAME_actual.png, NAME_diff.png and NAME_side.png (golden | actual | diff) under
/// options.out. SIGINT/SIGTERM stop it after the scene in progress. Returns the exit status: 0
/// every scene passes, 1 one failed, 128 + signal when interrupted.
int GoldenCheck(const GoldenOptions& options);

/// Renders every selected scene and writes its goldens (NAME.png, NAME_state.json), each file
/// whole or not at all. Returns the exit status: 0, or 128 + signal when interrupted.
int GoldenUpdate(const GoldenOptions& options);

}  // namespace fetchscope
