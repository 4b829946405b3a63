// Played episodes (src/episode.h, the trajectory's episodes) as Minari episodes.
#pragma once

#include <cstdint>
#include <optional>

#include "dataset/minari_format.h"
#include "src/episode.h"

namespace fetchscope {

/// One played episode as Minari stores it: the observations of steps 0..T; the actions as the
/// env applied them (clipped to the action space [-1, 1], then float32, the Box's dtype); the
/// rewards; no terminations (a Fetch task never terminates); the last step truncated (by
/// TimeLimit, or where the run's --steps ended it: DataCollector marks an episode cut short by a
/// reset the same way); is_success of every row; `seed` where its reset was seeded.
MinariEpisode ToMinariEpisode(const EpisodeRecord& episode, std::optional<uint64_t> seed,
                              int obs_dim);

}  // namespace fetchscope
