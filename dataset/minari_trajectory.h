// Played episodes (src/episode.h, the trajectory's episodes) as Minari episodes.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>

#include "dataset/minari_format.h"
#include "dataset/minari_writer.h"
#include "src/episode.h"
#include "src/trajectory.h"

namespace fetchscope {

/// One played episode as Minari stores it: the observations of steps 0..T; the actions as the
/// env applied them (clipped to the action space [-1, 1], then float32, the Box's dtype); the
/// rewards; no terminations (a Fetch task never terminates); the last step truncated (by
/// TimeLimit, or where the run's --steps ended it: DataCollector marks an episode cut short by a
/// reset the same way); is_success of every row; `seed` where its reset was seeded.
MinariEpisode ToMinariEpisode(const EpisodeRecord& episode, std::optional<uint64_t> seed,
                              int obs_dim);

/// Writes the episodes of `trajectory` (a run: episode 0 reset with its seed, the others
/// continuing the generator), in index order, as the dataset `options` names (its spec is the
/// trajectory's env). Returns the dataset folder.
std::filesystem::path WriteMinariDataset(const Trajectory& trajectory, MinariWriteOptions options);

}  // namespace fetchscope
