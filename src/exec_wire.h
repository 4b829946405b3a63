// What an exec: policy's child reads each step (docs/guide/your-policy.md, "Images for a vision
// policy"): one JSON line holding `t`, the state fields --exec-fields chose and, with
// --obs-camera, `cameras` (each camera's intrinsics and pose at this step) and `images` (name,
// layer, shape, dtype, bytes of each image); right after the line, the raw bytes of each image in
// that order. Without --obs-camera and --exec-fields the line is what it always was.
#pragma once

#include <array>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "src/fetch_env.h"

namespace fetchscope {

/// One image after the line: row-major, top row first; rgb uint8 (H, W, 3), depth float32
/// little-endian metres (H, W), segmentation int32 object ids (H, W).
struct WireImage {
  std::string name;             ///< the camera's key (NAME of --obs-camera)
  const char* layer = "rgb";    ///< "rgb", "depth" or "segmentation"
  std::vector<int> shape;       ///< [H, W, 3] or [H, W]
  const char* dtype = "uint8";  ///< "uint8", "float32" or "int32"
  const void* data = nullptr;   ///< the bytes, valid until the next step is drawn
  size_t bytes = 0;             ///< their count
};

/// One camera's geometry in this step's images (render/obs_view.h's conventions).
struct WireCamera {
  std::string name;
  double fovy = 0, fx = 0, fy = 0, cx = 0, cy = 0;
  std::array<double, 7> pose = {};  ///< x, y, z, qw, qx, qy, qz: the MuJoCo camera frame
};

/// The images of the state the policy is asked about.
struct WireStep {
  int t = -1;  ///< the step they show
  std::vector<WireCamera> cameras;
  std::vector<WireImage> images;
  /// [{"id", "body"|"site"}], sent on the first line of each episode; null without segmentation
  nlohmann::json legend;
};

/// The names --exec-fields accepts on a task with (`has_object`) or without an object: the
/// three Gymnasium keys, then the observation's slices (src/observation_layout.h).
std::vector<std::string> ExecFieldNames(bool has_object);

/// --exec-fields: "all" (or empty) gives an empty list, which means every field as before;
/// else a comma-separated list of ExecFieldNames, each once. Throws UsageError naming the bad
/// name and the accepted ones.
std::vector<std::string> ParseExecFields(const std::string& text, bool has_object);

/// --exec-fields's help.
inline constexpr const char* kExecFieldsHelp =
    "The state fields each line to an exec: policy carries, comma-separated: observation, "
    "achieved_goal, desired_goal, or observation slices by name (grip_pos, gripper_state, "
    "grip_velp, gripper_vel; with an object also object_pos, object_rel_pos, object_rot, "
    "object_velp, object_velr), each under its own key; `t` and the images are always sent. "
    "Default all (observation, achieved_goal, desired_goal)";

/// The line for step `t`: `t`, the fields (empty: all three), and `step`'s cameras and images
/// when it is given (its legend too where `with_legend`).
nlohmann::json ExecMessage(const Observation& obs, int t, const std::vector<std::string>& fields,
                           const WireStep* step, bool with_legend);

}  // namespace fetchscope
