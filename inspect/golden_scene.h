// Golden-image scenes: golden/manifest.json, rendering one scene (its image and its state), and
// comparing a state with its golden. The `golden check|update` subcommands (cli/golden.cc) are
// built from these.
//
// manifest.json:
//   {"version": 1,
//    "defaults": {"msaa": 4, "state_atol": 1e-6,
//                 "tolerance": {"threshold": 32, "max_fraction": 0.002, "max_rms": 2.0}},
//    "scenes": [{"name": "reach_reset", "env_id": "FetchReach-v4", "assets": "bundled",
//                "seed": 0, "policy": "zero", "steps": 0, "camera": "default",
//                "overlay": "none", "width": 320, "height": 240, "msaa": 4,
//                "tolerance": {"max_fraction": 0.002},
//                "same_backend_tolerance": {"threshold": 8},
//                "mask": [[x, y, width, height], ...],
//                "randomize": "colors,textures,lighting,camera", "look_seed": 11}, ...]}
// "tolerance" applies when the goldens were made on another backend or GL renderer,
// "same_backend_tolerance" (defaults: kSameBackendTolerance) when on this one; a scene's members
// override the defaults one by one. "mask" lists frame rectangles left out of the image
// comparison. "randomize" (as --randomize) renders the scene under one fixed randomized look:
// the draw `fetchscope render --seed LOOK_SEED --randomize LIST` makes (DrawLook from
// LookSeed(look_seed, 0)); "look_seed" defaults to "seed". A look never changes the physics, so
// its state golden is the plain scene's (a changed draw fails in pixels). Its goldens are
// NAME.png, NAME_state.json and NAME_meta.json (how and where they were made,
// inspect/golden_meta.h) beside the manifest.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "inspect/image_diff.h"
#include "render/gl_context.h"
#include "render/look.h"
#include "src/policy_spec.h"

namespace fetchscope {

/// How close an image must be to its golden.
struct GoldenTolerance {
  int threshold = 32;  ///< a pixel differs when its largest channel difference exceeds this
  double max_fraction = 0.002;  ///< at most this fraction of pixels may differ
  double max_rms = 2.0;         ///< RMS error over all channels, levels
};

/// The built-in tolerance of a check on the backend and GL renderer the goldens were made on:
/// such a renderer gives the same pixels again, so a change of a few levels in a colour (a
/// block's red 0.2 -> 0.25 moves it 15-18 levels) fails.
inline constexpr GoldenTolerance kSameBackendTolerance{8, 0.0002, 1.0};

/// A frame rectangle left out of the image comparison, pixels, row 0 at the top.
struct GoldenMask {
  int x = 0;       ///< left column
  int y = 0;       ///< top row
  int width = 0;   ///< columns
  int height = 0;  ///< rows
};

/// One canonical scene.
struct GoldenScene {
  std::string name;    ///< file stem of its goldens; [A-Za-z0-9_-]+
  std::string env_id;  ///< a v4 id
  std::string assets;  ///< "bundled", "genuine" or a folder relative to the golden dir
  uint64_t seed = 0;   ///< env.reset(seed=...)
  /// zero | scripted | random | replay:FILE (FILE in the golden dir), parsed by
  /// ReadGoldenManifest (a replay file read then); `text` is what the state golden names
  PolicySpec policy = PolicySpec::Zero();
  int steps = 0;                   ///< policy steps before the frame (0 = the reset frame)
  std::string camera = "default";  ///< as --camera
  std::string overlay = "none";    ///< as --overlay
  int width = 320;                 ///< pixels of each camera tile (the frame is FrameSize)
  int height = 240;                ///< pixels
  int msaa = 4;                    ///< multisample count, pinned so goldens never follow a default
  GoldenTolerance tolerance;       ///< image tolerance across backends or GL renderers
  GoldenTolerance same_tolerance = kSameBackendTolerance;  ///< on the goldens' own backend
  std::vector<GoldenMask> masks;                           ///< left out of the image comparison
  double state_atol = 1e-6;  ///< absolute tolerance on every state number
  std::string randomize;     ///< "randomize" as given ("" = the plain look)
  LookConfig look;           ///< ParseRandomize(randomize); look.any() false: the plain look
  uint64_t look_seed = 0;    ///< the look's seed: DrawLook(look, LookSeed(look_seed, 0), ...)
};

/// A parsed manifest.
struct GoldenManifest {
  std::string dir;                  ///< the golden folder holding manifest.json
  std::vector<GoldenScene> scenes;  ///< in manifest order
};

/// Reads DIR/manifest.json. Throws UsageError for a missing folder or manifest, RunError naming
/// the scene and member for a malformed one (unknown env id, bad size, duplicate name, ...).
GoldenManifest ReadGoldenManifest(const std::string& dir);

/// The scenes named in `only` (each entry a name or a comma list), or all when `only` is empty.
/// Throws UsageError for an unknown name, listing the valid ones.
std::vector<const GoldenScene*> SelectScenes(const GoldenManifest& manifest,
                                             const std::vector<std::string>& only);

/// What one scene gives: its frame and the trajectory up to it.
struct SceneResult {
  int width = 0;                    ///< frame width: the scene's width per camera tile (FrameSize)
  int height = 0;                   ///< frame height
  std::vector<uint8_t> rgb;         ///< width * height * 3 bytes, row 0 = top
  nlohmann::json state;             ///< see StateJson
  std::string assets_sha256;        ///< the assets' content hash (AssetSource::sha256)
  int msaa_used = 0;                ///< multisamples the renderer used (the driver may cap)
  std::string msaa_reason;          ///< why, e.g. "capped at the driver's maximum 4"
  std::string segmentation_sha256;  ///< hash of the frame's segmentation object indices
};

/// Runs the scene's episode and renders its last frame on `gl` (current on this thread).
/// `assets_root` is what ResolveAssets accepts: "bundled" or a folder.
SceneResult RenderScene(GlContext& gl, const GoldenScene& scene, const std::string& assets_root);

/// Where a scene's assets come from: "bundled", `genuine_dir` for "genuine", else the folder
/// relative to `golden_dir`.
std::string SceneAssets(const GoldenScene& scene, const std::string& golden_dir,
                        const std::string& genuine_dir);

/// The one line saying which of the scene's masks reaches outside a width x height frame, or ""
/// when every one lies inside it.
std::string MaskOutsideFrame(const GoldenScene& scene, int width, int height);

/// Copies `golden`'s pixels into `actual` inside each mask (clipped to the frame), so that masked
/// pixels never differ. Both are width * height * 3 bytes.
void ApplyMasks(const std::vector<GoldenMask>& masks, const uint8_t* golden, uint8_t* actual,
                int width, int height);

/// Result of comparing two state JSON documents.
struct StateComparison {
  bool equal = true;   ///< every number within the tolerance, everything else identical
  double max_abs = 0;  ///< largest absolute difference of two numbers
  std::string first;   ///< where they first differ, e.g. "steps[0].desired_goal[1]: 0.75 vs 0.76"
};

/// Compares `golden` with `actual` member by member: numbers within `atol`, strings, booleans
/// and nulls exactly, arrays and objects by shape.
StateComparison CompareStates(const nlohmann::json& golden, const nlohmann::json& actual,
                              double atol);

}  // namespace fetchscope
