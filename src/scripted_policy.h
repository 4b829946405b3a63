// A built-in controller per task, written from the observation only.
#pragma once

#include <memory>

#include "src/env_spec.h"

namespace fetchscope {

class Policy;

/// Reach: go to the goal. Push: get behind the block and push it. PickAndPlace: open,
/// descend, grasp, lift, carry, hold. Slide: line up behind the puck and strike it with a
/// speed calibrated to the distance (best effort).
std::unique_ptr<Policy> MakeScriptedPolicy(const EnvSpec& env);

}  // namespace fetchscope
