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
  bool require_genuine = false;    ///< genuine-asset scenes that cannot run are an error (exit 2)
  std::string junit;               ///< check: JUnit XML report to write; "": none
  std::string json;                ///< check: JSON report to write; "": none
  std::string tolerance = "auto";  ///< check: auto | same | cross | threshold=N[,...]
};

/// Compares every selected scene with its goldens and prints a table, worst first; a failed
/// scene leaves NAME_golden.png, NAME_actual.png, NAME_diff.png and NAME_side.png (golden |
/// actual | diff) under options.out, and index.html there reviews them (inspect/golden_report.h).
/// SIGINT/SIGTERM stop it after the scene in progress. Returns the exit status: 0 every scene
/// passes, 1 one regressed, 2 a scene could not be checked (its assets or XML broken, a golden
/// unreadable), 128 + signal when interrupted. Throws UsageError (exit 2) for a manifest, an
/// assets folder or a GL that cannot be used.
int GoldenCheck(const GoldenOptions& options);

/// Renders every selected scene and writes its goldens (NAME.png, NAME_state.json,
/// NAME_meta.json), each file whole or not at all, saying what changed (pixels, and the state by
/// named quantity), with a review page of the changes in options.out. Returns the exit status: 0,
/// or 128 + signal when interrupted.
int GoldenUpdate(const GoldenOptions& options);

}  // namespace fetchscope
