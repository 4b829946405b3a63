// Played episodes (src/episode.h, the trajectory's episodes) as Minari episodes.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "dataset/minari_format.h"
#include "dataset/minari_writer.h"
#include "src/episode.h"
#include "src/episode_source.h"
#include "src/trajectory.h"

namespace fetchscope {

/// One played episode as Minari stores it: the observations of steps 0..T; the actions as the
/// env applied them (clipped to the action space [-1, 1], then float32, the Box's dtype); the
/// rewards; no terminations (a Fetch task never terminates); the last step truncated (by
/// TimeLimit, or where the run's --steps ended it: DataCollector marks an episode cut short by a
/// reset the same way); is_success of every row; `seed` where its reset was seeded.
MinariEpisode ToMinariEpisode(const EpisodeRecord& episode, std::optional<uint64_t> seed,
                              int obs_dim);

/// A dataset episode as a trajectory episode (index = its id): the observation rows, its
/// float32 actions (replayed on Gymnasium's float32 path), rewards, and is_success (the
/// dataset's, else computed with `spec`'s threshold); `file` names the dataset file.
TrajectoryEpisode FromMinariEpisode(const MinariEpisode& episode, const EnvSpec& spec,
                                    const std::string& file);

/// How a dataset episode starts: its `seed`, else its first observation (desired_goal[0]; the
/// object's position and rotation from observation[0] for object tasks).
EpisodeStart MinariEpisodeStart(const MinariEpisode& episode, const EnvSpec& spec);

}  // namespace fetchscope
