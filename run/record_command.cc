#include "run/record_command.h"

#include <signal.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "base/errors.h"
#include "base/stop_signal.h"
#include "encode/episode_sink.h"
#include "encode/video_format.h"
#include "render/layers.h"
#include "run/minari_output.h"
#include "run/progress.h"
#include "run/run_files.h"
#include "run/run_folder.h"
#include "run/run_summary.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;

// The GPUs and the encoder, decided once (driver work in a child process); without mp4 no
// H.264 is encoded, and nothing is probed for it.
NodeProbe ProbeRecordNode(RecordJob* job) {
  RecordPlan& plan = job->plan;
  const bool h264 = EncodesH264(plan.formats);
  const NodeProbe node = ProbeNode(plan.view, h264 ? &plan.video : nullptr);
  plan.gpu = node.gpu;
  if (h264) plan.video.codec = node.codec.codec;
  if (!node.warnings.empty() && !job->quiet) {
    std::fprintf(stderr, "fetchscope: warning: %s\n", node.warnings.c_str());
  }
  const std::string gif_note =
      GifHudNote(MakeEpisodeSinkOptions(plan), plan.view.render.width, plan.view.render.height);
  if (!gif_note.empty() && job->hud && !job->quiet) {
    std::fprintf(stderr, "fetchscope: note: %s\n", gif_note.c_str());
  }
  return node;
}

RunFolderRequest MakeRunFolderRequest(const RecordJob& job, const RunParameters& parameters) {
  const Shard shard = job.shard;
  RunFolderRequest request;
  request.out = job.plan.out;
  request.mode = ParseReuseMode(job.overwrite, job.resume);
  request.manifest_name = ShardManifestName(shard);
  request.sharded = shard.sharded();
  request.owns = [shard](int k) { return shard.Owns(k); };
  request.episodes = job.episodes;
  request.parameters = parameters;
  request.sources = {{"--from", job.from_option}};
  if (!job.replay_file.empty()) request.sources.push_back({"--policy", job.replay_file});
  request.report = job.report && !shard.sharded();
  return request;
}

// --resume of a whole run: say so, change nothing; a run killed between its manifest and its
// report gets the report now.
int FinishCompleteRun(const RecordJob& job, const RunFolder& folder) {
  const std::string& out = job.plan.out;
  if (!job.quiet) std::fprintf(stderr, "%s\n", AlreadyCompleteText(out, folder.kept()).c_str());
  const fs::path manifest_path = fs::path(out) / ShardManifestName(job.shard);
  if (job.report && !job.shard.sharded() &&
      !fs::exists(manifest_path.parent_path() / kReportFileName)) {
    job.write_report(manifest_path.string());
  }
  return 0;
}

// Records the folder's episodes still to do on the scheduler (nothing after an early signal).
ScheduleResult ScheduleRecord(const RecordJob& job, const RunFolder& folder,
                              ProgressReporter& progress, int early_signal) {
  ScheduleResult result;
  if (early_signal) {
    result.signal = early_signal;
    result.jobs = job.jobs;
    result.missing = folder.todo();
    return result;
  }
  ScheduleOptions schedule;
  schedule.episodes = folder.todo();
  schedule.jobs = job.jobs;
  schedule.mode = job.mode;
  schedule.on_progress = [&](int n) { progress.Frames(n); };
  // an episode an interruption ended is kept, but not counted as done
  schedule.on_done = [&](int, const nlohmann::json& result) {
    const nlohmann::json* entry = result.contains("entry") ? &result["entry"] : nullptr;
    if (!entry || entry->value("complete", true)) progress.EpisodeDone();
  };
  return RecordEpisodes(job.plan, schedule);
}

// The run folder's episode files, read back as export reads them, written as the datasets.
int WriteRecordDatasets(const RecordJob& job) {
  const std::string& out = job.plan.out;
  const TrajectorySource run = LoadTrajectorySource(out);
  Trajectory t;
  t.env_id = run.env_id;
  t.seed = run.seed;
  t.policy = run.policy;
  for (const auto& [k, episode] : run.episodes) t.episodes.push_back(episode);
  std::string advice, what;
  std::optional<MinariOutput> minari;
  std::optional<RobomimicOutput> robomimic;
  std::vector<EpisodeOutput*> outputs;
  if (job.minari) {
    what = "record --minari";
    outputs.push_back(&minari.emplace(*job.minari));
    // a dataset of state alone can be written again from the run folder
    if (!job.plan.pixels.stages()) {
      advice = "; the run is kept in " + out + ": `fetchscope export " + out + " --minari " +
               job.minari->dataset_id +
               (job.minari_root_given.empty() ? "" : " --minari-root " + job.minari_root_given) +
               (job.overwrite ? " --overwrite" : "") + "` writes the dataset from it";
    }
  }
  if (job.robomimic) {
    what = what.empty() ? "record --robomimic" : "record --minari/--robomimic";
    outputs.push_back(&robomimic.emplace(*job.robomimic));
  }
  // the datasets, the episodes they keep, then each episode's staging file removed
  EpisodeOutputs all(outputs);
  SelectedEpisodes selected(all, job.keep_successful, job.shard.index, job.shard.count);
  EpisodeOutput& chosen =
      job.keep_successful || job.shard.sharded() ? static_cast<EpisodeOutput&>(selected) : all;
  std::optional<StagingConsumer> consumer;
  if (job.plan.pixels.stages()) consumer.emplace(chosen, job.plan.pixels.staging);
  EpisodeOutput& output = consumer ? static_cast<EpisodeOutput&>(*consumer) : chosen;
  try {
    WriteEpisodes(t, RecordOutputRun(job), output);
  } catch (const MinariInterrupted& e) {
    std::fprintf(stderr, "%s: %s%s\n", what.c_str(), e.what(), advice.c_str());
    return 128 + e.signal;
  } catch (const std::exception& e) {
    throw RunError(what + ": " + std::string(e.what()) + advice);
  }
  if (job.keep_successful) {
    std::printf("kept %zu successful episode(s) of %d tried\n", selected.kept().size(),
                selected.tried());
  }
  if (minari) {
    std::printf("wrote Minari dataset %s at %s\n", job.minari->dataset_id.c_str(),
                minari->written().c_str());
  }
  if (robomimic) std::printf("wrote robomimic file %s\n", job.robomimic->file.c_str());
  return 0;
}

}  // namespace

OutputRun RecordOutputRun(const RecordJob& job) {
  const RecordPlan& plan = job.plan;
  OutputRun run;
  run.command = "record";
  run.spec = plan.spec;
  run.seed = plan.seed;
  run.seed_text = plan.seed_text;
  run.policy = plan.policy.text;
  run.episodes = job.episodes_requested;
  run.steps = plan.steps;
  // a dataset's episodes, and a recording's placed by hand (no seed resets to them)
  if (plan.from) {
    for (const auto& [k, start] : plan.from->starts) run.episode_seeds[k] = start.seed;
  }
  return run;
}

void CheckRecordRobomimic(const RecordJob& job) { CheckRobomimicOutput(*job.robomimic); }

void CheckRecordMinari(const RecordJob& job) {
  // an existing id or an unwritable datasets folder fails now, not after the run (an existing
  // one is replaced after the run, atomically, with --overwrite). A shard writes its own dataset,
  // which records the shard: merge-datasets joins them.
  CheckMinariOutput(*job.minari, RecordOutputRun(job));
}

int RecordRun(RecordJob job) {
  const NodeProbe node = ProbeRecordNode(&job);
  // never two runs in one folder; a failure below leaves nothing this run made. From here a
  // SIGINT/SIGTERM is an interruption (the scheduler takes over the handlers when it starts).
  InstallStopSignals();
  const RunParameters parameters = RecordParameters(job);
  RunFolder folder(MakeRunFolderRequest(job, parameters));
  if (!folder.notice().empty() && !job.quiet) {
    std::fprintf(stderr, "fetchscope: note: %s\n", folder.notice().c_str());
  }
  if (folder.already_complete()) return FinishCompleteRun(job, folder);
  // --obs-camera: the workers' images wait beside the run folder until the dataset is written
  std::optional<PixelStaging> staging;
  if (job.plan.pixels.stages()) {
    staging.emplace(fs::absolute(job.plan.out).parent_path());
    job.plan.pixels.staging = staging->path();
    if (job.minari && job.plan.pixels.setup.enabled()) {
      job.minari->staging = staging->path();
      job.minari->pixels = &job.plan.pixels.layout;
    }
    if (job.robomimic) {
      job.robomimic->staging = staging->path();
      job.robomimic->pixels = &job.plan.pixels.layout;
    }
  }
  const int early_signal = StopSignal();  // before the scheduler: record nothing
  ProgressReporter progress("record", static_cast<int>(folder.todo().size()), job.plan.steps + 1,
                            job.quiet);
  const ScheduleResult result = ScheduleRecord(job, folder, progress, early_signal);
  const std::map<int, EpisodeResult> results = RecordResults(result);
  const bool any_complete = std::any_of(results.begin(), results.end(), [](const auto& r) {
    return r.second.entry.complete.value_or(false);
  });
  if (result.signal && !any_complete && folder.replacing()) {
    // interrupted before --overwrite recorded a whole episode: the earlier run stays as it was
    if (!job.quiet) {
      std::fprintf(stderr,
                   "record: interrupted before any episode was complete; the earlier "
                   "run in %s is kept as it was\n",
                   job.plan.out.c_str());
    }
    return 128 + result.signal;  // `folder` removes this run's files, puts the earlier run back
  }
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - job.wall_start).count();
  RecordTally tally = TallyRecordResults(results);
  tally.entries = folder.WithKept(std::move(tally.entries));
  if (result.results.empty() && result.signal == 0 && !result.failures.empty()) {
    // nothing was recorded: no manifest, and `folder` removes what this run made
    const WorkerFailure& first = result.failures.front();
    if (first.usage) throw UsageError(first.message);
    throw RunError(DescribeFailures(result));
  }
  const Manifest manifest =
      BuildRecordManifest(job, node, result, std::move(tally), wall, progress.frames(), parameters,
                          job.resume && !folder.kept().empty());
  const fs::path manifest_path = fs::path(job.plan.out) / ShardManifestName(job.shard);
  WriteManifest(manifest_path, manifest);
  folder.Commit();
  const std::string summary =
      RecordSummaryText(manifest, result.results.size(), folder.kept().size(), job.plan.out);
  progress.Done(summary);
  const size_t rest = summary.find("record: to record the rest");
  if (job.quiet && rest != std::string::npos) {  // even --quiet: a batch job's log needs the way on
    std::fprintf(stderr, "%s\n", summary.substr(rest).c_str());
  }
  // a shard's episodes are only part of the run: merge-manifests writes the run's report
  if (job.report && !job.shard.sharded()) job.write_report(manifest_path.string());
  if (result.signal) return 128 + result.signal;
  if (!result.failures.empty()) {
    throw RunError(DescribeFailures(result) + "; the manifest lists the missing episodes (" +
                   std::to_string(result.missing.size()) + "): --resume records them");
  }
  return job.minari || job.robomimic ? WriteRecordDatasets(job) : 0;
}

}  // namespace fetchscope
