// fetchscope record: episodes -> a run folder of videos, contact sheets, trajectories and
// one manifest. This file turns the options into a RecordPlan, decides the GPUs and the encoder
// once (run/node_probe.h), opens the run folder, records the episodes through run/record_run.h
// (--jobs N workers on the episode scheduler, each rendering into frame pools that the episode
// video sinks of encode/episode_sink.h encode), and writes the manifest and the summary.
// --shard I/N records every N-th episode so that machines split a batch. Either way episode k
// comes out exactly as in a sequential run, byte for byte.
#include <signal.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "base/errors.h"
#include "base/suggest.h"
#include "cli/command.h"
#include "cli/common.h"
#include "cli/jobs_options.h"
#include "cli/look_options.h"
#include "cli/obs_options.h"
#include "cli/record_from.h"
#include "cli/resolve.h"
#include "cli/shard_options.h"
#include "cli/view_options.h"
#include "dataset/minari_format.h"
#include "encode/episode_sink.h"
#include "encode/video_format.h"
#include "encode/video_writer.h"
#include "inspect/report.h"
#include "render/layers.h"
#include "render/text.h"
#include "run/episode_look.h"
#include "run/episode_scheduler.h"
#include "run/manifest.h"
#include "run/node_probe.h"
#include "run/progress.h"
#include "run/record_command.h"
#include "run/record_run.h"
#include "run/run_files.h"
#include "run/run_folder.h"
#include "run/run_summary.h"
#include "run/shard.h"
#include "src/episode_source.h"
#include "src/policy.h"
#include "src/trajectory.h"

namespace fetchscope::cli {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct RecordOptions {
  EnvOptions env;
  ViewOptions view;
  int episodes = 1;
  int steps = 50;
  PolicyOptions policy;  // --policy, --exec-timeout, --replay-dtype
  int fps = 25;
  std::string codec = "auto";
  int crf = 23;
  std::string preset;
  std::string formats = "mp4";  // --format: comma list of mp4, webm, gif
  int gif_fps = 10;
  int gif_width = 320;
  int sheet_every = 0;
  bool no_sheets = false;  // --no-sheets
  std::string out = "out";
  bool quiet = false;
  int jobs = 1;  // workers; 0 = one per core
  std::string worker_mode = "process";
  std::string shard;                  // "I/N"; empty: from the environment, else the whole run
  int shard_count = 0;                // with JOB_COMPLETION_INDEX; 0 = not given
  bool overwrite = false;             // replace the run already in --out
  bool resume = false;                // continue the run already in --out
  bool episodes_given = false;        // --episodes was on the command line
  bool no_report = false;             // no index.html (inspect/report.h)
  std::string from;                   // record --from: a run folder or trajectory JSON
  std::string layers = "rgb";         // --layers: rgb plus depth, segmentation
  std::string signals = "none";       // --signals: none, contacts
  std::string minari;                 // --minari: also write the run as this Minari dataset
  std::string minari_root;            // --minari-root
  DatasetAuthor author;               // --minari-author, --minari-author-email
  double tolerance = 1e-6;            // --tolerance: record --from DATASET
  ObsOptions obs;                     // --obs-camera, --obs-size, --obs-layers, --obs-overlay
  LookOptions look;                   // --randomize, --randomize-config
  RobomimicOptions robomimic;         // --robomimic, --no-next-obs, --valid-fraction
  EpisodeSelectionOptions selection;  // --keep, --stop-after-success
};

// record --from: the recorded episodes' indices, ascending.
std::vector<int> FromEpisodes(const TrajectorySource& from) {
  std::vector<int> out;
  for (const auto& [k, episode] : from.episodes) out.push_back(k);
  return out;
}

int RunRecord(const RecordOptions& o, const PolicySpec& policy, const std::string& command_line,
              const TrajectorySource* from = nullptr);

// record --from: the trajectory sets env, seed, policy, steps and episodes; then as record. The
// recording's actions are replayed: its policy is not run, only named (a zero spec under its
// name, for the manifest and the trajectories).
int RunRecordFrom(RecordOptions o, const CLI::App& sub, const std::string& command_line) {
  const TrajectorySource source =
      LoadFromSource(sub, {o.from, o.minari_root, sub.count("--episodes") ? o.episodes : 0,
                           sub.count("--env-id") ? o.env.env_id : "", o.tolerance,
                           sub.count("--assets") ? o.env.assets : "", o.quiet});
  ApplyFromSource(source, sub, &o.env.env_id, &o.env.seed, &o.policy.policy, &o.steps, &o.episodes,
                  &o.env.assets);
  // the recording's actions replay as recorded: --replay-dtype is refused as for any policy but
  // replay:FILE (its message names the zero actions played)
  if (!o.policy.replay_dtype.empty() || !o.policy.exec_fields.empty())
    ParsePolicyOptions(
        {"zero", o.policy.exec_timeout, o.policy.replay_dtype, o.policy.exec_fields});
  return RunRecord(o, PolicySpec::Zero(o.policy.policy), command_line, &source);
}

// record: --policy parsed once (a replay file read here, never again); replay:FILE.json
// brings its env and seed.
int RunRecordPolicy(RecordOptions o, const std::string& command_line) {
  const PolicySpec policy = ParsePolicyOptions(o.policy);
  ApplyReplayedEnv(policy, &o.env);
  return RunRecord(o, policy, command_line);
}

// Starting an exec: child is the only full check of it, and the workers do that; every other
// policy is built once here so that a bad one fails before anything is written.
void ValidatePolicy(const PolicySpec& policy, const EnvSpec& spec, const PolicyContext& context) {
  if (policy.is_exec()) return;
  MakePolicy(policy, spec, context);
}

// --shard, or the environment's array index, with a note where a Slurm array and the run in
// --out disagree on the number of shards.
Shard ResolveRecordShard(const RecordOptions& o) {
  const int run_shards = RunShardCount(o.out);
  const Shard shard = ResolveShard(o.shard, o.shard_count, nullptr, run_shards);
  const char* task_count = std::getenv("SLURM_ARRAY_TASK_COUNT");
  if (shard.source == "SLURM_ARRAY_TASK_ID" && run_shards > 0 && task_count &&
      std::to_string(run_shards) != task_count && !o.quiet) {
    std::fprintf(stderr,
                 "fetchscope: note: --out '%s' holds a run of %d shards and this array has %s "
                 "task(s): task %d records shard %s of that run\n",
                 o.out.c_str(), run_shards, task_count, shard.index, ShardLabel(shard).c_str());
  }
  return shard;
}

// --fps, --codec, --crf, --preset, --gif-*, --format and --layers into the plan, checked.
void ResolveRecordVideo(const RecordOptions& o, RecordPlan* plan) {
  plan->video.fps = o.fps;
  plan->video.codec = o.codec;
  plan->video.crf = o.crf;
  plan->video.preset = o.preset;
  plan->video.gif_fps = o.gif_fps;
  plan->video.gif_width = o.gif_width;
  plan->formats = ParseVideoFormats(o.formats);
  plan->layers = ParseRecordLayers(o.layers);
  plan->contact_signals = ParseContactSignals(o.signals);
  ValidateVideoOptions(plan->video);
}

// Whether an episode's look may jitter the cameras: --randomize camera, or (record --from
// without --randomize) a recorded episode whose look did.
bool CameraLookDrawn(const RecordPlan& plan) {
  if (plan.look) return plan.look->camera;
  if (!plan.from) return false;
  for (const auto& [k, episode] : plan.from->episodes) {
    if (episode.look.is_object() && episode.look.value("camera", false)) return true;
  }
  return false;
}

// The policy checked, the font and the frame size: the model
// is loaded once here so that bad assets, cameras or an edited recording fail before any file.
void ResolveRecordWorld(const RecordOptions& o, RecordJob* job) {
  RecordPlan& plan = job->plan;
  if (!plan.from) ValidatePolicy(plan.policy, *plan.spec, plan.policy_context);
  Font::Default();  // the sheets' font: missing or unreadable, the run stops before any file
  {
    FetchEnv env(*plan.spec, plan.assets);         // bad assets and bad cameras fail here
    plan.view = ResolveView(o.view, env.model());  // the cameras checked against the model
    const FrameDims frame = FrameSize(plan.view.render);
    plan.video.width = frame.width;  // --width/--height size each camera's tile
    plan.video.height = frame.height;
    job->model_path = env.model_path();
    if (plan.from) VerifyRecording(env, *plan.from);  // an edited recording stops here
    if (plan.from && !plan.look) {                    // and so does a stored look that is not one
      for (const auto& [k, episode] : plan.from->episodes) {
        EpisodeLook(std::nullopt, 0, k, &episode, {}, env.model());
      }
    }
    // --obs-camera: the dataset's images, at the run's --msaa (as render draws them)
    ObsSetup obs = ResolveObs(o.obs, env.model(), plan.view.render.msaa_samples);
    if (CameraLookDrawn(plan)) {  // each episode's jitter moves every camera: poses per step
      for (ObsCamera& camera : obs.cameras) camera.moving = true;
    }
    plan.pixels = PlanPixels(obs, env.model(), !o.minari.empty(), !o.robomimic.file.empty());
    if (plan.pixels.stages() && o.resume) {
      throw UsageError(std::string(plan.pixels.setup.enabled() ? "--obs-camera" : "--robomimic") +
                       " cannot --resume: the images and states of the episodes already "
                       "recorded are gone; record the run again with --overwrite");
    }
  }
  ValidateVideoOptions(plan.video);
}

// Parse and resolve: the options into the workers' plan and the run around it, each checked in
// the order record has always reported them.
RecordJob ResolveRecord(RecordOptions* options, const PolicySpec& policy,
                        const TrajectorySource* from) {
  RecordOptions& o = *options;  // a trajectory replay sets the episodes
  RecordJob job;
  job.wall_start = Clock::now();
  RecordPlan& plan = job.plan;
  plan.from = from;
  // --overlay is reported before the other options (ResolveView parses it again with the rest)
  const OverlaySet overlays = ParseOverlays(o.view.overlay);
  plan.hindsight = overlays.hindsight;
  job.hud = overlays.hud;
  plan.look = ResolveLook(o.look);
  plan.look_seed = ResolveLookSeed(o.look);
  // the one resolver: env, seed, assets, the episodes (a replayed trajectory's own) and the
  // policy's context
  EpisodeRequest request{policy,  o.episodes, o.episodes_given,
                         o.steps, o.quiet,    "in the trajectory JSON and the HUD"};
  const ResolvedRun run = ResolveRun(o.env, request);
  plan.spec = run.env.spec;
  plan.seed = run.env.seed;
  plan.seed_text = o.env.seed;
  plan.assets = run.env.assets;
  plan.policy = WithExecFields(policy, o.policy, *run.env.spec);
  plan.policy_context = run.policy_context;
  plan.steps = o.steps;
  o.episodes = run.policy_context.episodes;  // a replayed trajectory: one past its last
  job.view_text = {o.view.camera, o.view.overlay, o.view.msaa, o.view.gpu};
  plan.out = o.out;
  plan.sheet_every = o.no_sheets ? -1 : o.sheet_every;
  job.shard = ResolveRecordShard(o);
  job.mode = ParseWorkerMode(o.worker_mode);
  job.worker_mode = o.worker_mode;
  job.quiet = o.quiet;
  job.report = !o.no_report;
  job.overwrite = o.overwrite;
  job.resume = o.resume;
  if (!o.minari.empty()) {
    job.minari_root_given = o.minari_root;
    job.minari = MinariRequest{
        o.minari, MinariRoot(o.minari_root), o.overwrite, o.author.name, o.author.email, nullptr,
        {}};
    CheckRecordMinari(job);
  }
  job.keep_successful = KeepSuccessful(o.selection, !o.minari.empty() || !o.robomimic.file.empty());
  if (o.selection.stop_after_success >= 0 && from) {
    throw UsageError(
        "--stop-after-success does not apply to record --from: the recording's "
        "episodes keep their own lengths");
  }
  if (o.selection.stop_after_success >= 0 && o.resume) {
    throw UsageError(
        "--stop-after-success cannot --resume (the manifest does not record it); "
        "record the run again with --overwrite");
  }
  plan.stop_after_success = o.selection.stop_after_success;
  if (!o.robomimic.file.empty()) {
    job.robomimic =
        RobomimicRequest{o.robomimic.file,           o.overwrite, !o.robomimic.no_next_obs,
                         o.robomimic.valid_fraction, nullptr,     {}};
    CheckRecordRobomimic(job);
  }
  ResolveRecordVideo(o, &plan);
  job.formats_text = o.formats;
  job.episodes = from ? FromEpisodes(*from) : ShardEpisodes(job.shard, run.episodes);
  plan.policy_context.episode_indices = job.episodes;
  job.episodes_requested = o.episodes;
  job.jobs = ResolveJobs(o.jobs, static_cast<int>(job.episodes.size()));
  plan.encoders = EncodersPerWorker(job.jobs);
  ResolveRecordWorld(o, &job);
  job.from_option = o.from;
  if (const policy_spec::Replay* replay = plan.policy.replay()) job.replay_file = replay->path;
  return job;
}

// parse (AddRecord) -> resolve -> run -> print (the summary and report, from RecordRun).
int RunRecord(const RecordOptions& options, const PolicySpec& policy,
              const std::string& command_line, const TrajectorySource* from) {
  RecordOptions o = options;
  RecordJob job = ResolveRecord(&o, policy, from);
  job.command_line = command_line;
  job.write_report = [quiet = o.quiet](const std::string& manifest_path) {
    WriteRunReportOrWarn(manifest_path, quiet);
  };
  return RecordRun(std::move(job));
}
// --fps, --codec, --crf, --preset, --format, --gif-*, --layers and --sheet-every.
void AddRecordVideoOptions(CLI::App* sub, RecordOptions* o) {
  sub->add_option("--fps", o->fps, "Video frame rate (25 = the control rate: real time)")
      ->capture_default_str();
  sub->add_option("--codec", o->codec,
                  "auto (h264_nvenc where the GPU has NVENC, else libx264; decided once per run), "
                  "libx264 or h264_nvenc")
      ->capture_default_str();
  sub->add_option("--crf", o->crf, "H.264 quality, 0 (lossless) .. 51 (worst)")
      ->capture_default_str();
  sub->add_option("--preset", o->preset,
                  std::string("Encoder preset (default ") + kDefaultVideoPreset + ")");
  sub->add_option(
         "--format", o->formats,
         "Video formats, a comma list: " + VideoFormatHelp() + "; one file per episode and format")
      ->capture_default_str();
  sub->add_option("--gif-fps", o->gif_fps, "GIF frame rate, 1..50 (at most --fps)")
      ->capture_default_str();
  sub->add_option(
         "--gif-width", o->gif_width,
         "GIF width in pixels, 16..4096 (never wider than the frames; height keeps the aspect); "
         "the GIF's HUD is sized for this width, and left out where a view would show smaller "
         "than 320x240")
      ->capture_default_str();
  AddSignalsOption(sub, &o->signals);
  sub->add_option("--layers", o->layers,
                  "Comma list of rgb (always recorded), depth, segmentation: each extra layer is "
                  "one more video per episode and --format, episode_NNN_depth.mp4 (grey: white "
                  "near .. dark far, black = no depth; the scale is fixed per episode from its "
                  "reset frame and given in the manifest), episode_NNN_segmentation.mp4 (a fixed "
                  "colour per body or site, as render --layers) with "
                  "episode_NNN_segmentation_legend.json naming each colour's body and geoms. "
                  "Layers show no overlays; contact sheets stay rgb")
      ->capture_default_str();
  sub->add_option(
         "--sheet-every", o->sheet_every,
         "Contact sheet: every K-th frame (0: about 12 tiles); the last frame is always included")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000));
  sub->add_flag("--no-sheets", o->no_sheets,
                "No contact sheets (episode_NNN_sheet.png), when the point of the run is its "
                "dataset or videos; the report shows no thumbnails")
      ->excludes("--sheet-every");
}

// --minari with its root and author, --overwrite and --resume.
void AddRecordReuseOptions(CLI::App* sub, RecordOptions* o) {
  sub->add_option("--minari", o->minari,
                  "Also write the recorded episodes as a Minari dataset of this id (docs/guide/"
                  "datasets.md); an existing one is refused, --overwrite replaces it after the "
                  "run");
  sub->add_option("--minari-root", o->minari_root,
                  "Datasets root (default $MINARI_DATASETS_PATH, else ~/.minari/datasets)");
  AddDatasetAuthorOptions(sub, &o->author);
  sub->add_flag("--overwrite", o->overwrite,
                "Replace the record run already in --out: only the files fetchscope wrote (its "
                "manifest, the files the manifest lists, its report); other files stay, and one "
                "under a run's name that fetchscope did not write is refused, naming it. The "
                "earlier run is kept aside until the new one has its manifest, and put back if it "
                "fails or is interrupted before an episode is complete. Without --overwrite or "
                "--resume such a folder is refused. With --minari, also replaces the dataset of "
                "that id (after the run, atomically)");
  sub->add_flag("--resume", o->resume,
                "Continue the interrupted record run in --out: keep its complete episodes and "
                "record the others, byte-identical to an uninterrupted run; the options must "
                "be those of that run, except a larger --episodes, which extends it (a smaller "
                "one is refused). A run already whole is summarised and left as it is. With "
                "nothing to resume (no such folder, or no manifest in it) the whole run is "
                "recorded, with a note saying so");
}
}  // namespace

Command AddRecord(CLI::App& app) {
  auto o = std::make_shared<RecordOptions>();
  CLI::App* sub = app.add_subcommand(
      "record", "Record episodes: episode_NNN." + std::string(VideoFormats().front().extension) +
                    " (" + OtherVideoExtensions() +
                    ": --format), episode_NNN_sheet.png, episode_NNN.json, "
                    "manifest.json");
  AddEnvOptions(sub, &o->env);
  AddViewOptions(sub, &o->view);
  sub->add_option("--episodes", o->episodes, "Number of episodes")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  sub->add_option("--steps", o->steps, kStepsHelp)
      ->capture_default_str()
      ->check(CLI::Range(1, kMaxSteps));
  AddPolicyOptions(sub, &o->policy);
  AddRecordVideoOptions(sub, o.get());
  sub->add_option("--out", o->out,
                  "Output folder: checked writable before anything is rendered; never --from's "
                  "folder, one holding it or one inside it")
      ->capture_default_str();
  sub->add_flag("-q,--quiet", o->quiet, "No progress or summary on stderr");
  AddRecordReuseOptions(sub, o.get());
  AddJobsOptions(sub, &o->jobs, &o->worker_mode);
  sub->add_option("--shard", o->shard,
                  "Record only shard I of N (0 <= I < N): episodes k with k mod N = I. Without it: "
                  "JOB_COMPLETION_INDEX (with --shard-count) or SLURM_ARRAY_TASK_ID/COUNT if set");
  sub->add_option("--shard-count", o->shard_count,
                  "Number of shards when the index comes from JOB_COMPLETION_INDEX (a Kubernetes "
                  "Indexed Job's completions)");
  sub->add_flag("--no-report", o->no_report,
                "Do not write the run's HTML report (index.html; see `fetchscope report`)");
  AddFromOption(sub, &o->from, &o->tolerance);
  AddObsOptions(sub, &o->obs);
  AddLookOptions(sub, &o->look,
                 "; record --from without it draws each episode as it was recorded (its stored "
                 "look), --randomize none plainly");
  AddRobomimicOptions(sub, &o->robomimic);
  AddEpisodeSelectionOptions(sub, &o->selection);
  return {sub, [o, sub] {
            o->episodes_given = sub->count("--episodes") > 0;
            CheckObsUse(sub, o->obs, !o->minari.empty() || !o->robomimic.file.empty(),
                        o->from.empty() && o->policy.policy.rfind("exec:", 0) == 0, o->robomimic);
            if (!o->from.empty()) return RunRecordFrom(*o, *sub, CommandLine());
            return RunRecordPolicy(*o, CommandLine());
          }};
}

}  // namespace fetchscope::cli
