#include "run/record_from_source.h"

#include <cmath>
#include <cstdio>

#include "base/errors.h"
#include "dataset/minari_format.h"
#include "dataset/minari_source.h"
#include "src/assets.h"
#include "src/observation_layout.h"

namespace fetchscope {
namespace {

std::string Num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

// "object_pos.x (observation[3])", or the value's index alone where it has no other name
std::string Place(const std::string& component, const std::string& where) {
  return component.empty() || component == where ? where : component + " (" + where + ")";
}

// "largest difference 0.0642 rad in object_rot.z (observation[11]) at step 27"
std::string Largest(const EpisodeDivergence& d) {
  if (d.max_step < 0) return "largest difference 0";
  if (!std::isfinite(d.max_difference)) {
    return "largest difference not finite, in " + Place(d.max_component, d.max_where) +
           " at step " + std::to_string(d.max_step);
  }
  return "largest difference " + FormatInDisplayUnit(d.max_signed, d.max_unit) + " in " +
         Place(d.max_component, d.max_where) + " at step " + std::to_string(d.max_step);
}

}  // namespace

std::string DescribeDivergence(int k, const EpisodeDivergence& d) {
  std::string line =
      "episode " + std::to_string(k) + ": reset " +
      (d.reset == "seed"                  ? std::string("from its seed")
       : d.reset == "continued generator" ? "by continuing the generator of episode " +
                                                std::to_string(d.continued_from) + "'s seed"
                                          : "from its first observation") +
      "; ";
  if (d.first_step < 0) {
    return line + "replays within " + Num(d.tolerance) + " (" + Largest(d) + ")";
  }
  if (d.first_step == 0) line += "the reset differs from the dataset's first row: ";
  return line + "diverges at step " + std::to_string(d.first_step) + " in " +
         Place(d.component, d.where) + " by " + FormatInDisplayUnit(d.difference, d.unit) +
         " (tolerance " + Num(d.tolerance) + "); " + Largest(d);
}

TrajectorySource LoadRecordFromSource(const FromRequest& r) {
  if (IsTrajectoryPath(r.from)) return LoadTrajectorySource(r.from);
  MinariSourceRequest request;
  request.what = r.from;
  request.root = r.minari_root;
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
  // a dataset the genuine env made: its assets, where a gymnasium_robotics is installed
  if (!r.assets && found.genuine_env) {
    const AssetSource automatic = ResolveAssets("auto");
    if (automatic.kind != "bundled") {
      source.assets = automatic;
      if (!r.quiet) {
        std::fprintf(stderr,
                     "record --from: the dataset's env_spec is Gymnasium-Robotics' own: replaying "
                     "on its assets at %s (--assets auto: %s)\n",
                     automatic.root.c_str(), automatic.origin.c_str());
      }
    } else {
      // measured: 10 random-policy episodes (seed 0, 50 steps) per task played on the genuine
      // assets, replayed on the bundled models; largest gripper/object position difference
      const Task task = FindEnvSpec(source.env_id).task;
      const char* drift = task == Task::kReach          ? "6 mm"
                          : task == Task::kPush         ? "0.02 mm"
                          : task == Task::kPickAndPlace ? "4 mm"
                                                        : "14 mm";
      std::fprintf(stderr,
                   "record --from: the dataset's env_spec is Gymnasium-Robotics' own, and no "
                   "installed gymnasium_robotics was found: replaying on the bundled models, "
                   "which differ slightly from its assets, so the replay drifts (on %s, "
                   "positions up to about %s off after 50 random-policy steps); pass --assets "
                   "DIR (a gymnasium_robotics envs/assets folder) or set FETCHSCOPE_ASSETS to "
                   "replay exactly\n",
                   source.env_id.c_str(), drift);
    }
  }
  FetchEnv env(FindEnvSpec(source.env_id),
               r.assets ? *r.assets : ResolveAssets(SourceAssets(source)));
  MeasureDivergence(env, &source);
  // a reset unlike the dataset's first row, on an env the dataset did not name: the wrong env
  if (!found.env_from_spec && !r.tolerance_given) {
    for (const auto& [k, d] : source.divergence) {
      if (d.first_step != 0) continue;
      throw UsageError("record --from: " + DescribeDivergence(k, d) +
                       ". The dataset has no env_spec, and its reset is not one of --env-id " +
                       source.env_id +
                       ": name the env it was made on with --env-id (and its assets with "
                       "--assets), or raise --tolerance to render it anyway");
    }
  }
  if (!r.quiet) {
    for (const auto& [k, d] : source.divergence) {
      std::fprintf(stderr, "record --from: %s\n", DescribeDivergence(k, d).c_str());
    }
  }
  return std::move(found.source);
}

}  // namespace fetchscope
