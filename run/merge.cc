#include "run/merge.h"

#include <algorithm>
#include <map>
#include <optional>

#include "base/errors.h"
#include "base/folder_lock.h"
#include "run/manifest.h"
#include "run/run_files.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct ShardManifest {
  fs::path path;  // the manifest file
  Manifest data;
  int index = 0;
  int count = 1;
};

std::string Label(int index, int count) {
  return std::to_string(index) + "/" + std::to_string(count);
}

// The record manifests in `dir`, sorted by name; a manifest.json written by an earlier merge is not
// an input.
std::vector<ShardManifest> ReadManifests(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw RunError("'" + dir.string() + "' is not a folder");
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (entry.is_regular_file() && IsManifestFileName(entry.path().filename().string())) {
      files.push_back(entry.path());
    }
  }
  if (ec) throw RunError("cannot list '" + dir.string() + "': " + ec.message());
  std::sort(files.begin(), files.end());
  std::vector<ShardManifest> manifests;
  for (const fs::path& file : files) {
    ShardManifest m;
    m.path = file;
    m.data = ReadManifest(file);
    if (m.data.merged) continue;
    // manifests from before sharding: the whole run
    const ManifestShard shard = m.data.shard.value_or(ManifestShard{});
    m.index = shard.index;
    m.count = shard.count;
    if (m.count < 1 || m.index < 0 || m.index >= m.count) {
      throw RunError("'" + file.string() + "' has a bad shard " + Label(m.index, m.count));
    }
    manifests.push_back(std::move(m));
  }
  return manifests;
}

// Every manifest a shard of the run of the first, by the one definition of the same run.
void CheckOneRun(const std::vector<ShardManifest>& manifests) {
  const ShardManifest& first = manifests.front();
  for (const ShardManifest& m : manifests) {
    if (!m.data.parameters.recorded) {
      throw RunError("'" + m.path.string() +
                     "' does not record the run's parameters (written by an "
                     "older fetchscope), so "
                     "it cannot be told to be a shard of the same run: record "
                     "that shard again");
    }
    const std::optional<RunDifference> d =
        SameRun(m.data.parameters, first.data.parameters, SameRunScope::kShards);
    if (d) {
      throw RunError("'" + m.path.string() + "' (shard " + Label(m.index, m.count) +
                     ") belongs to another run: " + d->parameter + " is " + d->a + " there but " +
                     d->b + " in '" + first.path.string() + "' (shard " +
                     Label(first.index, first.count) +
                     "); record every shard of a run with the same options");
    }
  }
}

// "2, 5, 8" (at most 10, then the count).
std::string EpisodeList(const std::vector<int>& episodes) {
  std::string s;
  for (size_t i = 0; i < episodes.size() && i < 10; ++i)
    s += (i ? ", " : "") + std::to_string(episodes[i]);
  if (episodes.size() > 10) s += ", ... (" + std::to_string(episodes.size()) + " in all)";
  return s;
}

// A path for the merged manifest: relative to the folder it is written in.
std::string RelativeTo(const fs::path& file, const fs::path& folder) {
  return fs::absolute(file)
      .lexically_normal()
      .lexically_relative(fs::absolute(folder).lexically_normal())
      .string();
}

// The files an episode needs to count as recorded: its video in every format, sheet and trajectory;
// each one missing is a problem.
bool HasFiles(const ManifestEpisode& e, const fs::path& folder,
              std::vector<std::string>* problems) {
  std::vector<std::pair<std::string, std::string>> needed;  // what, file
  for (const EpisodeVideo& v : EpisodeVideos(e)) needed.emplace_back("video", v.file);
  if (needed.empty()) needed.emplace_back("video", "");
  if (!e.sheet.empty()) needed.emplace_back("sheet", e.sheet);  // none with --no-sheets
  needed.emplace_back("trajectory", e.trajectory);
  bool files = true;
  for (const auto& [what, name] : needed) {
    const fs::path file = folder / name;
    if (name.empty() || !fs::is_regular_file(file)) {
      problems->push_back("episode " + std::to_string(e.index) + ": " + what + " '" +
                          file.string() + "' is missing");
      files = false;
    }
  }
  return files;
}

// The merged manifest: the run's settings from the first shard, every episode in order (file names
// relative to `out_dir`), and each shard's record.
Manifest Merged(const Manifest& first, const std::map<int, const ShardManifest*>& by_shard,
                const std::vector<std::pair<const ShardManifest*, const ManifestEpisode*>>& at,
                const fs::path& out_dir, const MergeRequest& request) {
  Manifest merged = first;
  merged.merged = true;  // the per-process members give way to "shards"
  merged.shard.reset();
  merged.episodes.clear();
  for (const auto& [m, e] : at) {
    ManifestEpisode episode = *e;
    for (std::string* name : episode.Files())
      *name = RelativeTo(m->path.parent_path() / *name, out_dir);
    merged.episodes.push_back(std::move(episode));
  }
  json shards = json::array();
  double wall_max = 0, wall = 0, sim = 0, render = 0, encode = 0, write = 0;
  long frames = 0;
  for (const auto& [index, m] : by_shard) {
    const Manifest& d = m->data;
    const ManifestTimings& t = d.timings_s;
    wall += t.wall.value_or(0.0);
    sim += t.sim.value_or(0.0);
    render += t.render.value_or(0.0);
    encode += t.encode.value_or(0.0);
    write += t.write.value_or(0.0);
    wall_max = std::max(wall_max, t.wall.value_or(0.0));
    frames += d.frames;
    const ManifestShard shard = d.shard.value_or(ManifestShard{});
    shards.push_back({{"index", index},
                      {"count", m->count},
                      {"source", shard.source ? json(*shard.source) : json(nullptr)},
                      {"manifest", RelativeTo(m->path, out_dir)},
                      {"episodes", d.episodes.size()},
                      {"jobs", d.jobs},
                      {"workers", ManifestWorkersToJson(d.workers)},
                      {"backend", ManifestBackendToJson(d.backend)},
                      {"timings_s", ManifestTimingsToJson(t)},
                      {"frames", d.frames},
                      {"command_line", d.command_line},
                      {"versions", d.versions}});
  }
  merged.shards = std::move(shards);
  merged.frames = frames;
  // wall: the slowest shard (they run side by side); the others: summed over shards
  merged.timings_s = ManifestTimings{};
  merged.timings_s.wall = wall_max;
  merged.timings_s.wall_sum = wall;
  merged.timings_s.sim = sim;
  merged.timings_s.render = render;
  merged.timings_s.encode = encode;
  merged.timings_s.write = write;
  merged.interrupted = false;
  merged.signal.reset();
  merged.command_line = request.command_line;
  merged.versions = request.versions;
  return merged;
}

// Where each episode is: its shard's manifest and entry, or nulls where it is missing or
// incomplete (a missing file goes into `problems`). Throws on a shard or episode listed twice
// and on an episode of another shard.
std::vector<std::pair<const ShardManifest*, const ManifestEpisode*>> EpisodesOfShards(
    const std::vector<ShardManifest>& manifests, std::map<int, const ShardManifest*>* by_shard,
    std::vector<std::string>* problems) {
  const ShardManifest& first = manifests.front();
  const int count = first.count;
  const int episodes = first.data.episodes_requested;
  const int steps = first.data.steps_per_episode;
  std::vector<std::pair<const ShardManifest*, const ManifestEpisode*>> episode_at(
      episodes, {nullptr, nullptr});
  for (const ShardManifest& m : manifests) {
    auto [it, fresh] = by_shard->emplace(m.index, &m);
    if (!fresh) {
      throw RunError("shard " + Label(m.index, count) + " appears twice: '" +
                     it->second->path.string() + "' and '" + m.path.string() + "'");
    }
    for (const ManifestEpisode& e : m.data.episodes) {
      const int k = e.index;
      if (k < 0 || k >= episodes || k % count != m.index) {
        throw RunError("'" + m.path.string() + "' lists episode " + std::to_string(k) +
                       ", which is not part of shard " + Label(m.index, count) + " of " +
                       std::to_string(episodes));
      }
      if (episode_at[k].first) {
        throw RunError("episode " + std::to_string(k) + " appears twice: in '" +
                       episode_at[k].first->path.string() + "' and '" + m.path.string() + "'");
      }
      // cut short by a signal: counted as missing
      if (!e.IsComplete(steps)) continue;
      if (HasFiles(e, m.path.parent_path(), problems)) episode_at[k] = {&m, &e};
    }
  }
  return episode_at;
}

// Throws naming every shard that lacks episodes (and how to record them again), and the
// `problems` found before.
void CheckComplete(const std::vector<std::pair<const ShardManifest*, const ManifestEpisode*>>& at,
                   const std::map<int, const ShardManifest*>& by_shard, int count,
                   std::vector<std::string> problems) {
  const int episodes = static_cast<int>(at.size());
  std::vector<int> redo;  // the shards to record again
  for (int s = 0; s < count; ++s) {
    std::vector<int> missing;
    for (int k = s; k < episodes; k += count) {
      if (!at[k].first) missing.push_back(k);
    }
    if (missing.empty()) continue;
    redo.push_back(s);
    const std::string label = Label(s, count);
    auto it = by_shard.find(s);
    if (it == by_shard.end()) {
      problems.push_back("shard " + label + " has no manifest (episodes " + EpisodeList(missing) +
                         ")");
    } else if (it->second->data.interrupted) {
      const std::optional<std::string>& sig = it->second->data.signal;
      problems.push_back("shard " + label + " was interrupted" + (sig ? " by " + *sig : "") +
                         " (episodes " + EpisodeList(missing) + " missing or incomplete)");
    } else {
      problems.push_back("shard " + label + " lacks episodes " + EpisodeList(missing));
    }
  }
  if (problems.empty()) return;
  std::string message = "the run is incomplete: ";
  for (size_t i = 0; i < problems.size(); ++i) message += (i ? "; " : "") + problems[i];
  if (!redo.empty() && count > 1) {
    std::string indices;
    for (int s : redo) indices += (indices.empty() ? "" : ",") + std::to_string(s);
    message += ". To record them, run their shards again with the run's options and --resume (" +
               std::string(redo.size() == 1 ? "--shard " + Label(redo.front(), count)
                                            : "--shard I/" + std::to_string(count)) +
               "; a Slurm array: requeue those tasks, or resubmit --array=" + indices + ")";
  }
  throw RunError(message);
}

}  // namespace

MergeResult MergeShardManifests(const MergeRequest& request) {
  MergeResult result;
  result.manifest = request.out.empty() ? fs::path(request.dirs.front()) / kManifestFileName
                                        : fs::path(request.out);
  const fs::path out_dir =
      result.manifest.parent_path().empty() ? fs::path(".") : result.manifest.parent_path();
  // shards still recording hold the folder (shared): the merge waits for none of them, it refuses
  std::error_code ec;
  FolderLock lock;
  if (fs::is_directory(out_dir, ec)) {
    lock =
        FolderLock(out_dir, FolderLock::Kind::kExclusive, "merge-manifests: the folder of --out");
  }
  std::vector<ShardManifest> manifests;
  for (const std::string& dir : request.dirs) {
    for (ShardManifest& m : ReadManifests(dir)) manifests.push_back(std::move(m));
  }
  if (manifests.empty()) {
    throw RunError("no record manifests (manifest.json or manifest_shard_*.json) in " +
                   request.dirs.front() +
                   (request.dirs.size() > 1 ? " and the other folders given" : ""));
  }
  CheckOneRun(manifests);
  const ShardManifest& first = manifests.front();
  const int count = first.count;
  const int episodes = first.data.episodes_requested;

  // every episode once, complete, with its files
  std::map<int, const ShardManifest*> by_shard;
  std::vector<std::string> problems;
  const std::vector<std::pair<const ShardManifest*, const ManifestEpisode*>> episode_at =
      EpisodesOfShards(manifests, &by_shard, &problems);
  CheckComplete(episode_at, by_shard, count, problems);

  const Manifest merged = Merged(first.data, by_shard, episode_at, out_dir, request);
  WriteManifest(result.manifest, merged);
  result.shards = static_cast<int>(by_shard.size());
  result.shard_count = count;
  result.episodes = episodes;
  for (const ManifestEpisode& e : merged.episodes) result.successes += e.is_success;
  return result;
}

}  // namespace fetchscope
