#include "cli/shard_options.h"

#include <algorithm>
#include <cstdlib>

#include "base/errors.h"

namespace fetchscope::cli {
namespace {

// A whole decimal number 0 .. 2^31-1, nothing else (no sign, no spaces, no "3.0").
bool ParseCount(const std::string& text, long* value) {
  if (text.empty() || text.size() > 10) return false;
  for (char c : text) {
    if (c < '0' || c > '9') return false;
  }
  *value = std::strtol(text.c_str(), nullptr, 10);
  return *value <= 2147483647L;
}

// An environment variable as a whole number; throws naming it and its value.
long EnvNumber(const EnvLookup& env, const char* name, bool* present = nullptr) {
  const char* raw = env(name);
  if (present) *present = raw != nullptr;
  if (!raw) return -1;
  long value = 0;
  if (!ParseCount(raw, &value)) {
    throw UsageError(std::string(name) + "='" + raw + "' is not a non-negative whole number");
  }
  return value;
}

}  // namespace

Shard ParseShard(const std::string& text) {
  const size_t slash = text.find('/');
  long index = 0, count = 0;
  if (slash == std::string::npos || !ParseCount(text.substr(0, slash), &index) ||
      !ParseCount(text.substr(slash + 1), &count)) {
    throw UsageError("--shard '" + text +
                     "' is not of the form I/N (e.g. 0/4: the first of 4 shards)");
  }
  if (count < 1) throw UsageError("--shard '" + text + "': N must be at least 1");
  if (index >= count) {
    throw UsageError("--shard '" + text + "': I must be below N (shards are numbered 0 .. " +
                     std::to_string(count - 1) + ")");
  }
  return {static_cast<int>(index), static_cast<int>(count), "--shard"};
}

Shard ResolveShard(const std::string& flag, int shard_count, const EnvLookup& lookup,
                   int run_shards) {
  const EnvLookup env =
      lookup ? lookup : [](const char* name) -> const char* { return std::getenv(name); };
  if (shard_count < 0)
    throw UsageError("--shard-count " + std::to_string(shard_count) + " must be at least 1");
  if (!flag.empty()) {
    Shard shard = ParseShard(flag);
    if (shard_count > 0 && shard_count != shard.count) {
      throw UsageError("--shard-count " + std::to_string(shard_count) + " disagrees with --shard " +
                       flag);
    }
    return shard;
  }

  bool has_index = false;
  const long job_index = EnvNumber(env, "JOB_COMPLETION_INDEX", &has_index);
  if (has_index) {
    if (shard_count == 0) {
      throw UsageError("JOB_COMPLETION_INDEX=" + std::to_string(job_index) +
                       " is set but the number of shards is not: pass --shard-count N (the Job's "
                       "completions), or --shard I/N");
    }
    if (job_index >= shard_count) {
      throw UsageError("JOB_COMPLETION_INDEX=" + std::to_string(job_index) +
                       " must be below --shard-count " + std::to_string(shard_count));
    }
    return {static_cast<int>(job_index), shard_count, "JOB_COMPLETION_INDEX"};
  }
  if (shard_count > 0) {
    throw UsageError("--shard-count " + std::to_string(shard_count) +
                     " needs JOB_COMPLETION_INDEX in the environment (a Kubernetes Indexed Job); "
                     "elsewhere use --shard I/N");
  }

  bool has_task = false;
  const long task = EnvNumber(env, "SLURM_ARRAY_TASK_ID", &has_task);
  if (!has_task) return {};
  bool has_count = false;
  const long count = EnvNumber(env, "SLURM_ARRAY_TASK_COUNT", &has_count);
  if (!has_count) {
    throw UsageError("SLURM_ARRAY_TASK_ID=" + std::to_string(task) +
                     " is set but SLURM_ARRAY_TASK_COUNT is not: pass --shard I/N");
  }
  if (count < 1)
    throw UsageError("SLURM_ARRAY_TASK_COUNT=" + std::to_string(count) + " must be at least 1");
  // --array=1-16 or --array=0-30:2 number tasks from MIN in steps of STEP: shard = (ID-MIN)/STEP
  const long min = std::max(0L, EnvNumber(env, "SLURM_ARRAY_TASK_MIN"));
  const long step = std::max(1L, EnvNumber(env, "SLURM_ARRAY_TASK_STEP"));
  bool has_max = false;
  const long max = EnvNumber(env, "SLURM_ARRAY_TASK_MAX", &has_max);
  const bool range = !has_max || max == min + (count - 1) * step;
  if (run_shards > 0 && (!range || count != run_shards)) {
    // some indices of the run in --out, resubmitted: the task ids are its shard indices
    if (task >= run_shards) {
      throw UsageError("SLURM_ARRAY_TASK_ID=" + std::to_string(task) +
                       " is not a shard of the run in --out, which has " +
                       std::to_string(run_shards) + " shards (0.." +
                       std::to_string(run_shards - 1) +
                       "): resubmit its missing shards by their index (--array=I,J...)");
    }
    return {static_cast<int>(task), run_shards, "SLURM_ARRAY_TASK_ID"};
  }
  if (!range) {
    throw UsageError("SLURM_ARRAY_TASK_MAX=" + std::to_string(max) + " with SLURM_ARRAY_TASK_MIN=" +
                     std::to_string(min) + ", SLURM_ARRAY_TASK_STEP=" + std::to_string(step) +
                     " and SLURM_ARRAY_TASK_COUNT=" + std::to_string(count) +
                     ": the array is not a range (--array=2,5,7?), so its tasks cannot be "
                     "numbered as shards; use --array=0-" +
                     std::to_string(count - 1) + " or pass --shard I/N");
  }
  if (task < min || (task - min) % step != 0 || (task - min) / step >= count) {
    throw UsageError("SLURM_ARRAY_TASK_ID=" + std::to_string(task) + " does not fit an array of " +
                     std::to_string(count) + " task(s) from " + std::to_string(min) +
                     " in steps of " + std::to_string(step) + ": use --array=0-" +
                     std::to_string(count - 1) + " or pass --shard I/N");
  }
  return {static_cast<int>((task - min) / step), static_cast<int>(count), "SLURM_ARRAY_TASK_ID"};
}

}  // namespace fetchscope::cli
