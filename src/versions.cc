#include "src/versions.h"

#include <mujoco/mujoco.h>

namespace fetchscope {

nlohmann::json VersionsJson() {
  return {{"fetchscope", FETCHSCOPE_VERSION}, {"mujoco", mj_versionString()}};
}

}  // namespace fetchscope
