// The record run's manifest, assembled from the plan and the workers' entries (RecordRun).
#include <signal.h>

#include <algorithm>
#include <cmath>

#include "base/suggest.h"
#include "encode/episode_sink.h"
#include "encode/video_format.h"
#include "render/layers.h"
#include "run/record_command.h"
#include "src/observation_layout.h"
#include "src/trajectory.h"
#include "src/versions.h"

namespace fetchscope {
namespace {

std::string PresetOrDefault(const std::string& preset) {
  return preset.empty() ? kDefaultVideoPreset : preset;
}

// The manifest's "video": the encoder of each format's files, and all of them in --format order
// as one line.
ManifestVideo RecordVideo(const RecordJob& job, const NodeProbe& node) {
  const RecordPlan& plan = job.plan;
  const VideoOptions& v = plan.video;
  ManifestVideo video;
  video.codecs.emplace();
  std::string codec_used;
  for (const VideoFormat* format : plan.formats) {
    const std::string codec = FormatCodec(*format, v.codec);
    (*video.codecs)[std::string(format->name)] = codec;
    codec_used += (codec_used.empty() ? "" : ", ") + codec;
  }
  video.codec = codec_used;
  video.codec_reason =
      EncodesH264(plan.formats)
          ? node.codec.reason
          : "--format " + job.formats_text + ": no H.264 encoded, so --codec does not apply";
  video.crf = v.crf;
  video.preset = PresetOrDefault(v.preset);
  video.fps = v.fps;
  video.width = v.width;
  video.height = v.height;
  video.encoded_width = (v.width + 1) & ~1;
  video.encoded_height = (v.height + 1) & ~1;
  video.encoder_threads = v.threads;
  video.x264_params = X264ParamsFor(PresetOrDefault(v.preset));
  video.encoders_per_worker = plan.encoders;
  video.container = plan.formats.front()->name;
  video.formats = VideoFormatNames(plan.formats);
  video.gif = ManifestVideoGif{std::min(v.gif_fps, v.fps), v.gif_width};
  video.pix_fmt = "yuv420p";
  return video;
}

// The manifest's "workers": each worker's Start() report (or its index) with its episodes.
std::vector<ManifestWorker> RecordWorkers(const std::vector<ManifestWorker>& started,
                                          std::map<int, std::vector<int>>& by_worker) {
  std::vector<ManifestWorker> workers;
  for (size_t w = 0; w < started.size(); ++w) {
    ManifestWorker entry = started[w];
    entry.episodes = by_worker[static_cast<int>(w)];
    workers.push_back(std::move(entry));
  }
  return workers;
}

// The GL setup, from the first worker that started (all run the same backend).
void AddRecordBackend(const std::vector<ManifestWorker>& started, Manifest* manifest) {
  ManifestWorker first;
  for (const ManifestWorker& w : started) {
    if (w.backend) {
      first = w;
      break;
    }
  }
  manifest->msaa = first.msaa.value_or(0);
  manifest->msaa_reason = first.msaa_reason.value_or("");
  manifest->backend.name = first.backend.value_or("");
  manifest->backend.device = first.device.value_or("");
  manifest->backend.gl_vendor = first.gl_vendor.value_or("");
  manifest->backend.gl_renderer = first.gl_renderer.value_or("");
  manifest->backend.gl_version = first.gl_version.value_or("");
}

}  // namespace

RunParameters RecordParameters(const RecordJob& job) {
  const RecordPlan& plan = job.plan;
  RunParameters p;
  p.env_id = plan.spec->id;
  p.seed = plan.seed;
  p.policy = plan.policy.text;
  p.replay_dtype = plan.policy.replay_dtype();
  p.episodes = job.episodes_requested;
  p.steps = plan.steps;
  p.sheet_every = plan.sheet_every;
  p.assets_sha256 = plan.assets.sha256;
  p.camera = job.view_text.camera;
  p.overlay = job.view_text.overlay;
  p.width = plan.view.render.width;
  p.height = plan.view.render.height;
  p.msaa = job.view_text.msaa;
  p.codec = plan.video.codec;
  p.crf = plan.video.crf;
  p.preset = PresetOrDefault(plan.video.preset);
  p.fps = plan.video.fps;
  p.shard_index = job.shard.index;
  p.shard_count = job.shard.count;
  p.formats = VideoFormatNames(plan.formats);
  p.gif_fps = plan.video.gif_fps;
  p.gif_width = plan.video.gif_width;
  p.layers = LayersLabel(plan.layers);
  p.signals = plan.contact_signals ? "contacts" : "none";
  return p;
}

RecordTally TallyRecordResults(const std::map<int, EpisodeResult>& results) {
  RecordTally tally;
  double sim = 0, render = 0, encode = 0, write = 0;
  for (const auto& [k, result] : results) {
    const EpisodeTimings& t = result.timings;
    sim += t.sim;
    render += t.render;
    encode += t.encode;
    write += t.write;
    for (const auto& [stage, seconds] : t.cpu_s) tally.cpu_stages[stage] += seconds;
    tally.by_worker[result.worker].push_back(k);
    tally.entries.push_back(result.entry);
  }
  tally.timings.sim = sim;
  tally.timings.render = render;
  tally.timings.encode = encode;
  tally.timings.write = write;
  return tally;
}

Manifest BuildRecordManifest(const RecordJob& job, const NodeProbe& node,
                             const ScheduleResult& result, RecordTally tally, double wall,
                             long frames, const RunParameters& parameters, bool resumed) {
  const RecordPlan& plan = job.plan;
  Manifest m;
  m.env_id = plan.spec->id;
  m.seed = plan.seed;
  m.policy = plan.policy.text;
  if (plan.from) m.from = plan.from->path;
  m.episodes_requested = job.episodes_requested;
  m.steps_per_episode = plan.steps;
  m.sheet_every = plan.sheet_every;
  m.episodes = std::move(tally.entries);
  if (plan.from) AddDivergence(*plan.from, &m.episodes, &m.extra);  // a dataset's drift
  m.missing = result.missing;
  for (const WorkerFailure& f : result.failures)
    m.failures.push_back({f.worker, f.episodes, f.message});
  m.shard = ManifestShard{job.shard.index, job.shard.count, std::nullopt, job.episodes};
  if (!job.shard.source.empty()) m.shard->source = job.shard.source;
  m.jobs = result.jobs;
  m.worker_mode = job.worker_mode;
  const std::vector<ManifestWorker> started = StartedWorkers(result);
  m.workers = RecordWorkers(started, tally.by_worker);
  m.gpu.request = job.view_text.gpu;
  m.gpu.choice = plan.gpu.reason;
  m.gpu.devices = plan.gpu.devices;
  m.assets = AssetsJson(plan.assets);
  m.model_file = job.model_path;
  m.camera = job.view_text.camera;
  for (const CameraSpec& c : plan.view.render.cameras) m.cameras.push_back(CameraText(c));
  if (plan.pixels.setup.enabled()) {
    const ObsSetup& obs = plan.pixels.setup;
    nlohmann::json cams = nlohmann::json::array();
    for (const ObsCamera& c : obs.cameras) cams.push_back({{"name", c.name}, {"camera", c.text}});
    nlohmann::json layers = nlohmann::json::array();
    for (Layer l : obs.layers) layers.push_back(LayerName(l));
    m.obs = {{"size", {obs.width, obs.height}},
             {"layers", layers},
             {"overlay", obs.overlay_text},
             {"cameras", cams}};
  }
  m.overlay = job.view_text.overlay;
  AddRecordBackend(started, &m);
  m.layers = SplitCommaList(LayersLabel(plan.layers));
  m.video = RecordVideo(job, node);
  m.versions = VersionsJson();
  m.timings_s = tally.timings;
  m.timings_s.wall = wall;
  m.frames = frames;
  AddCpuAccount(tally.cpu_stages, m.frames, &m.timings_s);
  // episodes cut short: by this run's signal, or already in the recording --from replays
  for (const ManifestEpisode& e : m.episodes) {
    if (!e.complete.value_or(true)) m.incomplete_episodes.push_back(e.index);
  }
  m.interrupted = result.signal != 0;
  if (result.signal != 0) m.signal = result.signal == SIGINT ? "SIGINT" : "SIGTERM";
  m.command_line = job.command_line;
  m.parameters = parameters;
  m.resumed = resumed;
  return m;
}

nlohmann::json DivergenceJson(const EpisodeDivergence& d) {
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
    j["component"] = d.component;
    j["unit"] = d.unit;
    j["difference"] = number(d.difference);
  }
  // the viewer's "replayed vs recorded" plot: position errors per row, in mm
  const auto millimetres = [&](const std::vector<double>& metres) {
    nlohmann::json out = nlohmann::json::array();
    for (double m : metres) out.push_back(number(InDisplayUnit(m, "m").value));
    return out;
  };
  j["position_error_mm"] = {{"gripper", millimetres(d.gripper_error)}};
  if (!d.object_error.empty()) j["position_error_mm"]["object"] = millimetres(d.object_error);
  if (d.max_step >= 0) {  // the largest difference, with its place
    j["max_step"] = d.max_step;
    j["max_where"] = d.max_where;
    j["max_component"] = d.max_component;
    j["max_unit"] = d.max_unit;
  }
  return j;
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
    e.extra["divergence"] = DivergenceJson(d);
  }
}

}  // namespace fetchscope
