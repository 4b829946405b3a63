// RAII owners for MuJoCo's simulation handles.
#pragma once

#include <mujoco/mujoco.h>

#include <memory>

namespace fetchscope {

/// Deleter for mjModel (mj_deleteModel).
struct MjModelDeleter {
  void operator()(mjModel* m) const noexcept { mj_deleteModel(m); }
};
/// Deleter for mjData (mj_deleteData).
struct MjDataDeleter {
  void operator()(mjData* d) const noexcept { mj_deleteData(d); }
};

using MjModelPtr = std::unique_ptr<mjModel, MjModelDeleter>;  ///< owns an mjModel
using MjDataPtr = std::unique_ptr<mjData, MjDataDeleter>;     ///< owns an mjData

}  // namespace fetchscope
