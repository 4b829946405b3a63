#include "run/episode_look.h"

namespace fetchscope {

std::optional<LookDraw> EpisodeLook(const std::optional<LookConfig>& given, uint64_t seed, int k,
                                    const TrajectoryEpisode* recorded,
                                    const std::vector<std::string>& camera_keys,
                                    const mjModel* model) {
  if (given) {
    if (!given->any()) return std::nullopt;
    return DrawLook(*given, LookSeed(seed, k), camera_keys, model);
  }
  if (recorded && !recorded->look.is_null()) {
    return ParseLookJson(recorded->look,
                         (recorded->file.empty() ? std::string("the recording") : recorded->file) +
                             ": episode " + std::to_string(k) + ": look");
  }
  return std::nullopt;
}

}  // namespace fetchscope
