// Splitting a batch of episodes across machines: --shard I/N, Slurm job arrays and
// Kubernetes Indexed Jobs. Episode k belongs to shard k mod N, so the shards of one run never
// overlap and together hold every episode; names and seeds derive from k alone.
// cli/shard_options.h turns the option and environment text into a Shard.
#pragma once

#include <string>
#include <vector>

namespace fetchscope {

/// One shard of a run: `index` of `count`, and where that came from.
struct Shard {
  int index = 0;       ///< 0 .. count-1
  int count = 1;       ///< number of shards; 1 = the whole run
  std::string source;  ///< "--shard", "JOB_COMPLETION_INDEX", "SLURM_ARRAY_TASK_ID" or "" (none)

  /// True when the run is split (count > 1).
  bool sharded() const { return count > 1; }
  /// True when episode k belongs to this shard.
  bool Owns(long k) const { return k % count == index; }
};

/// The number of shards of the record run whose shard manifests (manifest_shard_*_of_N.json)
/// are in `out`: N when they all say the same N, else 0 (none, unreadable, or disagreeing).
int RunShardCount(const std::string& out);

/// The episodes of `shard` among 0 .. episodes-1, ascending.
std::vector<int> ShardEpisodes(const Shard& shard, int episodes);

/// The episodes of `shard` among `episodes` (a run's list, ascending), in their order.
std::vector<int> ShardEpisodes(const Shard& shard, const std::vector<int>& episodes);

/// The shard's manifest file name (ManifestFileName): "manifest.json" for an unsplit run, else
/// "manifest_shard_IIII_of_NNNN.json".
std::string ShardManifestName(const Shard& shard);

/// "I/N" for messages.
std::string ShardLabel(const Shard& shard);

}  // namespace fetchscope
