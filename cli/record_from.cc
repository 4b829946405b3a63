#include "cli/record_from.h"

#include <algorithm>

#include "base/errors.h"
#include "dataset/minari_format.h"
#include "dataset/minari_source.h"
#include "src/assets.h"

namespace fetchscope::cli {

void AddFromOption(CLI::App* sub, std::string* from, double* tolerance) {
  sub->add_option(
      "--from", *from,
      "Re-render recorded episodes: a run folder (its episode_NNN.json), one trajectory JSON, "
      "or a Minari dataset (its id under --minari-root, its folder, or its main_data.hdf5). "
      "Env, seed, policy, steps and episodes come from it; camera, overlay, size, --layers and "
      "the rest are free. A recording is checked step by step against the recorded "
      "observation; the first difference stops the run, before any file, with its episode, "
      "step and value. An episode recorded incomplete (cut short by SIGINT) stays incomplete. "
      "A dataset: each episode resets with its seed, else from its first observation; its "
      "float32 actions are replayed and any drift beyond --tolerance is reported per episode "
      "(console, manifest, report), never fatal; --episodes N takes its first N episodes, "
      "--env-id names the env of a dataset without env_spec; the ghost overlay shows the "
      "dataset's own achieved goal");
  sub->add_option("--tolerance", *tolerance,
                  "record --from DATASET: largest |replayed - recorded| observation value that "
                  "is not a divergence")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e300));
}

void CheckFromFlags(const CLI::App& sub, const std::string& from, bool dataset) {
  for (const char* flag :
       {"--env-id", "--seed", "--policy", "--episodes", "--steps", "--shard", "--shard-count"}) {
    if (dataset && (std::string(flag) == "--env-id" || std::string(flag) == "--episodes")) {
      continue;
    }
    if (sub.count(flag) > 0) {
      throw UsageError(std::string(flag) + " cannot be used with --from: the env, seed, policy, " +
                       "steps and episodes come from " +
                       (dataset ? "the dataset '" : "the trajectory '") + from + "'");
    }
  }
  if (!dataset && sub.count("--tolerance") > 0) {
    throw UsageError("--tolerance applies to --from DATASET (a Minari dataset); a recording '" +
                     from + "' is checked exactly");
  }
}

TrajectorySource LoadFromSource(const CLI::App& sub, const FromOptions& o) {
  const bool dataset = !IsTrajectoryPath(o.from);
  CheckFromFlags(sub, o.from, dataset);
  FromRequest request;
  request.from = o.from;
  if (dataset) request.minari_root = MinariRoot(o.minari_root);
  request.episodes = o.episodes;
  request.env_id = o.env_id;
  request.tolerance = o.tolerance;
  if (!o.assets.empty()) request.assets = ResolveAssets(o.assets);
  request.quiet = o.quiet;
  request.tolerance_given = sub.count("--tolerance") > 0;
  return LoadRecordFromSource(request);
}

void ApplyFromSource(const TrajectorySource& source, const CLI::App& sub, std::string* env_id,
                     std::string* seed, std::string* policy, int* steps, int* episodes,
                     std::string* assets) {
  CheckFromFlags(sub, source.path, source.dataset);
  *env_id = source.env_id;
  *seed = std::to_string(source.seed);
  *policy = source.policy.empty() ? "unknown" : source.policy;
  *steps = std::max(1, source.max_steps);
  *episodes = source.episodes.rbegin()->first + 1;
  if (sub.count("--assets") == 0) *assets = SourceAssets(source);
}

}  // namespace fetchscope::cli
