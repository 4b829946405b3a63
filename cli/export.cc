// fetchscope export: a run folder's episode_NNN.json files, or a trajectory JSON (rollout
// --json-out), written as a Minari dataset (dataset/minari_writer.h).
#include <signal.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <regex>

#include "base/confined_file.h"
#include "base/errors.h"
#include "base/stop_signal.h"
#include "cli/command.h"
#include "cli/common.h"
#include "dataset/minari_format.h"
#include "run/episode_output.h"
#include "run/minari_output.h"
#include "run/progress.h"
#include "src/env_spec.h"
#include "src/trajectory.h"

namespace fetchscope::cli {
namespace {

namespace fs = std::filesystem;

struct ExportOptions {
  std::string input;        // RUN_DIR or TRAJ.json
  std::string minari;       // the dataset id
  std::string minari_root;  // --minari-root
  bool overwrite = false;
  bool include_incomplete = false;  // --include-incomplete
  DatasetAuthor author;
};

// The trajectory of a file, or of every episode_NNN.json of a run folder (one env id and seed)
Trajectory ReadInput(const std::string& input) {
  std::error_code ec;
  if (!fs::is_directory(input, ec)) {
    if (!fs::exists(input, ec)) throw UsageError("export: no such file or folder '" + input + "'");
    return ReadTrajectory(input);  // a regular file of at most kMaxJsonFileBytes
  }
  static const std::regex kEpisodeFile(R"(episode_\d+\.json)");
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(input, ec)) {
    // every one: one that leads outside the folder, or is not a regular file, is refused
    const std::string name = entry.path().filename().string();
    if (std::regex_match(name, kEpisodeFile)) {
      files.push_back(ResolveInside(input, name, "export: " + Quoted(input) + " holds"));
    }
  }
  if (files.empty()) {
    throw UsageError("export: folder '" + input + "' holds no episode_NNN.json trajectory");
  }
  std::sort(files.begin(), files.end());
  Trajectory all;
  std::map<int, TrajectoryEpisode> episodes;
  for (size_t i = 0; i < files.size(); ++i) {
    Trajectory t = ReadTrajectory(files[i].string());
    if (i == 0) {
      all = t;
      all.episodes.clear();
    } else if (t.env_id != all.env_id || t.seed != all.seed) {
      throw RunError("export: " + files[i].string() + " is from another run (" + t.env_id +
                     ", seed " + std::to_string(t.seed) + ") than " + files[0].string());
    }
    for (TrajectoryEpisode& e : t.episodes) {
      const int index = e.index;
      if (!episodes.emplace(index, std::move(e)).second) {
        throw RunError("export: episode " + std::to_string(index) + " is in two files");
      }
    }
  }
  for (auto& [index, e] : episodes) all.episodes.push_back(std::move(e));
  return all;
}

// Refuses episodes an interrupted run cut off (unless --include-incomplete), naming them; with
// it, says that their last step is marked truncated as DataCollector marks an episode it stops.
void CheckComplete(const Trajectory& t, const ExportOptions& o) {
  std::string cut;
  int count = 0;
  std::error_code ec;
  const bool folder = fs::is_directory(o.input, ec);  // name each episode's file
  for (const TrajectoryEpisode& e : t.episodes) {
    if (e.complete) continue;
    cut += (count++ ? ", " : "") + std::to_string(e.index) + " (" +
           std::to_string(e.steps.size() - 1) + " steps" +
           (!folder || e.file.empty() ? "" : ", " + fs::path(e.file).filename().string()) + ")";
  }
  if (count == 0) return;
  const std::string which = (count == 1 ? "episode " : "episodes ") + cut;
  if (!o.include_incomplete) {
    throw UsageError("export: " + o.input + ": " + which + (count == 1 ? " is" : " are") +
                     " incomplete (the run was interrupted): `fetchscope record --resume` "
                     "finishes a run folder; --include-incomplete exports it as it is");
  }
  std::fprintf(stderr,
               "export: %s incomplete (cut off by an interrupt, not by the TimeLimit): included "
               "(--include-incomplete), the last step marked truncated, as Minari's "
               "DataCollector marks an episode it stops\n",
               which.c_str());
}

int RunExport(const ExportOptions& o) {
  InstallStopSignals();  // SIGINT/SIGTERM: stop, leave nothing, keep an old dataset
  const Trajectory t = ReadInput(o.input);
  const EnvSpec& spec = FindEnvSpec(t.env_id);
  CheckComplete(t, o);
  OutputRun run;
  run.command = "export";
  run.spec = &spec;
  run.seed = t.seed;
  run.seed_text = std::to_string(t.seed);
  run.policy = t.policy;
  run.steps = LongestEpisodeSteps(t);  // the TimeLimit they ran under
  run.source = o.input;
  MinariOutput output({o.minari,
                       MinariRoot(o.minari_root),
                       o.overwrite,
                       o.author.name,
                       o.author.email,
                       nullptr,
                       {}});
  std::string path;
  ProgressReporter progress =
      ProgressReporter::ForLongRuns("export", static_cast<int>(t.episodes.size()), 1, "episodes");
  try {
    path = WriteEpisodes(t, run, output, [&] { progress.EpisodeDone(1); });
    progress.Clear();
  } catch (const MinariInterrupted& e) {
    progress.Clear();
    std::fprintf(stderr, "export: %s; nothing written%s\n", e.what(),
                 o.overwrite ? ", the existing dataset is unchanged" : "");
    return 128 + e.signal;
  }
  size_t steps = 0;
  for (const TrajectoryEpisode& e : t.episodes) steps += e.steps.size() - 1;
  std::printf("%s: %zu episode(s), %zu steps\nwrote Minari dataset %s at %s\n", spec.id.c_str(),
              t.episodes.size(), steps, o.minari.c_str(), path.c_str());
  return 0;
}

}  // namespace

Command AddExport(CLI::App& app) {
  auto o = std::make_shared<ExportOptions>();
  CLI::App* sub = app.add_subcommand(
      "export",
      "Write a run folder or trajectory JSON as a Minari dataset (docs/guide/datasets.md)");
  sub->add_option("input", o->input, "A run folder (its episode_NNN.json) or a trajectory JSON")
      ->required();
  sub->add_option("--minari", o->minari,
                  "Minari dataset id, (namespace/)name-vN, e.g. fetchscope/FetchPush/scripted-v0")
      ->required();
  sub->add_option("--minari-root", o->minari_root,
                  "Datasets root (default $MINARI_DATASETS_PATH, else ~/.minari/datasets)");
  sub->add_flag("--overwrite", o->overwrite, "Replace an existing dataset of that id");
  sub->add_flag("--include-incomplete", o->include_incomplete,
                "Also export episodes an interrupted run cut off (their last step marked "
                "truncated); without it they are refused");
  AddDatasetAuthorOptions(sub, &o->author);
  return {sub, [o] { return RunExport(*o); }};
}

}  // namespace fetchscope::cli
