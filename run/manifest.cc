#include "run/manifest.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <tuple>

#include "base/atomic_file.h"
#include "base/json_util.h"
#include "encode/video_format.h"

namespace fetchscope {
namespace {

using nlohmann::json;

// ---- the run's parameters: one row per record option, in the order SameRun compares them

struct ParameterRow {
  const char* option;
  json (*get)(const RunParameters&);
  void (*set)(RunParameters*, const json&);
  bool (*stored)(const RunParameters&);  // nullptr: always; else only when it changes the files
  bool same_episodes;                    // part of SameRunScope::kEpisodes
};

bool HasGif(const RunParameters& p) { return HasPaletteFormat(p.formats); }

#define FETCHSCOPE_PARAMETER(option, member, stored, episodes)                         \
  ParameterRow {                                                                       \
    option, [](const RunParameters& p) { return json(p.member); },                     \
        [](RunParameters* p, const json& v) { v.get_to(p->member); }, stored, episodes \
  }

// Newer options join only when they change the files, so that runs recorded before they existed
// stay the same run as the runs recorded after without them.
const std::vector<ParameterRow>& ParameterTable() {
  static const std::vector<ParameterRow> table = {
      FETCHSCOPE_PARAMETER("--env-id", env_id, nullptr, true),
      FETCHSCOPE_PARAMETER("--seed", seed, nullptr, true),
      FETCHSCOPE_PARAMETER("--policy", policy, nullptr, false),
      FETCHSCOPE_PARAMETER("--replay-dtype", replay_dtype, nullptr, false),
      FETCHSCOPE_PARAMETER("--episodes", episodes, nullptr, false),
      FETCHSCOPE_PARAMETER("--steps", steps, nullptr, true),
      FETCHSCOPE_PARAMETER("--sheet-every", sheet_every, nullptr, false),
      FETCHSCOPE_PARAMETER("--assets", assets_sha256, nullptr, false),
      FETCHSCOPE_PARAMETER("--camera", camera, nullptr, false),
      FETCHSCOPE_PARAMETER("--overlay", overlay, nullptr, false),
      FETCHSCOPE_PARAMETER("--width", width, nullptr, false),
      FETCHSCOPE_PARAMETER("--height", height, nullptr, false),
      FETCHSCOPE_PARAMETER("--msaa", msaa, nullptr, false),
      FETCHSCOPE_PARAMETER("--codec", codec, nullptr, false),
      FETCHSCOPE_PARAMETER("--crf", crf, nullptr, false),
      FETCHSCOPE_PARAMETER("--preset", preset, nullptr, false),
      FETCHSCOPE_PARAMETER("--fps", fps, nullptr, false),
      ParameterRow{
          "--shard",
          [](const RunParameters& p) {
            return json(std::to_string(p.shard_index) + "/" + std::to_string(p.shard_count));
          },
          [](RunParameters* p, const json& v) {
            const std::string text = v.get<std::string>();
            const size_t slash = text.find('/');
            if (slash == std::string::npos) {
              throw ManifestError("has a parameter --shard '" + text + "' that is not I/N");
            }
            p->shard_index = std::stoi(text.substr(0, slash));
            p->shard_count = std::stoi(text.substr(slash + 1));
          },
          nullptr, false},
      FETCHSCOPE_PARAMETER(
          "--format", formats,
          [](const RunParameters& p) { return p.formats != std::vector<std::string>{"mp4"}; },
          false),
      FETCHSCOPE_PARAMETER("--gif-fps", gif_fps, HasGif, false),
      FETCHSCOPE_PARAMETER("--gif-width", gif_width, HasGif, false),
      FETCHSCOPE_PARAMETER(
          "--layers", layers, [](const RunParameters& p) { return p.layers != "rgb"; }, false),
  };
  return table;
}

#undef FETCHSCOPE_PARAMETER

bool Stored(const ParameterRow& row, const RunParameters& p) {
  return !row.stored || row.stored(p);
}

// A parameter's value for a message: strings as they are, lists joined with commas.
std::string Shown(const json& value) {
  if (value.is_string()) return value.get<std::string>();
  if (value.is_array()) {
    std::string text;
    for (const json& v : value) text += (text.empty() ? "" : ",") + Shown(v);
    return text;
  }
  return value.dump();
}

json ParametersToJson(const RunParameters& p) {
  json out = json::object();
  for (const ParameterRow& row : ParameterTable()) {
    if (Stored(row, p)) out[row.option] = row.get(p);
  }
  return out;
}

RunParameters ParametersFromJson(const json& j) {
  RunParameters p;
  for (const ParameterRow& row : ParameterTable()) {
    if (j.contains(row.option)) row.set(&p, j.at(row.option));
  }
  return p;
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

bool SameDouble(const std::optional<double>& a, const std::optional<double>& b) {
  if (a.has_value() != b.has_value()) return false;
  if (!a) return true;
  return *a == *b || (std::isnan(*a) && std::isnan(*b));
}

std::string ReadText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ManifestError("cannot read '" + path.string() + "'");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

json OptionalString(const std::optional<std::string>& s) { return s ? json(*s) : json(nullptr); }

std::optional<std::string> ReadOptionalString(const json& j, const char* key) {
  if (!j.contains(key) || j.at(key).is_null()) return std::nullopt;
  return j.at(key).get<std::string>();
}

}  // namespace

// ---- RunParameters and SameRun

bool RunParameters::operator==(const RunParameters& o) const {
  return recorded == o.recorded && ParametersToJson(*this) == ParametersToJson(o);
}

std::vector<std::string> RunParameterNames() {
  std::vector<std::string> names;
  for (const ParameterRow& row : ParameterTable()) names.push_back(row.option);
  return names;
}

std::optional<RunDifference> SameRun(const RunParameters& a, const RunParameters& b,
                                     SameRunScope scope) {
  for (const ParameterRow& row : ParameterTable()) {
    if (scope == SameRunScope::kEpisodes && !row.same_episodes) continue;
    // an option neither run stored did not change their files (a gif's rate without gifs)
    if (!Stored(row, a) && !Stored(row, b)) continue;
    const json va = row.get(a), vb = row.get(b);
    if (va == vb) continue;
    // the shards of one run differ in their index alone
    if (scope == SameRunScope::kShards && std::string(row.option) == "--shard" &&
        a.shard_count == b.shard_count) {
      continue;
    }
    return RunDifference{row.option, Shown(va), Shown(vb)};
  }
  return std::nullopt;
}

// ---- episodes

std::vector<std::string*> ManifestEpisode::Files() {
  std::vector<std::string*> files;
  auto add = [&files](std::string* name) {
    if (!name->empty()) files.push_back(name);
  };
  add(&video);
  for (auto& [format, v] : videos) add(&v.file);
  add(&sheet);
  add(&trajectory);
  for (auto& [name, layer] : layers) {
    add(&layer.video);
    for (auto& [format, v] : layer.videos) add(&v.file);
    add(&layer.legend);
  }
  return files;
}

std::vector<std::string> ManifestEpisode::FileNames() const {
  ManifestEpisode copy = *this;
  std::vector<std::string> names;
  for (const std::string* name : copy.Files()) names.push_back(*name);
  return names;
}

bool ManifestEpisode::operator==(const ManifestEpisode& o) const {
  return std::tie(index, video, videos, sheet, trajectory, frames, steps, complete, is_success,
                  layers, extra) == std::tie(o.index, o.video, o.videos, o.sheet, o.trajectory,
                                             o.frames, o.steps, o.complete, o.is_success, o.layers,
                                             o.extra) &&
         SameDouble(episode_return, o.episode_return);
}

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

// ---- the manifest

bool Manifest::operator==(const Manifest& o) const {
  auto tie = [](const Manifest& m) {
    return std::tie(m.schema_version, m.env_id, m.seed, m.policy, m.from, m.episodes_requested,
                    m.steps_per_episode, m.sheet_every, m.episodes, m.missing, m.failures, m.shard,
                    m.jobs, m.worker_mode, m.workers, m.gpu, m.assets, m.model_file, m.camera,
                    m.overlay, m.msaa, m.msaa_reason, m.backend, m.layers, m.video, m.versions,
                    m.timings_s, m.frames, m.interrupted, m.incomplete_episodes, m.signal,
                    m.command_line, m.parameters, m.resumed, m.merged, m.shards, m.extra);
  };
  return tie(*this) == tie(o);
}

json ManifestToJson(const Manifest& m) {
  json out = m.extra.is_object() ? m.extra : json::object();
  out["schema_version"] = kManifestSchemaVersion;
  out["env_id"] = m.env_id;
  out["seed"] = m.seed;
  out["policy"] = m.policy;
  out["from"] = OptionalString(m.from);
  out["episodes_requested"] = m.episodes_requested;
  out["steps_per_episode"] = m.steps_per_episode;
  out["sheet_every"] = m.sheet_every;
  json episodes = json::array();
  for (const ManifestEpisode& e : m.episodes) episodes.push_back(ManifestEpisodeToJson(e));
  out["episodes"] = std::move(episodes);
  if (m.merged) {
    out["merged"] = true;
    out["shards"] = m.shards;
  } else {  // what one record process did
    out["missing"] = m.missing;
    json failures = json::array();
    for (const ManifestFailure& f : m.failures) {
      failures.push_back({{"worker", f.worker}, {"episodes", f.episodes}, {"message", f.message}});
    }
    out["failures"] = std::move(failures);
    if (m.shard) {
      out["shard"] = {{"index", m.shard->index},
                      {"count", m.shard->count},
                      {"source", OptionalString(m.shard->source)}};
      if (m.shard->episodes) out["shard"]["episodes"] = *m.shard->episodes;
    }
    out["jobs"] = m.jobs;
    out["worker_mode"] = m.worker_mode;
    out["workers"] = m.workers;
    out["gpu"] = m.gpu;
  }
  out["assets"] = m.assets;
  out["model_file"] = m.model_file;
  out["camera"] = m.camera;
  out["overlay"] = m.overlay;
  out["msaa"] = m.msaa;
  out["msaa_reason"] = m.msaa_reason;
  out["backend"] = m.backend;
  out["layers"] = m.layers;
  out["video"] = m.video;
  out["versions"] = m.versions;
  out["timings_s"] = m.timings_s;
  out["frames"] = m.frames;
  out["interrupted"] = m.interrupted;
  out["incomplete_episodes"] = m.incomplete_episodes;
  out["signal"] = OptionalString(m.signal);
  out["command_line"] = m.command_line;
  if (m.parameters.recorded) out["parameters"] = ParametersToJson(m.parameters);
  out["resumed"] = m.resumed;
  return out;
}

Manifest ManifestFromJson(const json& j) {
  Manifest m;
  // the version first: a newer one may have moved anything else
  const auto version = j.is_object() ? j.find("schema_version") : j.end();
  if (j.is_object() && version != j.end()) {
    if (!version->is_number_integer() || version->get<int>() < 0) {
      throw ManifestError("has a bad schema_version " + version->dump());
    }
    m.schema_version = version->get<int>();
    if (m.schema_version > kManifestSchemaVersion) {
      throw ManifestError("has manifest schema version " + std::to_string(m.schema_version) +
                          "; this fetchscope reads versions 0 to " +
                          std::to_string(kManifestSchemaVersion) + ": use a newer fetchscope");
    }
  } else {
    m.schema_version = 0;  // written before versions existed: the same layout
  }
  if (!j.is_object() || !j.contains("env_id") || !j.contains("episodes") ||
      !j.at("episodes").is_array()) {
    throw ManifestError("is not a record manifest (it lacks env_id or episodes)");
  }
  try {
    m.extra = j;
    m.env_id = j.at("env_id").get<std::string>();
    m.seed = j.value("seed", uint64_t{0});
    m.policy = j.value("policy", std::string());
    m.from = ReadOptionalString(j, "from");
    m.episodes_requested = j.value("episodes_requested", static_cast<int>(j.at("episodes").size()));
    m.steps_per_episode = j.value("steps_per_episode", 0);
    m.sheet_every = j.value("sheet_every", 0);
    for (const json& e : j.at("episodes")) m.episodes.push_back(ManifestEpisodeFromJson(e));
    m.missing = j.value("missing", std::vector<int>());
    for (const json& f : j.value("failures", json::array())) {
      m.failures.push_back({f.value("worker", 0), f.value("episodes", std::vector<int>()),
                            f.value("message", std::string())});
    }
    if (j.contains("shard") && j.at("shard").is_object()) {
      const json& s = j.at("shard");
      ManifestShard shard;
      shard.index = s.value("index", 0);
      shard.count = s.value("count", 1);
      shard.source = ReadOptionalString(s, "source");
      if (s.contains("episodes")) shard.episodes = s.at("episodes").get<std::vector<int>>();
      m.shard = std::move(shard);
    }
    m.jobs = j.value("jobs", 1);
    m.worker_mode = j.value("worker_mode", std::string());
    m.workers = j.value("workers", json::array());
    m.gpu = j.value("gpu", json::object());
    m.assets = j.value("assets", json::object());
    m.model_file = j.value("model_file", std::string());
    m.camera = j.value("camera", std::string());
    m.overlay = j.value("overlay", std::string());
    m.msaa = j.value("msaa", 0);
    m.msaa_reason = j.value("msaa_reason", std::string());
    m.backend = j.value("backend", json::object());
    m.layers = j.value("layers", std::vector<std::string>());
    m.video = j.value("video", json::object());
    m.versions = j.value("versions", json::object());
    m.timings_s = j.value("timings_s", json::object());
    m.frames = j.value("frames", 0L);
    m.interrupted = j.value("interrupted", false);
    m.incomplete_episodes = j.value("incomplete_episodes", std::vector<int>());
    m.signal = ReadOptionalString(j, "signal");
    m.command_line = j.value("command_line", std::string());
    if (j.contains("parameters")) {
      m.parameters = ParametersFromJson(j.at("parameters"));
    } else {  // from before "parameters": what the manifest's own members say
      m.parameters.recorded = false;
      m.parameters.env_id = m.env_id;
      m.parameters.seed = m.seed;
      m.parameters.steps = m.steps_per_episode;
    }
    m.resumed = j.value("resumed", false);
    m.merged = j.value("merged", false);
    m.shards = j.value("shards", json::array());
  } catch (const json::exception& e) {
    throw ManifestError(std::string("is not a record manifest: ") + e.what());
  } catch (const std::invalid_argument&) {  // --shard's std::stoi
    throw ManifestError("has a parameter --shard that is not I/N");
  } catch (const std::out_of_range&) {
    throw ManifestError("has a parameter --shard that is not I/N");
  }
  for (const char* key : {"schema_version",
                          "env_id",
                          "seed",
                          "policy",
                          "from",
                          "episodes_requested",
                          "steps_per_episode",
                          "sheet_every",
                          "episodes",
                          "missing",
                          "failures",
                          "shard",
                          "jobs",
                          "worker_mode",
                          "workers",
                          "gpu",
                          "assets",
                          "model_file",
                          "camera",
                          "overlay",
                          "msaa",
                          "msaa_reason",
                          "backend",
                          "layers",
                          "video",
                          "versions",
                          "timings_s",
                          "frames",
                          "interrupted",
                          "incomplete_episodes",
                          "signal",
                          "command_line",
                          "parameters",
                          "resumed",
                          "merged",
                          "shards"}) {
    m.extra.erase(key);
  }
  return m;
}

Manifest ReadManifest(const std::filesystem::path& path) {
  json j;
  try {
    j = json::parse(ReadText(path));
  } catch (const json::parse_error& e) {
    throw ManifestError("'" + path.string() + "' is not JSON: " + e.what());
  }
  try {
    return ManifestFromJson(j);
  } catch (const ManifestError& e) {
    throw ManifestError("'" + path.string() + "' " + e.what());
  }
}

void WriteManifest(const std::filesystem::path& path, const Manifest& manifest) {
  WriteFileAtomically(path.string(), DumpJson(ManifestToJson(manifest)) + "\n");
}

}  // namespace fetchscope
