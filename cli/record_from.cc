#include "cli/record_from.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "base/errors.h"
#include "dataset/minari_format.h"
#include "dataset/minari_source.h"
#include "src/assets.h"

namespace fetchscope::cli {
namespace {

std::string Num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

}  // namespace

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

std::string DescribeDivergence(int k, const EpisodeDivergence& d) {
  std::string line = "episode " + std::to_string(k) + ": reset from " +
                     (d.reset == "seed" ? std::string("its seed") : "its first observation") + "; ";
  if (d.first_step < 0) {
    return line + "replays within " + Num(d.tolerance) + " (largest difference " +
           Num(d.max_difference) + ")";
  }
  if (d.first_step == 0) line += "the reset differs from the dataset's first row: ";
  return line + "diverges at step " + std::to_string(d.first_step) + ", " + d.where + " off by " +
         Num(d.difference) + " (tolerance " + Num(d.tolerance) + "; largest difference " +
         Num(d.max_difference) + ")";
}

TrajectorySource LoadFromSource(const CLI::App& sub, const FromRequest& r) {
  if (IsTrajectoryPath(r.from)) {
    CheckFromFlags(sub, r.from);
    return LoadTrajectorySource(r.from);
  }
  CheckFromFlags(sub, r.from, /*dataset=*/true);
  MinariSourceRequest request;
  request.what = r.from;
  request.root = MinariRoot(r.minari_root);
  request.episodes = r.episodes;
  request.env_id = r.env_id;
  request.tolerance = r.tolerance;
  MinariSource found;
  try {
    found = LoadMinariSource(request);
  } catch (const UsageError& e) {
    const std::string what = e.what();
    if (what.rfind("no Minari dataset", 0) != 0) throw;
    throw UsageError("--from '" + r.from +
                     "' is none of what it accepts: a run folder of record, one trajectory "
                     "JSON file, or a Minari dataset (" +
                     what + ")");
  }
  TrajectorySource& source = found.source;
  if (!r.quiet) std::fprintf(stderr, "record --from: %s\n", found.found.c_str());
  // one replay without rendering: the divergence is known (and printed) before any file
  FetchEnv env(FindEnvSpec(source.env_id),
               ResolveAssets(r.assets.empty() ? SourceAssets(source) : r.assets));
  MeasureDivergence(env, &source);
  if (!r.quiet) {
    for (const auto& [k, d] : source.divergence) {
      std::fprintf(stderr, "record --from: %s\n", DescribeDivergence(k, d).c_str());
    }
  }
  return std::move(found.source);
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

void AddDivergence(const TrajectorySource& source, std::vector<ManifestEpisode>* episodes,
                   nlohmann::json* manifest_extra) {
  if (!source.dataset) return;
  (*manifest_extra)["dataset"] = {{"found", source.found}, {"tolerance", source.tolerance}};
  for (ManifestEpisode& e : *episodes) {
    const auto it = source.divergence.find(e.index);
    if (it == source.divergence.end()) continue;
    const EpisodeDivergence& d = it->second;
    e.extra["reset"] = d.reset;
    // a NaN in the dataset makes an infinite difference: null, as JSON has no infinity
    const auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nullptr; };
    nlohmann::json j = {{"first_step", nullptr},
                        {"where", nullptr},
                        {"difference", nullptr},
                        {"max_difference", number(d.max_difference)},
                        {"tolerance", d.tolerance}};
    if (d.first_step >= 0) {
      j["first_step"] = d.first_step;
      j["where"] = d.where;
      j["difference"] = number(d.difference);
    }
    e.extra["divergence"] = j;
  }
}

}  // namespace fetchscope::cli
