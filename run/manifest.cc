#include "run/manifest.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <tuple>

#include "base/atomic_file.h"
#include "base/confined_file.h"
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
          [](const RunParameters& p) {  // given unless the default (the table's first row) alone
            return p.formats != std::vector<std::string>{std::string(VideoFormats().front().name)};
          },
          false),
      FETCHSCOPE_PARAMETER("--gif-fps", gif_fps, HasGif, false),
      FETCHSCOPE_PARAMETER("--gif-width", gif_width, HasGif, false),
      FETCHSCOPE_PARAMETER(
          "--layers", layers, [](const RunParameters& p) { return p.layers != "rgb"; }, false),
      FETCHSCOPE_PARAMETER(
          "--signals", signals, [](const RunParameters& p) { return p.signals != "none"; }, false),
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

// The manifest's bytes: a regular file of at most kMaxJsonFileBytes (UsageError otherwise).
std::string ReadText(const std::filesystem::path& path) {
  try {
    return ReadFileCapped(path, kMaxJsonFileBytes);
  } catch (const RunError& e) {
    throw ManifestError(e.what());  // "cannot read 'PATH': REASON"
  }
}

json OptionalString(const std::optional<std::string>& s) { return s ? json(*s) : json(nullptr); }

std::optional<std::string> ReadOptionalString(const json& j, const char* key) {
  if (!j.contains(key) || j.at(key).is_null()) return std::nullopt;
  return j.at(key).get<std::string>();
}

// ---- the manifest's reader, by groups of members

// Every member the reader knows (the rest stay in Manifest::extra).
constexpr const char* kManifestKeys[] = {"schema_version",
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
                                         "shards"};

// "schema_version": 0 when absent (written before versions existed: the same layout); a newer
// version than this build reads is refused.
int ReadSchemaVersion(const json& j) {
  const auto version = j.is_object() ? j.find("schema_version") : j.end();
  if (!j.is_object() || version == j.end()) return 0;
  if (!version->is_number_integer() || version->get<int>() < 0) {
    throw ManifestError("has a bad schema_version " + version->dump());
  }
  const int read = version->get<int>();
  if (read > kManifestSchemaVersion) {
    throw ManifestError("has manifest schema version " + std::to_string(read) +
                        "; this fetchscope reads versions 0 to " +
                        std::to_string(kManifestSchemaVersion) + ": use a newer fetchscope");
  }
  return read;
}

// What was run: the environment, the episodes, the outcome, the command and its parameters.
void ReadRunMembers(const json& j, Manifest* m) {
  m->env_id = j.at("env_id").get<std::string>();
  m->seed = j.value("seed", uint64_t{0});
  m->policy = j.value("policy", std::string());
  m->from = ReadOptionalString(j, "from");
  m->episodes_requested = j.value("episodes_requested", static_cast<int>(j.at("episodes").size()));
  m->steps_per_episode = j.value("steps_per_episode", 0);
  m->sheet_every = j.value("sheet_every", 0);
  for (const json& e : j.at("episodes")) m->episodes.push_back(ManifestEpisodeFromJson(e));
  m->frames = j.value("frames", 0L);
  m->interrupted = j.value("interrupted", false);
  m->incomplete_episodes = j.value("incomplete_episodes", std::vector<int>());
  m->signal = ReadOptionalString(j, "signal");
  m->command_line = j.value("command_line", std::string());
  if (j.contains("parameters")) {
    m->parameters = ParametersFromJson(j.at("parameters"));
  } else {  // from before "parameters": what the manifest's own members say
    m->parameters.recorded = false;
    m->parameters.env_id = m->env_id;
    m->parameters.seed = m->seed;
    m->parameters.steps = m->steps_per_episode;
  }
  m->resumed = j.value("resumed", false);
  m->merged = j.value("merged", false);
  m->shards = j.value("shards", json::array());
}

// What one record process did: missing episodes, failures, its shard, its workers and GPU.
void ReadProcessMembers(const json& j, Manifest* m) {
  m->missing = j.value("missing", std::vector<int>());
  for (const json& f : j.value("failures", json::array())) {
    m->failures.push_back({f.value("worker", 0), f.value("episodes", std::vector<int>()),
                           f.value("message", std::string())});
  }
  if (j.contains("shard") && j.at("shard").is_object()) {
    const json& s = j.at("shard");
    ManifestShard shard;
    shard.index = s.value("index", 0);
    shard.count = s.value("count", 1);
    shard.source = ReadOptionalString(s, "source");
    if (s.contains("episodes")) shard.episodes = s.at("episodes").get<std::vector<int>>();
    m->shard = std::move(shard);
  }
  m->jobs = j.value("jobs", 1);
  m->worker_mode = j.value("worker_mode", std::string());
  if (j.contains("workers")) m->workers = ManifestWorkersFromJson(j.at("workers"));
  if (j.contains("gpu")) m->gpu = ManifestGpuFromJson(j.at("gpu"));
}

// How the files were made: assets, model, view, GL backend, encoding, versions, timings.
void ReadSetupMembers(const json& j, Manifest* m) {
  m->assets = j.value("assets", json::object());
  m->model_file = j.value("model_file", std::string());
  m->camera = j.value("camera", std::string());
  m->cameras = j.value("cameras", std::vector<std::string>());
  m->obs = j.value("obs", json());
  m->overlay = j.value("overlay", std::string());
  m->msaa = j.value("msaa", 0);
  m->msaa_reason = j.value("msaa_reason", std::string());
  if (j.contains("backend")) m->backend = ManifestBackendFromJson(j.at("backend"));
  m->layers = j.value("layers", std::vector<std::string>());
  if (j.contains("video")) m->video = ManifestVideoFromJson(j.at("video"));
  m->versions = j.value("versions", json::object());
  if (j.contains("timings_s")) m->timings_s = ManifestTimingsFromJson(j.at("timings_s"));
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
    out["workers"] = ManifestWorkersToJson(m.workers);
    out["gpu"] = ManifestGpuToJson(m.gpu);
  }
  out["assets"] = m.assets;
  out["model_file"] = m.model_file;
  out["camera"] = m.camera;
  if (!m.cameras.empty()) out["cameras"] = m.cameras;
  if (!m.obs.is_null()) out["obs"] = m.obs;
  out["overlay"] = m.overlay;
  out["msaa"] = m.msaa;
  out["msaa_reason"] = m.msaa_reason;
  out["backend"] = ManifestBackendToJson(m.backend);
  out["layers"] = m.layers;
  out["video"] = ManifestVideoToJson(m.video);
  out["versions"] = m.versions;
  out["timings_s"] = ManifestTimingsToJson(m.timings_s);
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
  m.schema_version = ReadSchemaVersion(j);
  if (!j.is_object() || !j.contains("env_id") || !j.contains("episodes") ||
      !j.at("episodes").is_array()) {
    throw ManifestError("is not a record manifest (it lacks env_id or episodes)");
  }
  try {
    m.extra = j;
    ReadRunMembers(j, &m);
    ReadProcessMembers(j, &m);
    ReadSetupMembers(j, &m);
  } catch (const json::exception& e) {
    throw ManifestError(std::string("is not a record manifest: ") + e.what());
  } catch (const std::invalid_argument&) {  // --shard's std::stoi
    throw ManifestError("has a parameter --shard that is not I/N");
  } catch (const std::out_of_range&) {
    throw ManifestError("has a parameter --shard that is not I/N");
  }
  for (const char* key : kManifestKeys) m.extra.erase(key);
  return m;
}

Manifest ReadManifest(const std::filesystem::path& path) {
  json j;
  const std::string text = ReadText(path);
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    throw ManifestError("'" + path.string() +
                        "' is not JSON: " + DescribeJsonError(e, text.size()));
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
