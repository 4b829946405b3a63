// probe-actions' grasp report: does the gripper action do what you think? From the seeded reset
// of an object task whose gripper is free (PickAndPlace), the grip is brought above the object
// with the fingers open, lowered to it, the fingers closed, and then +z commanded: which fingers
// touch the object after the close, how hard (their normal forces, src/contacts.h), and whether
// the object rises with the grip.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <vector>

#include "encode/contact_sheet.h"
#include "render/renderer.h"
#include "src/fetch_env.h"

namespace fetchscope {

/// Steps of each phase of the grasp probe, at most.
inline constexpr int kGraspApproachSteps = 30;  ///< above the object, fingers open
inline constexpr int kGraspDescendSteps = 20;   ///< down to it
inline constexpr int kGraspCloseSteps = 8;      ///< a[3] = -1, the grip held
inline constexpr int kGraspLiftSteps = 6;       ///< +z with the fingers closed

/// The grasp probe on `env` from reset(seed): {"done": false, "why"} where the gripper is blocked
/// or there is no object; else the phases' steps, "after_close" {left_finger_force,
/// right_finger_force (N), fingers_touching (body names), grasped}, "lift" {grip_rise, object_rise
/// (m), lifts}, and "answer", one line. With a renderer, `tiles` gets the frames after the close
/// and after the lift (drawn with the renderer's own overlays).
nlohmann::json GraspProbe(FetchEnv& env, uint64_t seed, Renderer* renderer,
                          std::vector<SheetTile>* tiles);

}  // namespace fetchscope
