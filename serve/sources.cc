#include "serve/sources.h"

#include <algorithm>
#include <cmath>
#include <system_error>

#include "base/confined_file.h"
#include "base/errors.h"
#include "inspect/report.h"
#include "run/run_files.h"
#include "src/fetch_env.h"
#include "src/observation_layout.h"
#include "src/trajectory.h"

namespace fetchscope::serve {
namespace {

namespace fs = std::filesystem;

// The assets a recording names (its manifest's or file's "assets"), resolved on this machine.
AssetSource RecordedAssets(const std::string& kind, const std::string& path) {
  return ResolveAssets(kind.empty() || kind == "bundled" || path.empty() ? "bundled" : path);
}

std::string Plural(size_t n, const char* what) {
  return std::to_string(n) + " " + what + (n == 1 ? "" : "s");
}

Source OpenRunFolder(const std::string& given) {
  const RecordedRun run = ReadRunFolder(given);
  const Manifest& m = run.manifest;
  Source s;
  s.kind = SourceKind::kRecording;
  s.given = given;
  s.spec = &FindEnvSpec(m.env_id);
  s.assets = RecordedAssets(m.assets.value("kind", ""), m.assets.value("path", ""));
  s.seed = m.seed;
  s.policy = m.policy;
  for (const auto& [k, entry] : run.recorded) {
    if (entry.trajectory.empty()) continue;  // nothing to replay
    ListedEpisode e;
    e.index = k;
    e.steps = entry.steps.value_or(entry.frames.value_or(1) - 1);
    e.complete = entry.IsComplete(m.steps_per_episode);
    e.success = entry.is_success;
    e.episode_return = entry.episode_return;
    s.episodes.push_back(e);
    s.files[k] = (run.dir / entry.trajectory).string();
  }
  if (s.episodes.empty()) throw RunError("serve: " + given + " holds no recorded episode");
  s.title = "run " + given + ": " + m.env_id + ", seed " + std::to_string(m.seed) + ", " +
            m.policy + ", " + Plural(s.episodes.size(), "episode");
  return s;
}

// Listed episodes of rows held in memory.
void ListRows(Source* s) {
  for (const auto& [k, episode] : s->rows->episodes) {
    ListedEpisode e;
    e.index = k;
    e.steps = static_cast<int>(episode.steps.size()) - 1;
    e.complete = episode.complete;
    if (!episode.steps.empty()) e.success = episode.steps.back().is_success;
    e.episode_return = episode.episode_return;
    s->episodes.push_back(e);
  }
}

Source OpenTrajectoryFile(const std::string& given) {
  Source s;
  s.kind = SourceKind::kRecording;
  s.given = given;
  s.rows = std::make_shared<TrajectorySource>(LoadTrajectorySource(given));
  s.spec = &FindEnvSpec(s.rows->env_id);
  s.assets = ResolveAssets(SourceAssets(*s.rows));
  s.seed = s.rows->seed;
  s.policy = s.rows->policy;
  ListRows(&s);
  s.title = "trajectory " + given + ": " + s.rows->env_id + ", seed " + std::to_string(s.seed) +
            ", " + s.policy + ", " + Plural(s.episodes.size(), "episode");
  return s;
}

Source OpenDataset(const std::string& given, const fs::path& root) {
  MinariSourceRequest request;
  request.what = given;
  request.root = root;
  MinariSource found;
  try {
    found = LoadMinariSource(request);
  } catch (const UsageError& e) {
    const std::string what = e.what();
    if (what.rfind("no Minari dataset", 0) != 0) throw;
    throw UsageError("serve: '" + given +
                     "' is none of what serve accepts: a run folder of record, a trajectory JSON "
                     "file, or a Minari dataset (" +
                     what + ")");
  }
  Source s;
  s.kind = SourceKind::kDataset;
  s.given = given;
  s.rows = std::make_shared<TrajectorySource>(std::move(found.source));
  s.spec = &FindEnvSpec(s.rows->env_id);
  // a dataset the genuine env made: its assets, where a gymnasium_robotics is installed
  const AssetSource automatic = found.genuine_env ? ResolveAssets("auto") : AssetSource{};
  s.assets = automatic.kind == "dir" ? automatic : ResolveAssets(SourceAssets(*s.rows));
  s.policy = s.rows->policy;
  ListRows(&s);
  s.title = "dataset " + found.found;
  return s;
}

}  // namespace

Source OpenSource(const std::string& given, const fs::path& minari_root) {
  std::error_code ec;
  if (fs::is_directory(given, ec) && fs::exists(fs::path(given) / "manifest.json", ec)) {
    return OpenRunFolder(given);
  }
  if (fs::is_regular_file(given, ec) && IsTrajectoryPath(given)) return OpenTrajectoryFile(given);
  return OpenDataset(given, minari_root);
}

Source LiveSource(const EnvSpec& spec, const AssetSource& assets, uint64_t seed) {
  Source s;
  s.kind = SourceKind::kLive;
  s.given = spec.id;
  s.spec = &spec;
  s.assets = assets;
  s.seed = seed;
  s.title = "live " + spec.id + ", seed " + std::to_string(seed);
  return s;
}

TrajectoryEpisode EpisodeRows(const Source& source, int index) {
  if (source.rows) {
    const auto it = source.rows->episodes.find(index);
    if (it == source.rows->episodes.end()) {
      throw RunError(source.given + " has no episode " + std::to_string(index));
    }
    return it->second;
  }
  const auto file = source.files.find(index);
  if (file == source.files.end()) {
    throw RunError(source.given + " has no episode " + std::to_string(index));
  }
  {  // checked again now: the folder may have changed since serve opened it
    const fs::path dir = (fs::path(source.given) / kManifestFileName).parent_path();
    const std::string prefix = (dir / "").string();
    std::string entry = file->second;
    if (entry.rfind(prefix, 0) == 0) entry.erase(0, prefix.size());
    if (!LiesInside(dir, file->second)) {  // a merged run's shard folder, or refused
      RunFile(ReadRunFolder(source.given), entry,
              std::string(kManifestFileName) + " names episode " + std::to_string(index) +
                  "'s trajectory");
    }
  }
  Trajectory t = ReadTrajectory(file->second);  // a regular file of at most kMaxJsonFileBytes
  if (t.episodes.size() != 1 || t.episodes[0].index != index) {
    throw RunError(file->second + ": holds no single episode " + std::to_string(index));
  }
  TrajectoryEpisode e = std::move(t.episodes[0]);
  e.file = file->second;
  return e;
}

nlohmann::json EpisodeColumns(const EnvSpec& spec, const std::vector<TrajectoryStep>& steps) {
  nlohmann::json c = {
      {"final_distance", nullptr}, {"first_success", nullptr}, {"object_displacement", nullptr}};
  if (steps.empty()) return c;
  const Observation& last = steps.back().obs;
  c["final_distance"] = GoalDistance(last.achieved_goal, last.desired_goal);
  for (const TrajectoryStep& s : steps) {
    if (s.t >= 1 && s.is_success) {
      c["first_success"] = s.t;
      break;
    }
  }
  const std::optional<ObservationSlice> object =
      FindObservationSlice(spec.has_object, "object_pos");
  const std::vector<double>& first = steps.front().obs.observation;
  if (object && first.size() >= static_cast<size_t>(object->end) &&
      last.observation.size() >= static_cast<size_t>(object->end)) {
    double d2 = 0;
    for (int i = object->first; i < object->end; ++i) {
      d2 += (last.observation[i] - first[i]) * (last.observation[i] - first[i]);
    }
    c["object_displacement"] = std::sqrt(d2);
  }
  if (std::any_of(steps.begin(), steps.end(), [](const TrajectoryStep& s) { return s.contacts; })) {
    c["grasped_at"] = nullptr;
    c["dropped_at"] = nullptr;
    bool held = false;
    for (const TrajectoryStep& s : steps) {
      if (!s.contacts) continue;
      if (s.contacts->grasped()) {
        if (c["grasped_at"].is_null()) c["grasped_at"] = s.t;
        held = true;
      } else if (held && !s.contacts->object_on_table && c["dropped_at"].is_null()) {
        // neither finger pair holds it nor does the table: it is falling
        const bool touched =
            s.contacts->left_finger_force > 0 || s.contacts->right_finger_force > 0;
        if (!touched) c["dropped_at"] = s.t;
        held = touched;
      }
    }
  }
  return c;
}

const ListedEpisode* FindEpisode(const Source& source, int index) {
  for (const ListedEpisode& e : source.episodes) {
    if (e.index == index) return &e;
  }
  return nullptr;
}

nlohmann::json SourcesJson(const std::vector<Source>& sources) {
  nlohmann::json list = nlohmann::json::array();
  for (size_t i = 0; i < sources.size(); ++i) {
    const Source& s = sources[i];
    nlohmann::json episodes = nlohmann::json::array();
    for (const ListedEpisode& e : s.episodes) {
      episodes.push_back(
          {{"index", e.index},
           {"steps", e.steps},
           {"complete", e.complete},
           {"success", e.success ? nlohmann::json(*e.success) : nullptr},
           {"return", e.episode_return ? nlohmann::json(*e.episode_return) : nullptr}});
    }
    static const char* kKinds[] = {"recording", "dataset", "live"};
    // the observation's index names and units, as describe prints them (the step inspector's)
    nlohmann::json labels = nlohmann::json::array();
    for (const LayoutLabel& l : ObservationLabels(s.spec->has_object)) {
      labels.push_back({{"name", l.name}, {"unit", l.unit}, {"meaning", l.meaning}});
    }
    list.push_back({{"source", i},
                    {"kind", kKinds[static_cast<int>(s.kind)]},
                    {"title", s.title},
                    {"env_id", s.spec->id},
                    {"seed", s.seed},
                    {"policy", s.policy},
                    {"has_object", s.spec->has_object},
                    {"threshold", s.spec->distance_threshold},
                    {"max_episode_steps", s.spec->max_episode_steps},
                    {"block_gripper", s.spec->block_gripper},
                    {"observation_labels", labels},
                    {"episodes", std::move(episodes)}});
  }
  return list;
}

}  // namespace fetchscope::serve
