// fetchscope rollout: episodes without rendering, written as trajectory JSON. --jobs runs them
// on the episode scheduler's worker processes; the JSON is byte-identical to --jobs 1.
#include <cstdio>
#include <filesystem>
#include <optional>

#include "base/errors.h"
#include "base/json_util.h"
#include "base/number_format.h"
#include "cli/command.h"
#include "cli/common.h"
#include "cli/jobs_options.h"
#include "cli/look_options.h"
#include "cli/obs_options.h"
#include "cli/resolve.h"
#include "cli/shard_options.h"
#include "cli/view_options.h"
#include "dataset/minari_format.h"
#include "render/view.h"
#include "run/episode_scheduler.h"
#include "run/minari_output.h"
#include "run/pixel_recorder.h"
#include "run/progress.h"
#include "run/robomimic_output.h"
#include "run/rollout_run.h"
#include "src/fetch_env.h"
#include "src/trajectory.h"

namespace fetchscope::cli {
namespace {

namespace fs = std::filesystem;

struct RolloutOptions {
  EnvOptions env;
  int episodes = 1;
  bool episodes_given = false;  // --episodes was on the command line
  int steps = 50;
  PolicyOptions policy;  // --policy, --exec-timeout, --replay-dtype
  std::string json_out;
  int jobs = 1;
  std::string worker_mode = "process";
  std::string minari;       // --minari: a Minari dataset id to write
  std::string minari_root;  // --minari-root
  bool overwrite =
      false;  // replace an existing Minari dataset, or a --json-out file of another env or seed
  DatasetAuthor author;               // --minari-author, --minari-author-email
  std::string signals = "none";       // --signals
  ObsOptions obs;                     // --obs-camera, --obs-size, --obs-layers, --obs-overlay
  LookOptions look;                   // --randomize, --randomize-config (the images' look)
  RobomimicOptions robomimic;         // --robomimic, --no-next-obs, --valid-fraction
  EpisodeSelectionOptions selection;  // --keep, --stop-after-success
  std::string shard;                  // --shard I/N
  int shard_count = 0;                // --shard-count (with JOB_COMPLETION_INDEX)
  std::string backend;                // --backend of the images
};

// The datasets a rollout writes (--minari, --robomimic), their destinations checked now, and the
// staging folder of the images and states the workers stage for them.
class DatasetOutputs {
 public:
  DatasetOutputs(const RolloutOptions& o, const OutputRun& run, PixelPlan pixels,
                 const Shard& shard, RolloutJob* job)
      : o_(o), keep_(KeepSuccessful(o.selection, !o.minari.empty() || !o.robomimic.file.empty())) {
    MinariRequest minari{
        o.minari, MinariRoot(o.minari_root), o.overwrite, o.author.name, o.author.email, nullptr,
        {}};
    RobomimicRequest robomimic{o.robomimic.file,           o.overwrite, !o.robomimic.no_next_obs,
                               o.robomimic.valid_fraction, nullptr,     {}};
    job->pixels = std::move(pixels);
    if (job->pixels.setup.enabled()) {  // images, for the datasets or an exec: policy
      ViewOptions view;
      view.backend = o.backend;
      const ViewSetup gl = ResolveGlView(view);
      job->backend = gl.backend;
      job->gpu = ResolveGpuChoice(gl);
    }
    if (job->pixels.stages()) {
      // the destinations first: nothing is made for a run that cannot write them
      if (!o.minari.empty()) CheckMinariOutput(minari, run);
      if (!o.robomimic.file.empty()) CheckRobomimicOutput(robomimic);
      staging_.emplace(!o.minari.empty() ? minari.root
                                         : fs::absolute(o.robomimic.file).parent_path());
      job->pixels.staging = staging_->path();
      minari.pixels = job->pixels.setup.enabled() ? &job->pixels.layout : nullptr;
      minari.staging = robomimic.staging = staging_->path();
      robomimic.pixels = &job->pixels.layout;
    }
    std::vector<EpisodeOutput*> all;
    if (!o.minari.empty()) all.push_back(&minari_.emplace(minari));
    if (!o.robomimic.file.empty()) all.push_back(&robomimic_.emplace(robomimic));
    if (all.size() == 1) output_ = all.front();
    if (all.size() == 2) output_ = &both_.emplace(all);
    // the episodes kept (--keep successful) and the shard recorded, then each episode's
    // staging file removed once the datasets have it (or have dropped it)
    if (output_ && (keep_ || shard.sharded())) {
      output_ = &selected_.emplace(*output_, keep_, shard.index, shard.count);
    }
    if (output_ && job->pixels.stages()) {
      output_ = &consumer_.emplace(*output_, job->pixels.staging);
    }
  }
  EpisodeOutput* output() { return output_; }
  // "wrote ..." lines for what was written
  std::string Wrote() const {
    std::string s;
    if (keep_ && selected_) {
      s += "kept " + std::to_string(selected_->kept().size()) + " successful episode(s) of " +
           std::to_string(selected_->tried()) + " tried\n";
    }
    if (minari_) s += "wrote Minari dataset " + o_.minari + " at " + minari_->written() + "\n";
    if (robomimic_) s += "wrote robomimic file " + o_.robomimic.file + "\n";
    return s;
  }

 private:
  const RolloutOptions& o_;
  std::optional<PixelStaging> staging_;
  std::optional<MinariOutput> minari_;
  std::optional<RobomimicOutput> robomimic_;
  std::optional<EpisodeOutputs> both_;
  const bool keep_;  // --keep successful
  std::optional<SelectedEpisodes> selected_;
  std::optional<StagingConsumer> consumer_;
  EpisodeOutput* output_ = nullptr;
};

// The images each step renders (--obs-camera) under the looks of --randomize, which needs them.
// Bad assets fail here, before any worker starts.
PixelPlan PlanRolloutPixels(const RolloutOptions& o, const EnvSpec& spec, const AssetSource& assets,
                            const std::optional<LookConfig>& look) {
  FetchEnv check(spec, assets);
  ObsSetup obs = ResolveObs(o.obs, check.model(), kMsaaAuto);
  if (look && look->any() && !obs.enabled()) {
    throw UsageError("--randomize " + o.look.randomize +
                     " draws the look of images, and rollout renders none; accepted: with "
                     "--obs-camera (the dataset's or an exec: policy's images)");
  }
  if (look && look->camera) {  // each episode's jitter moves every camera: poses per step
    for (ObsCamera& camera : obs.cameras) camera.moving = true;
  }
  return PlanPixels(obs, check.model(), !o.minari.empty(), !o.robomimic.file.empty());
}

// parse (AddRollout) -> resolve -> run (RunRolloutJob) -> print.
int RunRollout(const RolloutOptions& o) {
  EpisodeRequest request;
  request.policy = ParsePolicyOptions(o.policy);
  request.episodes = o.episodes;
  request.episodes_given = o.episodes_given;
  request.steps = o.steps;
  const WorkerMode mode = ParseWorkerMode(o.worker_mode);
  // a trajectory JSON replays its own episodes, each under its own index (as record does)
  const ResolvedRun run = ResolveRun(o.env, request);
  const EnvSpec& spec = *run.env.spec;
  const uint64_t seed = run.env.seed;
  const AssetSource& assets = run.env.assets;
  const std::string path = JsonOutPath(o.json_out, "rollout");
  CheckJsonOutReplaces(path, {{"env_id", spec.id}, {"seed", seed}}, o.overwrite);
  const std::optional<LookConfig> look = ResolveLook(o.look);
  const PixelPlan pixels = PlanRolloutPixels(o, spec, assets, look);
  // a shard plays its share of the run's episodes (episode k in shard k mod N), each as in the
  // whole run; merge-datasets puts the shards' datasets together
  const Shard shard = ResolveShard(o.shard, o.shard_count);
  const std::vector<int> episodes = ShardEpisodes(shard, run.episodes);
  const int count = static_cast<int>(episodes.size());
  RolloutJob job;
  job.spec = &spec;
  job.assets = assets;
  job.seed = seed;
  job.seed_text = o.env.seed;
  job.policy = WithExecFields(request.policy, o.policy, spec);
  job.policy_context = &run.policy_context;
  job.steps = o.steps;
  job.look = look;
  job.look_seed = ResolveLookSeed(o.look);
  job.contact_signals = ParseContactSignals(o.signals);
  job.episodes = episodes;
  job.episodes_requested = static_cast<int>(run.episodes.size());
  job.jobs = ResolveJobs(o.jobs, count);
  job.mode = mode;
  job.stop_after_success = o.selection.stop_after_success;
  // the trajectories are kept for --json-out, or stdout when nothing else is written
  job.keep_trajectories = !o.json_out.empty() || (o.minari.empty() && o.robomimic.file.empty());
  DatasetOutputs outputs(o, RolloutOutputRun(job), std::move(pixels), shard, &job);
  job.output = outputs.output();
  // progress on stderr (the JSON may be on stdout): a bar on a terminal, else a line every
  // FETCHSCOPE_PROGRESS_INTERVAL (30 s) of a long run
  ProgressReporter progress = ProgressReporter::ForLongRuns("rollout", count, o.steps, "steps");
  job.on_episode = [&] { progress.EpisodeDone(o.steps); };
  RolloutResult result = RunRolloutJob(job);
  progress.Clear();
  if (result.signal) {
    std::fprintf(stderr, "rollout: %s; nothing written\n", result.stopped.c_str());
    return 128 + result.signal;
  }
  if (o.json_out.empty() && result.output.empty()) {
    const nlohmann::json j =
        TrajectoryJson(spec, assets, seed, o.policy.policy, std::move(result.episodes));
    std::printf("%s\n", DumpJson(j).c_str());
    return 0;
  }
  std::string wrote;
  if (!o.json_out.empty()) {
    WriteJson(path,
              TrajectoryJson(spec, assets, seed, o.policy.policy, std::move(result.episodes)));
    wrote += "wrote " + path + "\n";
  }
  wrote += outputs.Wrote();
  std::printf("%s: %d episode(s) of %d steps, policy %s, seed %s: success %d/%d (%s)\n%s",
              spec.id.c_str(), count, o.steps, o.policy.policy.c_str(), o.env.seed.c_str(),
              result.successes, count, PercentText(result.successes, count).c_str(), wrote.c_str());
  return 0;
}

}  // namespace

Command AddRollout(CLI::App& app) {
  auto o = std::make_shared<RolloutOptions>();
  CLI::App* sub =
      app.add_subcommand("rollout", "Run episodes without rendering and write the trajectory JSON");
  AddEnvOptions(sub, &o->env);
  sub->add_option("--episodes", o->episodes,
                  "Number of episodes (a replay:FILE.json trajectory plays its own episodes)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  sub->add_option("--steps", o->steps, kStepsHelp)
      ->capture_default_str()
      ->check(CLI::Range(1, kMaxSteps));
  AddPolicyOptions(sub, &o->policy);
  AddSignalsOption(sub, &o->signals);
  sub->add_option("--json-out", o->json_out,
                  "Write F (.json), F/rollout.json if F ends in /, or F_rollout.json; without it "
                  "JSON goes to stdout");
  sub->add_option(
      "--minari", o->minari,
      "Also write the episodes as a Minari dataset of this id, e.g. "
      "fetchscope/FetchPush/scripted-v0 (docs/guide/datasets.md); without --json-out no "
      "JSON is printed");
  sub->add_option("--minari-root", o->minari_root,
                  "Datasets root (default $MINARI_DATASETS_PATH, else ~/.minari/datasets)");
  sub->add_flag("--overwrite", o->overwrite,
                "Replace an existing Minari dataset of that id, and let --json-out replace a "
                "result file of another env, seed or task");
  AddDatasetAuthorOptions(sub, &o->author);
  AddObsOptions(sub, &o->obs);
  AddLookOptions(sub, &o->look);
  AddRobomimicOptions(sub, &o->robomimic);
  AddEpisodeSelectionOptions(sub, &o->selection);
  sub->add_option(
      "--shard", o->shard,
      "Play only shard I of N (0 <= I < N): episodes k with k mod N = I, each as in the "
      "whole run; its dataset records the shard, and merge-datasets joins the shards' "
      "datasets. Without it: JOB_COMPLETION_INDEX (with --shard-count) or "
      "SLURM_ARRAY_TASK_ID/COUNT if set");
  sub->add_option("--shard-count", o->shard_count,
                  "Number of shards when the index comes from JOB_COMPLETION_INDEX");
  sub->add_option("--backend", o->backend,
                  "GL backend of --obs-camera's images: auto, egl or osmesa (default "
                  "$MUJOCO_GL, else auto)");
  AddJobsOptions(sub, &o->jobs, &o->worker_mode);
  return {sub, [o, sub] {
            o->episodes_given = sub->count("--episodes") > 0;
            CheckObsUse(sub, o->obs, !o->minari.empty() || !o->robomimic.file.empty(),
                        o->policy.policy.rfind("exec:", 0) == 0, o->robomimic);
            return RunRollout(*o);
          }};
}

}  // namespace fetchscope::cli
