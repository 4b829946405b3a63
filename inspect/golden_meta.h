// What a golden set records beside each scene's image and state (NAME_meta.json: the backend
// and GL renderer, the fetchscope and MuJoCo versions, the assets hash, the multisampling the
// driver gave and the segmentation's hash), how a check chooses its tolerance from it, and a
// state difference named by quantity (describe's labels).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "inspect/golden_scene.h"
#include "render/gl_context.h"

namespace fetchscope {

/// NAME_meta.json of a scene rendered on `gl`:
///   {"backend": "osmesa", "gl_renderer": "llvmpipe (LLVM 15.0.6, 256 bits)",
///    "versions": {"fetchscope": ..., "mujoco": ...}, "assets_sha256": ...,
///    "msaa": {"asked": 4, "used": 4}, "segmentation_sha256": ...}
nlohmann::json GoldenMetaJson(const GoldenScene& scene, const SceneResult& result,
                              const GlInfo& gl);

/// NAME_meta.json read; null when the file is missing (goldens written before fetchscope
/// recorded it). Throws RunError naming the file when it is not a JSON object.
nlohmann::json ReadGoldenMeta(const std::string& path);

/// What the goldens were made on, "BACKEND / GL_RENDERER" ("" when the meta lacks it).
std::string MadeOn(const nlohmann::json& meta);

/// What `gl` is, in MadeOn's words.
std::string RunningOn(const GlInfo& gl);

/// Which tolerance a check uses, and why.
struct ToleranceChoice {
  GoldenTolerance tolerance;
  bool same_backend = false;  ///< the goldens were made on this backend and GL renderer
  std::string why;            ///< e.g. "same backend (osmesa / llvmpipe ...)"
};

/// How --tolerance chooses: auto (same backend: the scene's tight tolerance, else its
/// cross-backend one), same, cross, or explicit numbers for every scene.
struct ToleranceOverride {
  std::string mode = "auto";  ///< "auto", "same", "cross" or "explicit"
  GoldenTolerance numbers;    ///< for "explicit"
};

/// Parses --tolerance: auto, same, cross, or threshold=N[,max_fraction=F][,max_rms=R] (members
/// left out keep the cross-backend defaults). Throws UsageError naming the bad part.
ToleranceOverride ParseToleranceOverride(const std::string& text);

/// The tolerance of `scene` for goldens made as `meta` says, checked on `gl`.
ToleranceChoice ChooseTolerance(const GoldenScene& scene, const nlohmann::json& meta,
                                const GlInfo& gl, const ToleranceOverride& override_);

/// One labelled number of the state that differs.
struct NamedDifference {
  std::string label;  ///< describe's label ("object_pos.z"), or the path of an unlabelled one
  double delta = 0;   ///< actual - golden, at the step where it is largest
  int t = 0;          ///< that step
  std::string text;   ///< "object_pos.z +2.00 mm at t=0"
  std::string unit;   ///< describe's unit ("m", "rad", "m/step", ...), "" for none
};

/// The labelled numbers of two states that differ by more than `atol`, positions first, then
/// angles, velocities and unitless numbers, each group largest first; at most `limit` of them (the
/// observation by describe's labels, desired_goal, action, reward).
std::vector<NamedDifference> NamedStateDifferences(const nlohmann::json& golden,
                                                   const nlohmann::json& actual, double atol,
                                                   size_t limit = 3);

/// "object_pos.z +2.00 mm at t=0, grip_pos.z +1.90 mm at t=0"; "" for none.
std::string JoinDifferences(const std::vector<NamedDifference>& differences);

}  // namespace fetchscope
