// Splitting a batch of episodes across machines: --shard I/N, Slurm job arrays and
// Kubernetes Indexed Jobs. Episode k belongs to shard k mod N, so the shards of one run never
// overlap and together hold every episode; names and seeds derive from k alone.
#pragma once

#include <functional>
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

/// Looks up an environment variable (nullptr when unset); std::getenv by default.
using EnvLookup = std::function<const char*(const char*)>;

/// Parses "I/N" (0 <= I < N). Throws UsageError naming the text and the accepted form.
Shard ParseShard(const std::string& text);

/// The shard of this process. In order: `flag` (--shard I/N) if not empty; else
/// JOB_COMPLETION_INDEX with `shard_count` (--shard-count N, 0 = not given); else
/// SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT (offset by SLURM_ARRAY_TASK_MIN and divided
/// by SLURM_ARRAY_TASK_STEP when those are set); else the whole run (0/1).
///
/// `run_shards` is the number of shards of the run already in --out (RunShardCount; 0: none).
/// A Slurm array that is not the whole of that run (a resubmission of some indices: --array=1 or
/// --array=1,3) records shard SLURM_ARRAY_TASK_ID of `run_shards`: its task ids are the shard
/// indices. Without such a run, an array that is not a range (--array=2,5,7: MAX is not
/// MIN + (COUNT-1)*STEP) is refused in every task, before anything is recorded.
/// Throws UsageError, naming the variable and its value, for a malformed or out-of-range value,
/// for JOB_COMPLETION_INDEX without --shard-count, and for --shard-count without
/// JOB_COMPLETION_INDEX or disagreeing with --shard.
Shard ResolveShard(const std::string& flag, int shard_count, const EnvLookup& env = nullptr,
                   int run_shards = 0);

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
