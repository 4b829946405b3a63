#include "cli/record_from.h"

#include <algorithm>

#include "base/errors.h"

namespace fetchscope::cli {

void AddFromOption(CLI::App* sub, std::string* from) {
  sub->add_option("--from", *from,
                  "Re-render recorded episodes: a run folder (its episode_NNN.json) or one "
                  "trajectory JSON. Env, seed, policy, steps and episodes come from it; camera, "
                  "overlay, size, --layers and the rest are free. Each replayed step is checked "
                  "against the recorded observation; the first difference stops the run, before "
                  "any file, with its episode, step and value. An episode recorded incomplete "
                  "(cut short by SIGINT) stays incomplete");
}

void CheckFromFlags(const CLI::App& sub, const std::string& from) {
  for (const char* flag :
       {"--env-id", "--seed", "--policy", "--episodes", "--steps", "--shard", "--shard-count"}) {
    if (sub.count(flag) > 0) {
      throw UsageError(std::string(flag) + " cannot be used with --from: the env, seed, policy, " +
                       "steps and episodes come from the trajectory '" + from + "'");
    }
  }
}

void ApplyFromSource(const TrajectorySource& source, const CLI::App& sub, std::string* env_id,
                     std::string* seed, std::string* policy, int* steps, int* episodes,
                     std::string* assets) {
  CheckFromFlags(sub, source.path);
  *env_id = source.env_id;
  *seed = std::to_string(source.seed);
  *policy = source.policy.empty() ? "unknown" : source.policy;
  *steps = std::max(1, source.max_steps);
  *episodes = source.episodes.rbegin()->first + 1;
  if (sub.count("--assets") == 0) *assets = SourceAssets(source);
}

}  // namespace fetchscope::cli
