// record --from RUN_DIR | TRAJECTORY_JSON | DATASET, once cli/record_from.cc has checked its
// flags: the source read (src/episode_source.h: TrajectorySource) and, for a Minari dataset
// (dataset/minari_source.h), replayed once without rendering to measure how far each episode
// drifts from it (MeasureDivergence), never fatal; what is found is said per episode. The
// manifest's entries for it: AddDivergence (run/record_command.h).
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "src/assets.h"
#include "src/episode_source.h"

namespace fetchscope {

/// What record --from reads the source with.
struct FromRequest {
  std::string from;                   ///< --from
  std::filesystem::path minari_root;  ///< the datasets root (MinariRoot; a dataset's only)
  int episodes = 0;                   ///< --episodes where given, else 0
  std::string env_id;                 ///< --env-id where given, else ""
  double tolerance = 1e-6;            ///< --tolerance
  std::optional<AssetSource> assets;  ///< --assets, resolved, where given
  bool quiet = false;                 ///< -q: print nothing
  bool tolerance_given = false;       ///< --tolerance was given (a dataset's wrong env is let pass)
};

/// Reads --from: a recording (LoadTrajectorySource) or a Minari dataset (LoadMinariSource),
/// which is then replayed once without rendering to measure its divergence; prints what was
/// found and, per episode, the reset used and the divergence (unless quiet). Throws as those do,
/// and UsageError where a dataset without env_spec resets unlike --env-id's env (unless
/// tolerance_given).
TrajectorySource LoadRecordFromSource(const FromRequest& request);

/// One episode's divergence as record prints it, e.g. "episode 2: reset from its first
/// observation; diverges at step 17, observation[3] off by 0.0012 (tolerance 1e-06)".
std::string DescribeDivergence(int k, const EpisodeDivergence& d);

}  // namespace fetchscope
