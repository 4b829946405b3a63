// One env action, in the precision it arrived in.
#pragma once

#include <array>

namespace fetchscope {

/// A 4-vector action (dx, dy, dz, gripper). Gymnasium applies clipping and the
/// 0.05 scaling in the action's own dtype, so the precision travels with it.
struct Action {
  std::array<double, 4> value{};  ///< components; exactly float-representable when is_float32
  bool is_float32 = false;        ///< true: float32 path (random policy, float32 .npy)
};

}  // namespace fetchscope
