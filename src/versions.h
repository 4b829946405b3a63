// The versions every output records.
#pragma once

#include <nlohmann/json.hpp>

namespace fetchscope {

/// {"fetchscope": our version, "mujoco": mj_versionString()}.
nlohmann::json VersionsJson();

}  // namespace fetchscope
