// The manifest's typed sections, read and written (run/manifest_sections.h), and each episode entry
// (run/manifest.h's ManifestEpisodeToJson): the manifest reader and writer of run/manifest.cc call
// these.
#include "run/manifest_sections.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "base/json_util.h"
#include "encode/video_format.h"
#include "run/manifest.h"

namespace fetchscope {
namespace {

using nlohmann::json;

// ---- one member: written when set; read when writing it back gives the same JSON text

template <class T>
json ValueToJson(const T& value) {
  return json(value);
}
json ValueToJson(const ManifestVideoGif& gif);

template <class T>
bool ValueFromJson(const json& j, T* value) {
  try {
    T v = j.get<T>();
    if (json(v).dump() != j.dump()) return false;  // 1 for a 1.0, 2.5 for an int...: kept as is
    *value = std::move(v);
    return true;
  } catch (const json::exception&) {
    return false;
  }
}
bool ValueFromJson(const json& j, ManifestVideoGif* gif);

// Writes `value` as `key` of `out` when it is set.
template <class T>
void Put(json* out, const char* key, const std::optional<T>& value) {
  if (value) (*out)[key] = ValueToJson(*value);
}

// Reads `key` of `*extra` into `value`, and takes it out of `extra`; a value of another type
// stays in `extra` (and so is written back as it was).
template <class T>
void Take(json* extra, const char* key, std::optional<T>* value) {
  const auto it = extra->find(key);
  if (it == extra->end()) return;
  T v;
  if (!ValueFromJson(*it, &v)) return;
  *value = std::move(v);
  extra->erase(it);
}

// ---- each section's members, for the writer (Put), the reader (Take) and ==

template <class S, class F>
void GifFields(S& g, F&& f) {
  f("fps", g.fps);
  f("width", g.width);
}

template <class S, class F>
void VideoFields(S& v, F&& f) {
  f("codec", v.codec);
  f("codecs", v.codecs);
  f("codec_reason", v.codec_reason);
  f("crf", v.crf);
  f("preset", v.preset);
  f("fps", v.fps);
  f("width", v.width);
  f("height", v.height);
  f("encoded_width", v.encoded_width);
  f("encoded_height", v.encoded_height);
  f("encoder_threads", v.encoder_threads);
  f("x264_params", v.x264_params);
  f("encoders_per_worker", v.encoders_per_worker);
  f("container", v.container);
  f("formats", v.formats);
  f("gif", v.gif);
  f("pix_fmt", v.pix_fmt);
}

template <class S, class F>
void BackendFields(S& b, F&& f) {
  f("name", b.name);
  f("device", b.device);
  f("gl_vendor", b.gl_vendor);
  f("gl_renderer", b.gl_renderer);
  f("gl_version", b.gl_version);
}

template <class S, class F>
void GpuFields(S& g, F&& f) {
  f("request", g.request);
  f("choice", g.choice);
  f("devices", g.devices);
}

template <class S, class F>
void WorkerFields(S& w, F&& f) {
  f("worker", w.worker);
  f("pid", w.pid);
  f("backend", w.backend);
  f("device", w.device);
  f("device_selection", w.device_selection);
  f("gl_vendor", w.gl_vendor);
  f("gl_renderer", w.gl_renderer);
  f("gl_version", w.gl_version);
  f("msaa", w.msaa);
  f("msaa_reason", w.msaa_reason);
  f("readback", w.readback);
  f("episodes", w.episodes);
}

template <class S, class F>
void TimingsFields(S& t, F&& f) {
  f("wall", t.wall);
  f("wall_sum", t.wall_sum);
  f("sim", t.sim);
  f("render", t.render);
  f("encode", t.encode);
  f("write", t.write);
  f("cpu_s", t.cpu_s);
  f("cpu_ms_per_frame", t.cpu_ms_per_frame);
}

template <class S, class F>
void HindsightFields(S& h, F&& f) {
  f("relabelled_successes", h.relabelled_successes);
  f("original_successes", h.original_successes);
  f("k", h.k);
  f("transitions", h.transitions);
}

// A section as JSON: its unknown members, then each member that is set.
template <class S, class Fields>
json SectionToJson(const S& section, Fields fields) {
  json out = section.extra.is_object() ? section.extra : json::object();
  fields(section, [&out](const char* key, const auto& value) { Put(&out, key, value); });
  return out;
}

// A section from JSON: `what` names it in the error for what is not an object.
template <class S, class Fields>
S SectionFromJson(const json& j, const char* what, Fields fields) {
  if (!j.is_object()) throw ManifestError("has a " + std::string(what) + " that is not an object");
  S section;
  section.extra = j;
  fields(section, [&section](const char* key, auto& value) { Take(&section.extra, key, &value); });
  return section;
}

#define FETCHSCOPE_FIELDS(name) [](auto& s, auto&& f) { name(s, f); }

json ValueToJson(const ManifestVideoGif& gif) {
  return SectionToJson(gif, FETCHSCOPE_FIELDS(GifFields));
}

bool ValueFromJson(const json& j, ManifestVideoGif* gif) {
  if (!j.is_object()) return false;
  *gif = SectionFromJson<ManifestVideoGif>(j, "video gif", FETCHSCOPE_FIELDS(GifFields));
  return true;
}

// ---- episodes

json VideosToJson(const std::map<std::string, VideoFile>& videos) {
  json out = json::object();
  for (const auto& [format, v] : videos) {
    json file = {{"file", v.file}};
    if (v.frames >= 0) file["frames"] = v.frames;
    out[format] = std::move(file);
  }
  return out;
}

std::map<std::string, VideoFile> VideosFromJson(const json& j) {
  std::map<std::string, VideoFile> videos;
  for (const auto& [format, v] : j.items()) {
    VideoFile file;
    file.file = v.at("file").get<std::string>();
    file.frames = v.value("frames", -1);
    videos[format] = std::move(file);
  }
  return videos;
}

// mp4 (H.264) and webm (VP9) play in every browser; a gif is an image
int FormatRank(const std::string& format) {
  const VideoFormat* row = FindVideoFormat(format);
  return row != nullptr ? row->browser_rank : static_cast<int>(VideoFormats().size());
}

std::vector<EpisodeVideo> SortedVideos(const std::string& video,
                                       const std::map<std::string, VideoFile>& videos, int frames) {
  std::vector<EpisodeVideo> out;
  for (const auto& [format, v] : videos) out.push_back({format, v.file, v.frames});
  if (out.empty() && !video.empty()) {  // manifests from before --format
    std::string format = std::filesystem::path(video).extension().string();
    if (!format.empty()) format.erase(0, 1);
    out.push_back({format, video, frames});
  }
  std::stable_sort(out.begin(), out.end(), [](const EpisodeVideo& a, const EpisodeVideo& b) {
    const int ra = FormatRank(a.format), rb = FormatRank(b.format);
    return ra != rb ? ra < rb : a.format < b.format;
  });
  return out;
}

std::optional<int> OptionalInt(const json& j, const char* key) {
  if (!j.contains(key)) return std::nullopt;
  return j.at(key).get<int>();
}

// "return": a number, or JsonDouble's "inf", "-inf", "nan"
double ReadDouble(const json& v) {
  if (v.is_string()) {
    const std::string s = v.get<std::string>();
    if (s == "inf") return HUGE_VAL;
    if (s == "-inf") return -HUGE_VAL;
    if (s == "nan") return std::nan("");
    throw ManifestError("has a number written as '" + s + "'");
  }
  return v.get<double>();
}

}  // namespace

// ---- the sections

bool ManifestVideoGif::operator==(const ManifestVideoGif& o) const {
  return ValueToJson(*this) == ValueToJson(o);
}

json ManifestVideoToJson(const ManifestVideo& video) {
  return SectionToJson(video, FETCHSCOPE_FIELDS(VideoFields));
}

ManifestVideo ManifestVideoFromJson(const json& j) {
  return SectionFromJson<ManifestVideo>(j, "video", FETCHSCOPE_FIELDS(VideoFields));
}

bool ManifestVideo::operator==(const ManifestVideo& o) const {
  return ManifestVideoToJson(*this) == ManifestVideoToJson(o);
}

json ManifestBackendToJson(const ManifestBackend& backend) {
  return SectionToJson(backend, FETCHSCOPE_FIELDS(BackendFields));
}

ManifestBackend ManifestBackendFromJson(const json& j) {
  return SectionFromJson<ManifestBackend>(j, "backend", FETCHSCOPE_FIELDS(BackendFields));
}

bool ManifestBackend::operator==(const ManifestBackend& o) const {
  return ManifestBackendToJson(*this) == ManifestBackendToJson(o);
}

json ManifestGpuToJson(const ManifestGpu& gpu) {
  return SectionToJson(gpu, FETCHSCOPE_FIELDS(GpuFields));
}

ManifestGpu ManifestGpuFromJson(const json& j) {
  return SectionFromJson<ManifestGpu>(j, "gpu", FETCHSCOPE_FIELDS(GpuFields));
}

bool ManifestGpu::operator==(const ManifestGpu& o) const {
  return ManifestGpuToJson(*this) == ManifestGpuToJson(o);
}

json ManifestWorkerToJson(const ManifestWorker& worker) {
  return SectionToJson(worker, FETCHSCOPE_FIELDS(WorkerFields));
}

ManifestWorker ManifestWorkerFromJson(const json& j) {
  return SectionFromJson<ManifestWorker>(j, "worker", FETCHSCOPE_FIELDS(WorkerFields));
}

bool ManifestWorker::operator==(const ManifestWorker& o) const {
  return ManifestWorkerToJson(*this) == ManifestWorkerToJson(o);
}

json ManifestWorkersToJson(const std::vector<ManifestWorker>& workers) {
  json out = json::array();
  for (const ManifestWorker& w : workers) out.push_back(ManifestWorkerToJson(w));
  return out;
}

std::vector<ManifestWorker> ManifestWorkersFromJson(const json& j) {
  if (!j.is_array()) throw ManifestError("has workers that are not a list");
  std::vector<ManifestWorker> workers;
  for (const json& w : j) workers.push_back(ManifestWorkerFromJson(w));
  return workers;
}

json ManifestTimingsToJson(const ManifestTimings& timings) {
  return SectionToJson(timings, FETCHSCOPE_FIELDS(TimingsFields));
}

ManifestTimings ManifestTimingsFromJson(const json& j) {
  return SectionFromJson<ManifestTimings>(j, "timings_s", FETCHSCOPE_FIELDS(TimingsFields));
}

bool ManifestTimings::operator==(const ManifestTimings& o) const {
  return ManifestTimingsToJson(*this) == ManifestTimingsToJson(o);
}

json EpisodeHindsightToJson(const EpisodeHindsight& hindsight) {
  return SectionToJson(hindsight, FETCHSCOPE_FIELDS(HindsightFields));
}

EpisodeHindsight EpisodeHindsightFromJson(const json& j) {
  return SectionFromJson<EpisodeHindsight>(j, "hindsight", FETCHSCOPE_FIELDS(HindsightFields));
}

#undef FETCHSCOPE_FIELDS

// ---- episodes

std::vector<EpisodeVideo> EpisodeVideos(const ManifestEpisode& episode) {
  return SortedVideos(episode.video, episode.videos, episode.frames.value_or(-1));
}

std::vector<EpisodeVideo> EpisodeVideos(const EpisodeLayer& layer) {
  return SortedVideos(layer.video, layer.videos, -1);
}

json ManifestEpisodeToJson(const ManifestEpisode& e) {
  json out = e.extra.is_object() ? e.extra : json::object();
  out["index"] = e.index;
  if (!e.video.empty()) out["video"] = e.video;
  if (!e.videos.empty()) out["videos"] = VideosToJson(e.videos);
  if (!e.sheet.empty()) out["sheet"] = e.sheet;
  if (!e.trajectory.empty()) out["trajectory"] = e.trajectory;
  if (e.frames) out["frames"] = *e.frames;
  if (e.steps) out["steps"] = *e.steps;
  if (e.complete) out["complete"] = *e.complete;
  if (e.episode_return) out["return"] = JsonDouble(*e.episode_return);
  out["is_success"] = e.is_success;
  if (e.hindsight) out["hindsight"] = EpisodeHindsightToJson(*e.hindsight);
  if (!e.layers.empty()) {
    json layers = json::object();
    for (const auto& [name, layer] : e.layers) {
      json l = layer.details.is_object() ? layer.details : json::object();
      l["video"] = layer.video;
      l["videos"] = VideosToJson(layer.videos);
      if (!layer.legend.empty()) l["legend"] = layer.legend;
      layers[name] = std::move(l);
    }
    out["layers"] = std::move(layers);
  }
  return out;
}

ManifestEpisode ManifestEpisodeFromJson(const json& j) {
  if (!j.is_object() || !j.contains("index") || !j.at("index").is_number_integer()) {
    throw ManifestError("has an episode without an index: " + j.dump());
  }
  ManifestEpisode e;
  e.extra = j;
  auto take = [&e](const char* key) -> const json* {
    const auto it = e.extra.find(key);
    return it == e.extra.end() ? nullptr : &*it;
  };
  e.index = j.at("index").get<int>();
  if (const json* v = take("video")) e.video = v->get<std::string>();
  if (const json* v = take("videos")) e.videos = VideosFromJson(*v);
  if (const json* v = take("sheet")) e.sheet = v->get<std::string>();
  if (const json* v = take("trajectory")) e.trajectory = v->get<std::string>();
  e.frames = OptionalInt(j, "frames");
  e.steps = OptionalInt(j, "steps");
  if (const json* v = take("complete")) e.complete = v->get<bool>();
  if (const json* v = take("return")) e.episode_return = ReadDouble(*v);
  if (const json* v = take("is_success")) e.is_success = v->get<bool>();
  if (const json* v = take("hindsight"); v != nullptr && v->is_object()) {
    e.hindsight = EpisodeHindsightFromJson(*v);
    e.extra.erase("hindsight");
  }
  if (const json* v = take("layers")) {
    for (const auto& [name, l] : v->items()) {
      EpisodeLayer layer;
      layer.details = l;
      layer.video = l.value("video", std::string());
      if (l.contains("videos")) layer.videos = VideosFromJson(l.at("videos"));
      layer.legend = l.value("legend", std::string());
      for (const char* key : {"video", "videos", "legend"}) layer.details.erase(key);
      e.layers[name] = std::move(layer);
    }
  }
  for (const char* key : {"index", "video", "videos", "sheet", "trajectory", "frames", "steps",
                          "complete", "return", "is_success", "layers"}) {
    e.extra.erase(key);
  }
  return e;
}

}  // namespace fetchscope
