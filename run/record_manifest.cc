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
nlohmann::json RecordVideoJson(const RecordJob& job, const NodeProbe& node) {
  const RecordPlan& plan = job.plan;
  const VideoOptions& v = plan.video;
  const bool h264 = EncodesH264(plan.formats);
  nlohmann::json codecs = nlohmann::json::object();
  std::string codec_used;
  for (const VideoFormat* format : plan.formats) {
    const std::string codec = FormatCodec(*format, v.codec);
    codecs[std::string(format->name)] = codec;
    codec_used += (codec_used.empty() ? "" : ", ") + codec;
  }
  const std::string codec_reason =
      h264 ? node.codec.reason
           : "--format " + job.formats_text + ": no H.264 encoded, so --codec does not apply";
  return {{"codec", codec_used},
          {"codecs", codecs},
          {"codec_reason", codec_reason},
          {"crf", v.crf},
          {"preset", PresetOrDefault(v.preset)},
          {"fps", v.fps},
          {"width", v.width},
          {"height", v.height},
          {"encoded_width", (v.width + 1) & ~1},
          {"encoded_height", (v.height + 1) & ~1},
          {"encoder_threads", v.threads},
          {"x264_params", X264ParamsFor(PresetOrDefault(v.preset))},
          {"encoders_per_worker", plan.encoders},
          {"container", plan.formats.front()->name},
          {"formats", VideoFormatNames(plan.formats)},
          {"gif", {{"fps", std::min(v.gif_fps, v.fps)}, {"width", v.gif_width}}},
          {"pix_fmt", "yuv420p"}};
}

// The manifest's "workers": each worker's Start() entry (or its index) with its episodes.
nlohmann::json RecordWorkersJson(const ScheduleResult& result,
                                 std::map<int, std::vector<int>>& by_worker) {
  nlohmann::json workers = nlohmann::json::array();
  for (size_t w = 0; w < result.workers.size(); ++w) {
    nlohmann::json entry =
        result.workers[w].is_null() ? nlohmann::json{{"worker", w}} : result.workers[w];
    entry["episodes"] = by_worker[static_cast<int>(w)];
    workers.push_back(std::move(entry));
  }
  return workers;
}

// The GL setup, from the first worker that started (all run the same backend).
void AddRecordBackend(const ScheduleResult& result, Manifest* manifest) {
  nlohmann::json first;
  for (const nlohmann::json& w : result.workers) {
    if (!w.is_null()) {
      first = w;
      break;
    }
  }
  manifest->msaa = first.value("msaa", 0);
  manifest->msaa_reason = first.value("msaa_reason", "");
  manifest->backend = {{"name", first.value("backend", "")},
                       {"device", first.value("device", "")},
                       {"gl_vendor", first.value("gl_vendor", "")},
                       {"gl_renderer", first.value("gl_renderer", "")},
                       {"gl_version", first.value("gl_version", "")}};
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
  return p;
}

RecordTally TallyRecordResults(const ScheduleResult& result) {
  RecordTally tally;
  tally.timings = {{"sim", 0}, {"render", 0}, {"encode", 0}, {"write", 0}};
  for (const auto& [k, entry] : result.results) {
    nlohmann::json e = entry;
    for (auto& [phase, seconds] : tally.timings) seconds += e["timings_s"][phase].get<double>();
    if (e["timings_s"].contains("cpu_s")) {
      for (const auto& [stage, seconds] : e["timings_s"]["cpu_s"].items()) {
        tally.cpu_stages[stage] += seconds.get<double>();
      }
    }
    tally.by_worker[e.at("worker").get<int>()].push_back(k);
    // what differs with --jobs stays out of the episode entries (they are identical)
    e.erase("worker");
    e.erase("timings_s");
    e.erase("codec");
    e.erase("encoded_width");
    e.erase("encoded_height");
    tally.entries.push_back(ManifestEpisodeFromJson(e));
  }
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
  m.workers = RecordWorkersJson(result, tally.by_worker);
  m.gpu = {
      {"request", job.view_text.gpu}, {"choice", plan.gpu.reason}, {"devices", plan.gpu.devices}};
  m.assets = AssetsJson(plan.assets);
  m.model_file = job.model_path;
  m.camera = job.view_text.camera;
  m.overlay = job.view_text.overlay;
  AddRecordBackend(result, &m);
  m.layers = SplitCommaList(LayersLabel(plan.layers));
  m.video = RecordVideoJson(job, node);
  m.versions = VersionsJson();
  m.timings_s = {{"wall", wall},
                 {"sim", tally.timings["sim"]},
                 {"render", tally.timings["render"]},
                 {"encode", tally.timings["encode"]},
                 {"write", tally.timings["write"]}};
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
    e.extra["divergence"] = j;
  }
}

}  // namespace fetchscope
