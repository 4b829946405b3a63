#include "dataset/minari_source.h"

#include <algorithm>
#include <regex>

#include "base/errors.h"
#include "dataset/minari_reader.h"
#include "dataset/minari_trajectory.h"
#include "src/observation_layout.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;

// "all 3", "none" or "2 of 3": which episodes carry a seed attribute
std::string SeedsFound(const std::vector<MinariEpisode>& episodes) {
  const size_t seeded = std::count_if(episodes.begin(), episodes.end(),
                                      [](const MinariEpisode& e) { return e.seed.has_value(); });
  if (seeded == 0) return "none (each reset rebuilt from its first observation)";
  if (seeded == episodes.size()) return "all";
  return std::to_string(seeded) + " of " + std::to_string(episodes.size());
}

}  // namespace

bool IsTrajectoryPath(const std::string& path) {
  std::error_code ec;
  // any file but a folder (a FIFO, a device too: LoadTrajectorySource refuses those by name)
  if (fs::exists(path, ec) && !fs::is_directory(path, ec)) {
    return fs::path(path).extension() != ".hdf5";
  }
  if (!fs::is_directory(path, ec)) return false;
  const std::regex name("episode_[0-9]+\\.json");
  for (const auto& entry : fs::directory_iterator(path, ec)) {
    if (std::regex_match(entry.path().filename().string(), name)) return true;
  }
  // a folder with no dataset in it either: LoadTrajectorySource says what --from accepts
  const fs::path dir(path);
  return !fs::exists(dir / "data", ec) && !fs::exists(dir / "main_data.hdf5", ec) &&
         !fs::exists(dir / "metadata.json", ec);
}

MinariSource LoadMinariSource(const MinariSourceRequest& r) {
  MinariDataset d = ReadMinariDataset(r.what, r.root);
  const std::string file = d.location.hdf5.string();
  const MinariMetadata& m = d.metadata;
  std::string env_id = r.env_id;
  if (m.env_id) {
    if (!r.env_id.empty() && r.env_id != *m.env_id) {
      throw UsageError("--env-id " + r.env_id + " conflicts with the dataset's env_spec id " +
                       *m.env_id + " (" + d.location.metadata.string() +
                       "): drop --env-id, or name " + *m.env_id);
    }
    env_id = *m.env_id;
  } else if (env_id.empty()) {
    throw UsageError(d.location.metadata.string() +
                     ": the dataset has no env_spec; name its env with --env-id (e.g. "
                     "FetchPush-v4)");
  }
  const EnvSpec& spec = FindEnvSpec(env_id);
  if (ObservationSize(spec.has_object) != m.obs_dim) {
    throw UsageError("--env-id " + env_id + " has " +
                     std::to_string(ObservationSize(spec.has_object)) +
                     " observation values, the dataset " + file + " " + std::to_string(m.obs_dim));
  }
  std::sort(d.episodes.begin(), d.episodes.end(),
            [](const MinariEpisode& a, const MinariEpisode& b) { return a.id < b.id; });
  if (r.episodes > static_cast<int>(d.episodes.size())) {
    throw UsageError("--episodes " + std::to_string(r.episodes) + ": the dataset " + file +
                     " holds " + std::to_string(d.episodes.size()) + " episode(s)");
  }
  if (r.episodes > 0) d.episodes.resize(r.episodes);
  if (d.episodes.empty()) throw RunError(file + ": holds no episodes");

  MinariSource out;
  TrajectorySource& s = out.source;
  s.path = r.what;
  s.env_id = env_id;
  s.seed = d.episodes.front().seed.value_or(0);
  s.policy = m.algorithm_name.empty() ? "minari" : m.algorithm_name;
  s.dataset = true;
  s.tolerance = r.tolerance;
  int64_t steps = 0;
  for (const MinariEpisode& e : d.episodes) {
    TrajectoryEpisode episode = FromMinariEpisode(e, spec, file);
    s.starts[episode.index] = MinariEpisodeStart(e, spec);
    s.max_steps = std::max(s.max_steps, e.steps());
    steps += e.steps();
    s.episodes.emplace(episode.index, std::move(episode));
  }
  out.found = "Minari dataset " + (m.dataset_id.empty() ? r.what : m.dataset_id) + " (" + file +
              "): env " + env_id + (m.env_id ? " (env_spec)" : " (--env-id)") + ", " +
              std::to_string(d.episodes.size()) + " of " + std::to_string(m.total_episodes) +
              " episode(s), " + std::to_string(steps) + " steps, seeds " + SeedsFound(d.episodes) +
              ", minari_version " + m.minari_version;
  s.found = out.found;
  out.env_from_spec = m.env_id.has_value();
  out.genuine_env = m.entry_point.rfind("gymnasium_robotics.", 0) == 0 &&
                    m.code_permalink.rfind("fetchscope ", 0) != 0;
  return out;
}

}  // namespace fetchscope
