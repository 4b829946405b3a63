// Which look each episode of a run is drawn with (--randomize; render/look.h): one draw per
// episode from LookSeed(seed, k), or, re-rendering a recording without --randomize, the look
// each recorded episode stored; else the plain look.
#pragma once

#include <mujoco/mujoco.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "render/look.h"
#include "src/trajectory.h"

namespace fetchscope {

/// The look of episode `k`: with `given` (--randomize), its draw from LookSeed(seed, k) for the
/// views `camera_keys` (nullopt for --randomize none); without, `recorded`'s stored look (record
/// --from), or nullopt (the plain look). Throws UsageError naming the episode's file for a
/// stored look that is not one.
std::optional<LookDraw> EpisodeLook(const std::optional<LookConfig>& given, uint64_t seed, int k,
                                    const TrajectoryEpisode* recorded,
                                    const std::vector<std::string>& camera_keys,
                                    const mjModel* model);

}  // namespace fetchscope
