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
#include "cli/record_from.h"
#include "cli/resolve.h"
#include "cli/view_options.h"
#include "dataset/minari_trajectory.h"
#include "dataset/minari_writer.h"
#include "encode/episode_sink.h"
#include "encode/video_writer.h"
#include "inspect/report.h"
#include "render/layers.h"
#include "render/text.h"
#include "run/episode_scheduler.h"
#include "run/manifest.h"
#include "run/node_probe.h"
#include "run/progress.h"
#include "run/record_run.h"
#include "run/run_files.h"
#include "run/run_folder.h"
#include "run/run_summary.h"
#include "run/shard.h"
#include "src/episode_source.h"
#include "src/trajectory.h"

namespace fetchscope::cli {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

struct RecordOptions {
  EnvOptions env;
  ViewOptions view;
  int episodes = 1;
  int steps = 50;
  std::string policy = "random";
  double exec_timeout = 10.0;
  int fps = 25;
  std::string codec = "auto";
  int crf = 23;
  std::string preset;
  std::string formats = "mp4";  // --format: comma list of mp4, webm, gif
  int gif_fps = 10;
  int gif_width = 320;
  int sheet_every = 0;
  std::string out = "out";
  bool quiet = false;
  int jobs = 1;  // workers; 0 = one per core
  std::string worker_mode = "process";
  std::string shard;            // "I/N"; empty: from the environment, else the whole run
  int shard_count = 0;          // with JOB_COMPLETION_INDEX; 0 = not given
  bool overwrite = false;       // replace the run already in --out
  bool resume = false;          // continue the run already in --out
  std::string replay_dtype;     // --replay-dtype: "", float32, float64
  bool episodes_given = false;  // --episodes was on the command line
  bool no_report = false;       // no index.html (inspect/report.h)
  std::string from;             // record --from: a run folder or trajectory JSON
  std::string layers = "rgb";   // --layers: rgb plus depth, segmentation
  std::string minari;           // --minari: also write the run as this Minari dataset
  std::string minari_root;      // --minari-root
  DatasetAuthor author;         // --minari-author, --minari-author-email
  double tolerance = 1e-6;      // --tolerance: record --from DATASET
};

// record --from: the recorded episodes' indices, ascending.
std::vector<int> FromEpisodes(const TrajectorySource& from) {
  std::vector<int> out;
  for (const auto& [k, episode] : from.episodes) out.push_back(k);
  return out;
}

int RunRecord(const RecordOptions& o, const std::string& command_line,
              const TrajectorySource* from = nullptr);

// record --from: the trajectory sets env, seed, policy, steps and episodes; then as record.
int RunRecordFrom(RecordOptions o, const CLI::App& sub, const std::string& command_line) {
  const TrajectorySource source =
      LoadFromSource(sub, {o.from, o.minari_root, sub.count("--episodes") ? o.episodes : 0,
                           sub.count("--env-id") ? o.env.env_id : "", o.tolerance,
                           sub.count("--assets") ? o.env.assets : "", o.quiet});
  ApplyFromSource(source, sub, &o.env.env_id, &o.env.seed, &o.policy, &o.steps, &o.episodes,
                  &o.env.assets);
  return RunRecord(o, command_line, &source);
}

// Starting an exec: child is the only full check of it, and the workers do that; every other
// policy is built once here so that a bad one fails before anything is written.
void ValidatePolicy(const std::string& policy, const EnvSpec& spec, const PolicyContext& context) {
  if (policy.rfind("exec:", 0) == 0 && policy.size() > 5) return;
  MakePolicy(policy, spec, context);
}

// What makes two record runs the same run (SameRun), by option: what a resumed run must repeat for
// its episodes to come out byte for byte as the run it continues (--jobs, --gpu and --backend
// are free: outputs do not depend on them on one machine).
RunParameters RecordParameters(const RecordOptions& o, const RecordPlan& plan, const Shard& shard) {
  RunParameters p;
  p.env_id = plan.spec->id;
  p.seed = plan.seed;
  p.policy = o.policy;
  p.replay_dtype = o.replay_dtype;
  p.episodes = o.episodes;
  p.steps = o.steps;
  p.sheet_every = o.sheet_every;
  p.assets_sha256 = plan.assets.sha256;
  p.camera = o.view.camera;
  p.overlay = o.view.overlay;
  p.width = o.view.width;
  p.height = o.view.height;
  p.msaa = o.view.msaa;
  p.codec = plan.video.codec;
  p.crf = o.crf;
  p.preset = o.preset.empty() ? kDefaultVideoPreset : o.preset;
  p.fps = o.fps;
  p.shard_index = shard.index;
  p.shard_count = shard.count;
  p.formats = plan.formats;
  p.gif_fps = o.gif_fps;
  p.gif_width = o.gif_width;
  p.layers = LayersLabel(plan.layers);
  return p;
}

RunFolderRequest MakeRunFolderRequest(const RecordOptions& o, const Shard& shard,
                                      const std::vector<int>& episodes,
                                      const RunParameters& parameters) {
  RunFolderRequest request;
  request.out = o.out;
  request.mode = ParseReuseMode(o.overwrite, o.resume);
  request.manifest_name = ShardManifestName(shard);
  request.sharded = shard.sharded();
  request.owns = [shard](int k) { return shard.Owns(k); };
  request.episodes = episodes;
  request.parameters = parameters;
  request.sources = {{"--from", o.from}};
  if (o.policy.rfind("replay:", 0) == 0)
    request.sources.push_back({"--policy", o.policy.substr(7)});
  request.report = !o.no_report && !shard.sharded();
  return request;
}

// The episodes this run records: those of its shard among 0 .. --episodes-1 or, replaying a
// trajectory JSON, the file's episodes, each under its own index (and so with its own reset);
// --episodes then becomes one past the last index.
std::vector<int> RecordEpisodeList(RecordOptions* o, const Shard& shard, const RecordPlan& plan) {
  const std::optional<std::vector<int>> indices = ReplayedEpisodes(
      o->policy, o->episodes_given ? o->episodes : 0, plan.spec->id, plan.seed, o->quiet);
  if (!indices) return ShardEpisodes(shard, o->episodes);
  o->episodes = indices->back() + 1;
  std::vector<int> mine;
  for (int k : *indices) {
    if (shard.Owns(k)) mine.push_back(k);
  }
  return mine;
}

int RunRecord(const RecordOptions& options, const std::string& command_line,
              const TrajectorySource* from) {
  const auto wall_start = Clock::now();
  RecordOptions o = options;  // a trajectory replay sets the episodes
  RecordPlan plan;
  plan.from = from;
  plan.hindsight = ParseOverlays(o.view.overlay).hindsight;
  plan.spec = &FindEnvSpec(o.env.env_id);
  plan.seed = ParseSeed(o.env.seed);
  plan.seed_text = o.env.seed;
  plan.policy = o.policy;
  plan.steps = o.steps;
  NotePastTimeLimit(*plan.spec, o.steps, o.quiet, "in the trajectory JSON and the HUD");
  plan.view = o.view;
  plan.out = o.out;
  plan.sheet_every = o.sheet_every;
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
  const WorkerMode mode = ParseWorkerMode(o.worker_mode);
  MinariWriteOptions minari;
  if (!o.minari.empty()) {
    if (shard.sharded()) {
      throw UsageError(
          "record --minari: a shard records part of the run; once every shard is "
          "done, `fetchscope export " +
          o.out + " --minari " + o.minari + "`");
    }
    minari.dataset_id = o.minari;
    minari.root = MinariRoot(o.minari_root);
    minari.spec = plan.spec;
    minari.algorithm_name = o.policy;
    minari.overwrite = o.overwrite;      // replaced after the run, atomically
    minari.max_episode_steps = o.steps;  // gym.make(id, max_episode_steps=--steps)
    if (!o.author.name.empty()) minari.author = o.author.name;
    minari.author_email = o.author.email;
    minari.description = plan.spec->id + " episodes recorded by fetchscope (policy " + o.policy +
                         ", seed " + o.env.seed + ")";
    // an existing id or an unwritable datasets folder fails now, not after the run
    CheckMinariDestination(minari);
  }
  plan.video.fps = o.fps;
  plan.video.codec = o.codec;
  plan.video.crf = o.crf;
  plan.video.preset = o.preset;
  plan.video.gif_fps = o.gif_fps;
  plan.video.gif_width = o.gif_width;
  plan.formats = ParseVideoFormats(o.formats);
  plan.layers = ParseRecordLayers(o.layers);
  ValidateVideoOptions(plan.video);
  const std::vector<int> episodes = from ? FromEpisodes(*from) : RecordEpisodeList(&o, shard, plan);
  const int jobs = ResolveJobs(o.jobs, static_cast<int>(episodes.size()));
  plan.encoders = EncodersPerWorker(jobs);

  plan.policy_context.seed = plan.seed;
  plan.policy_context.steps_per_episode = o.steps;
  plan.policy_context.episodes = o.episodes;
  plan.policy_context.exec_timeout_s = o.exec_timeout;
  plan.policy_context.stop_requested = [] { return StopSignal() != 0; };
  plan.policy_context.replay_dtype = o.replay_dtype;
  plan.policy_context.episode_indices = episodes;
  if (!from) ValidatePolicy(o.policy, *plan.spec, plan.policy_context);
  Font::Default();  // the sheets' font: missing or unreadable, the run stops before any file
  plan.assets = ResolveAssets(o.env.assets);
  std::string model_path;
  {
    FetchEnv env(*plan.spec, plan.assets);  // bad assets and bad cameras fail here
    const FrameDims frame = FrameSize(MakeRenderOptions(o.view, env.model()));
    plan.video.width = frame.width;  // --width/--height size each camera's tile
    plan.video.height = frame.height;
    model_path = env.model_path();
    if (from) VerifyRecording(env, *from);  // an edited recording stops here, before any file
  }
  ValidateVideoOptions(plan.video);

  // The GPUs and the encoder, decided once (driver work in a child process); without mp4 no
  // H.264 is encoded, and nothing is probed for it.
  const bool h264 =
      std::find(plan.formats.begin(), plan.formats.end(), "mp4") != plan.formats.end();
  const NodeProbe node = ProbeNode(o.view, h264 ? &plan.video : nullptr);
  plan.gpu = node.gpu;
  if (h264) plan.video.codec = node.codec.codec;
  if (!node.warnings.empty() && !o.quiet) {
    std::fprintf(stderr, "fetchscope: warning: %s\n", node.warnings.c_str());
  }
  const std::string gif_note =
      GifHudNote(MakeEpisodeSinkOptions(plan), o.view.width, o.view.height);
  if (!gif_note.empty() && ParseOverlays(o.view.overlay).hud && !o.quiet) {
    std::fprintf(stderr, "fetchscope: note: %s\n", gif_note.c_str());
  }

  // never two runs in one folder; a failure below leaves nothing this run made. From here a
  // SIGINT/SIGTERM is an interruption (the scheduler takes over the handlers when it starts).
  InstallStopSignals();
  const RunParameters parameters = RecordParameters(o, plan, shard);
  RunFolder folder(MakeRunFolderRequest(o, shard, episodes, parameters));
  if (!folder.notice().empty() && !o.quiet) {
    std::fprintf(stderr, "fetchscope: note: %s\n", folder.notice().c_str());
  }
  if (folder.already_complete()) {  // --resume of a whole run: say so, change nothing
    if (!o.quiet) std::fprintf(stderr, "%s\n", AlreadyCompleteText(o.out, folder.kept()).c_str());
    // killed between its manifest and its report: the report is written now
    const fs::path manifest_path = fs::path(o.out) / ShardManifestName(shard);
    if (!o.no_report && !shard.sharded() &&
        !fs::exists(manifest_path.parent_path() / kReportFileName)) {
      WriteRunReportOrWarn(manifest_path, o.quiet);
    }
    return 0;
  }
  const int early_signal = StopSignal();  // before the scheduler: record nothing

  ProgressReporter progress("record", static_cast<int>(folder.todo().size()), o.steps + 1, o.quiet);
  int successes = 0;
  ScheduleOptions schedule;
  schedule.episodes = folder.todo();
  schedule.jobs = jobs;
  schedule.mode = mode;
  schedule.on_progress = [&](int n) { progress.Frames(n); };
  schedule.on_done = [&](int, const nlohmann::json& entry) {
    progress.EpisodeDone();
    successes += entry.at("is_success").get<bool>();
  };
  ScheduleResult result;
  if (early_signal) {
    result.signal = early_signal;
    result.jobs = jobs;
    result.missing = folder.todo();
  } else {
    result = RecordEpisodes(plan, schedule);
  }
  const bool any_complete =
      std::any_of(result.results.begin(), result.results.end(),
                  [](const auto& r) { return r.second.value("complete", false); });
  if (result.signal && !any_complete && folder.replacing()) {
    // interrupted before --overwrite recorded a whole episode: the earlier run stays as it was
    if (!o.quiet) {
      std::fprintf(stderr,
                   "record: interrupted before any episode was complete; the earlier "
                   "run in %s is kept as it was\n",
                   o.out.c_str());
    }
    return 128 + result.signal;  // `folder` removes this run's files, puts the earlier run back
  }

  const double wall = Since(wall_start);
  std::vector<ManifestEpisode> entries;
  std::map<std::string, double> timings = {{"sim", 0}, {"render", 0}, {"encode", 0}, {"write", 0}};
  std::map<int, std::vector<int>> by_worker;  // the episodes each worker recorded
  std::map<std::string, double> cpu_stages;   // thread CPU by stage (base/cpu_clock.h)
  for (const auto& [k, entry] : result.results) {
    nlohmann::json e = entry;
    for (auto& [phase, seconds] : timings) seconds += e["timings_s"][phase].get<double>();
    if (e["timings_s"].contains("cpu_s")) {
      for (const auto& [stage, seconds] : e["timings_s"]["cpu_s"].items()) {
        cpu_stages[stage] += seconds.get<double>();
      }
    }
    by_worker[e.at("worker").get<int>()].push_back(k);
    // what differs with --jobs stays out of the episode entries (they are identical)
    e.erase("worker");
    e.erase("timings_s");
    e.erase("codec");
    e.erase("encoded_width");
    e.erase("encoded_height");
    entries.push_back(ManifestEpisodeFromJson(e));
  }
  entries = folder.WithKept(std::move(entries));
  // The first worker that started speaks for the GL setup (all run the same backend).
  nlohmann::json first_worker;
  for (const nlohmann::json& w : result.workers) {
    if (!w.is_null()) {
      first_worker = w;
      break;
    }
  }
  if (result.results.empty() && result.signal == 0 && !result.failures.empty()) {
    // nothing was recorded: no manifest, and `folder` removes what this run made
    const WorkerFailure& first = result.failures.front();
    if (first.usage) throw UsageError(first.message);
    throw RunError(DescribeFailures(result));
  }
  nlohmann::json workers_json = nlohmann::json::array();
  for (size_t w = 0; w < result.workers.size(); ++w) {
    nlohmann::json entry =
        result.workers[w].is_null() ? nlohmann::json{{"worker", w}} : result.workers[w];
    entry["episodes"] = by_worker[static_cast<int>(w)];
    workers_json.push_back(std::move(entry));
  }
  const int sig = result.signal;
  // the encoder of each format's files, and all of them in --format order as one line
  nlohmann::json codecs = nlohmann::json::object();
  std::string codec_used;
  for (const std::string& format : plan.formats) {
    codecs[format] = FormatCodec(format, plan.video.codec);
    codec_used += (codec_used.empty() ? "" : ", ") + codecs[format].get<std::string>();
  }
  const std::string codec_reason =
      h264 ? node.codec.reason
           : "--format " + o.formats + ": no H.264 encoded, so --codec does not apply";
  // episodes cut short: by this run's signal, or already in the recording --from replays
  std::vector<int> incomplete;
  for (const ManifestEpisode& e : entries) {
    if (!e.complete.value_or(true)) incomplete.push_back(e.index);
  }
  Manifest manifest;
  manifest.env_id = plan.spec->id;
  manifest.seed = plan.seed;
  manifest.policy = o.policy;
  if (from) manifest.from = from->path;
  manifest.episodes_requested = o.episodes;
  manifest.steps_per_episode = o.steps;
  manifest.sheet_every = o.sheet_every;
  manifest.episodes = std::move(entries);
  if (from) AddDivergence(*from, &manifest.episodes, &manifest.extra);  // a dataset's drift
  manifest.missing = result.missing;
  for (const WorkerFailure& f : result.failures) {
    manifest.failures.push_back({f.worker, f.episodes, f.message});
  }
  manifest.shard = ManifestShard{shard.index, shard.count, std::nullopt, episodes};
  if (!shard.source.empty()) manifest.shard->source = shard.source;
  manifest.jobs = result.jobs;
  manifest.worker_mode = o.worker_mode;
  manifest.workers = workers_json;
  manifest.gpu = {
      {"request", o.view.gpu}, {"choice", plan.gpu.reason}, {"devices", plan.gpu.devices}};
  manifest.assets = AssetsJson(plan.assets);
  manifest.model_file = model_path;
  manifest.camera = o.view.camera;
  manifest.overlay = o.view.overlay;
  manifest.msaa = first_worker.value("msaa", 0);
  manifest.msaa_reason = first_worker.value("msaa_reason", "");
  manifest.backend = {{"name", first_worker.value("backend", "")},
                      {"device", first_worker.value("device", "")},
                      {"gl_vendor", first_worker.value("gl_vendor", "")},
                      {"gl_renderer", first_worker.value("gl_renderer", "")},
                      {"gl_version", first_worker.value("gl_version", "")}};
  manifest.layers = SplitCommaList(LayersLabel(plan.layers));
  manifest.video = {
      {"codec", codec_used},
      {"codecs", codecs},
      {"codec_reason", codec_reason},
      {"crf", o.crf},
      {"preset", o.preset.empty() ? kDefaultVideoPreset : o.preset},
      {"fps", o.fps},
      {"width", plan.video.width},
      {"height", plan.video.height},
      {"encoded_width", (plan.video.width + 1) & ~1},
      {"encoded_height", (plan.video.height + 1) & ~1},
      {"encoder_threads", plan.video.threads},
      {"x264_params", X264ParamsFor(o.preset.empty() ? kDefaultVideoPreset : o.preset)},
      {"encoders_per_worker", plan.encoders},
      {"container", plan.formats.front()},
      {"formats", plan.formats},
      {"gif", {{"fps", std::min(o.gif_fps, o.fps)}, {"width", o.gif_width}}},
      {"pix_fmt", "yuv420p"}};
  manifest.versions = VersionsJson();
  manifest.timings_s = {{"wall", wall},
                        {"sim", timings["sim"]},
                        {"render", timings["render"]},
                        {"encode", timings["encode"]},
                        {"write", timings["write"]}};
  manifest.frames = progress.frames();
  AddCpuAccount(cpu_stages, manifest.frames, &manifest.timings_s);
  manifest.interrupted = sig != 0;
  manifest.incomplete_episodes = incomplete;
  if (sig != 0) manifest.signal = sig == SIGINT ? "SIGINT" : "SIGTERM";
  manifest.command_line = command_line;
  manifest.parameters = parameters;
  manifest.resumed = o.resume && !folder.kept().empty();
  const fs::path manifest_path = fs::path(o.out) / ShardManifestName(shard);
  WriteManifest(manifest_path, manifest);
  folder.Commit();
  const std::string summary =
      RecordSummaryText(manifest, result.results.size(), folder.kept().size(), o.out);
  progress.Done(summary);
  const size_t rest = summary.find("record: to record the rest");
  if (o.quiet && rest != std::string::npos) {  // even --quiet: a batch job's log needs the way on
    std::fprintf(stderr, "%s\n", summary.substr(rest).c_str());
  }
  // a shard's episodes are only part of the run: merge-manifests writes the run's report
  if (!o.no_report && !shard.sharded()) WriteRunReportOrWarn(manifest_path, o.quiet);
  if (sig) return 128 + sig;
  if (!result.failures.empty()) {
    throw RunError(DescribeFailures(result) + "; the manifest lists the missing episodes (" +
                   std::to_string(result.missing.size()) + "): --resume records them");
  }
  if (!o.minari.empty()) {  // the run folder's episode files, read back as export reads them
    const TrajectorySource run = LoadTrajectorySource(o.out);
    Trajectory t;
    t.env_id = run.env_id;
    t.seed = run.seed;
    t.policy = run.policy;
    for (const auto& [k, episode] : run.episodes) t.episodes.push_back(episode);
    minari.code_permalink =
        DatasetPermalink("record", t.env_id, o.policy, plan.seed, o.episodes, o.steps);
    fs::path path;
    const std::string advice = "; the run is kept in " + o.out + ": `fetchscope export " + o.out +
                               " --minari " + o.minari +
                               (o.minari_root.empty() ? "" : " --minari-root " + o.minari_root) +
                               (o.overwrite ? " --overwrite" : "") + "` writes the dataset from it";
    try {
      path = WriteMinariDataset(t, minari);
    } catch (const MinariInterrupted& e) {
      std::fprintf(stderr, "record --minari: %s%s\n", e.what(), advice.c_str());
      return 128 + e.signal;
    } catch (const std::exception& e) {
      throw RunError("record --minari: " + std::string(e.what()) + advice);
    }
    std::printf("wrote Minari dataset %s at %s\n", o.minari.c_str(), path.c_str());
  }
  return 0;
}

}  // namespace

Command AddRecord(CLI::App& app) {
  auto o = std::make_shared<RecordOptions>();
  CLI::App* sub = app.add_subcommand(
      "record",
      "Record episodes: episode_NNN.mp4 (.webm, .gif: --format), episode_NNN_sheet.png, "
      "episode_NNN.json, manifest.json");
  AddEnvOptions(sub, &o->env);
  AddViewOptions(sub, &o->view);
  sub->add_option("--episodes", o->episodes, "Number of episodes")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  sub->add_option("--steps", o->steps, kStepsHelp)
      ->capture_default_str()
      ->check(CLI::Range(1, kMaxSteps));
  sub->add_option("--policy", o->policy, kPolicyHelp)->capture_default_str();
  sub->add_option("--exec-timeout", o->exec_timeout, "Seconds an exec: policy may take per answer")
      ->capture_default_str()
      ->check(CLI::Range(0.001, 86400.0));
  sub->add_option("--replay-dtype", o->replay_dtype, kReplayDtypeHelp);
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
  sub->add_option("--format", o->formats,
                  "Video formats, a comma list: mp4 (H.264), webm (VP9, plays in every browser and "
                  "wandb), gif (one palette per clip, scaled by --gif-fps/--gif-width); one file "
                  "per episode and format")
      ->capture_default_str();
  sub->add_option("--gif-fps", o->gif_fps, "GIF frame rate, 1..50 (at most --fps)")
      ->capture_default_str();
  sub->add_option(
         "--gif-width", o->gif_width,
         "GIF width in pixels, 16..4096 (never wider than the frames; height keeps the aspect); "
         "the GIF's HUD is sized for this width, and left out where a view would show smaller "
         "than 320x240")
      ->capture_default_str();
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
  sub->add_option("--out", o->out,
                  "Output folder: checked writable before anything is rendered; never --from's "
                  "folder, one holding it or one inside it")
      ->capture_default_str();
  sub->add_flag("-q,--quiet", o->quiet, "No progress or summary on stderr");
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
  return {sub, [o, sub] {
            o->episodes_given = sub->count("--episodes") > 0;
            if (!o->from.empty()) return RunRecordFrom(*o, *sub, CommandLine());
            ApplyReplayedEnv(o->policy, &o->env);  // replay:FILE.json brings its env and seed
            return RunRecord(*o, CommandLine());
          }};
}

}  // namespace fetchscope::cli
