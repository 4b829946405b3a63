// Replaying one Minari episode on our env and measuring how far it drifts from the dataset (a
// seedless episode continues the generator here). record --from DATASET does the same through
// src/episode_source.h (MeasureDivergence), rebuilding a seedless reset from its first row.
#pragma once

#include <string>

#include "dataset/minari_format.h"
#include "src/fetch_env.h"

namespace fetchscope {

/// How a replayed dataset episode compares with the dataset, row by row.
struct MinariDivergence {
  /// "seed": reset with the episode's seed; "continued": it has none, so the reset continued
  /// the generator from the previous one (Gymnasium's behaviour, DataCollector without autoseed)
  std::string reset;
  int first_step = -1;    ///< first row t (0 = the reset) off by more than the tolerance; -1 none
  std::string where;      ///< its first value off, e.g. "observation[3]", "desired_goal[0]"
  double difference = 0;  ///< replayed - recorded there
  double max_difference = 0;  ///< largest |replayed - recorded| over every row
};

/// Resets `env` (with the episode's seed, else continuing its generator), steps the episode's
/// actions on Gymnasium's float32 path (the action space's dtype, as the dataset stores them)
/// and compares every observation, achieved_goal and desired_goal row with the dataset's.
/// `tolerance` bounds |replayed - recorded| (0: bit for bit).
MinariDivergence ReplayMinariEpisode(FetchEnv& env, const MinariEpisode& episode, double tolerance);

}  // namespace fetchscope
