// Merging the shard manifests of one sharded record run (manifest_shard_IIII_of_NNNN.json, or an
// unsplit run's manifest.json) into one manifest listing every episode in order, after checking
// that the shards are of one run (SameRun), and that every episode is there exactly once, complete,
// with its files.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace fetchscope {

/// What to merge, and what the merged manifest records of the merge itself.
struct MergeRequest {
  std::vector<std::string> dirs;  ///< folders holding the shard manifests (and their files)
  std::string out;                ///< the merged manifest ("" = dirs[0]/manifest.json)
  std::string command_line;       ///< the merge's own command line, as recorded
  nlohmann::json versions;        ///< the versions of this build, as recorded
};

/// What the merge wrote.
struct MergeResult {
  std::filesystem::path manifest;  ///< the merged manifest's path
  int shards = 0;                  ///< shard manifests merged
  int shard_count = 1;             ///< the run's number of shards
  int episodes = 0;                ///< episodes in the run
  int successes = 0;               ///< of them, successful
};

/// Merges the manifests in `request.dirs` and writes the result. Throws RunError (exit 1) for a
/// folder without manifests, a manifest that cannot be read, shards of different runs (naming the
/// first differing record option:
/// "'B' (shard 1/2) belongs to another run: --msaa is 4 there but auto in 'A' (shard 0/2); ..."), a
/// shard or episode that appears twice, and a run that is incomplete (naming every missing,
/// interrupted or incomplete shard and missing file).
MergeResult MergeShardManifests(const MergeRequest& request);

}  // namespace fetchscope
