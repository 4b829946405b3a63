// --shard I/N, --shard-count N and the job-array environment variables (Slurm job arrays,
// Kubernetes Indexed Jobs) as the user gave them, and their parsers: the command line turns
// them into run/shard.h's typed Shard here, once, in the parent; run/ never sees the text.
#pragma once

#include <functional>
#include <string>

#include "run/shard.h"

namespace fetchscope::cli {

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

}  // namespace fetchscope::cli
