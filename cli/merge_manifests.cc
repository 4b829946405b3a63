// fetchscope merge-manifests DIR...: the shard manifests of one sharded record run
// (manifest_shard_IIII_of_NNNN.json, or an unsplit run's manifest.json) -> one manifest.json
// listing every episode in order, after checking that the shards belong to the same run, that
// every episode is there exactly once, complete, with its files.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "base/errors.h"
#include "base/json_util.h"
#include "cli/command.h"
#include "cli/common.h"
#include "inspect/report.h"
#include "run/shard.h"

namespace fetchscope::cli {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// The settings that make two manifests parts of one run (JSON pointers into a manifest).
constexpr const char* kRunIdentity[] = {
    "/env_id",       "/seed",      "/policy",      "/episodes_requested", "/steps_per_episode",
    "/sheet_every",  "/camera",    "/overlay",     "/assets/sha256",      "/video/crf",
    "/video/preset", "/video/fps", "/video/width", "/video/height",       "/shard/count",
    "/video/formats"};

struct ShardManifest {
  fs::path path;  // the manifest file
  json data;
  int index = 0;
  int count = 1;
};

std::string ReadText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw RunError("cannot read '" + path.string() + "'");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

bool IsManifestName(const std::string& name) {
  if (name == "manifest.json") return true;
  return name.rfind("manifest_shard_", 0) == 0 && name.size() > 5 &&
         name.compare(name.size() - 5, 5, ".json") == 0;
}

// The record manifests in `dir`, sorted by name; a manifest.json written by an earlier merge is
// not an input.
std::vector<ShardManifest> ReadManifests(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw RunError("'" + dir.string() + "' is not a folder");
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (entry.is_regular_file() && IsManifestName(entry.path().filename().string())) {
      files.push_back(entry.path());
    }
  }
  if (ec) throw RunError("cannot list '" + dir.string() + "': " + ec.message());
  std::sort(files.begin(), files.end());
  std::vector<ShardManifest> manifests;
  for (const fs::path& file : files) {
    ShardManifest m;
    m.path = file;
    try {
      m.data = json::parse(ReadText(file));
    } catch (const json::exception& e) {
      throw RunError("'" + file.string() + "' is not valid JSON: " + e.what());
    }
    if (!m.data.is_object() || !m.data.contains("episodes") || !m.data.contains("env_id")) {
      throw RunError("'" + file.string() + "' is not a record manifest (no env_id/episodes)");
    }
    if (m.data.value("merged", false)) continue;
    // manifests from before sharding: the whole run
    if (!m.data.contains("shard")) m.data["shard"] = {{"index", 0}, {"count", 1}};
    m.index = m.data["shard"].value("index", 0);
    m.count = m.data["shard"].value("count", 1);
    if (m.count < 1 || m.index < 0 || m.index >= m.count) {
      throw RunError("'" + file.string() + "' has a bad shard " + m.data["shard"].dump());
    }
    manifests.push_back(std::move(m));
  }
  return manifests;
}

std::string Value(const json& j, const char* pointer) {
  const json::json_pointer p(pointer);
  return j.contains(p) ? j.at(p).dump() : "(absent)";
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

// The file names in a shard's episode entry (video, the videos of the other formats, sheet,
// trajectory, per-layer files...) made relative to the merged manifest's folder: every string
// with an extension that names a file in the shard's folder.
void RebaseFiles(json* j, const fs::path& folder, const fs::path& out_dir) {
  if (j->is_string()) {
    const fs::path name = j->get<std::string>();
    std::error_code ec;
    if (name.has_extension() && fs::is_regular_file(folder / name, ec)) {
      *j = RelativeTo(folder / name, out_dir);
    }
  } else if (j->is_structured()) {
    for (json& child : *j) RebaseFiles(&child, folder, out_dir);
  }
}

int Merge(const std::vector<std::string>& dirs, std::string out, bool quiet, bool report) {
  std::vector<ShardManifest> manifests;
  for (const std::string& dir : dirs) {
    for (ShardManifest& m : ReadManifests(dir)) manifests.push_back(std::move(m));
  }
  if (manifests.empty()) {
    throw RunError("no record manifests (manifest.json or manifest_shard_*.json) in " +
                   dirs.front() + (dirs.size() > 1 ? " and the other folders given" : ""));
  }
  const ShardManifest& first = manifests.front();
  for (const ShardManifest& m : manifests) {
    for (const char* key : kRunIdentity) {
      if (Value(m.data, key) != Value(first.data, key)) {
        throw RunError("'" + m.path.string() + "' belongs to another run: " + (key + 1) + " is " +
                       Value(m.data, key) + " there but " + Value(first.data, key) + " in '" +
                       first.path.string() + "'");
      }
    }
  }
  const int count = first.count;
  const int episodes = first.data.value("episodes_requested", 0);
  const int steps = first.data.value("steps_per_episode", 0);

  // every episode once, complete, with its files
  std::map<int, const ShardManifest*> by_shard;
  std::vector<std::string> problems;
  std::vector<std::pair<const ShardManifest*, const json*>> episode_at(episodes,
                                                                       {nullptr, nullptr});
  for (const ShardManifest& m : manifests) {
    auto [it, fresh] = by_shard.emplace(m.index, &m);
    if (!fresh) {
      throw RunError("shard " + std::to_string(m.index) + "/" + std::to_string(count) +
                     " appears twice: '" + it->second->path.string() + "' and '" + m.path.string() +
                     "'");
    }
    for (const json& e : m.data["episodes"]) {
      const int k = e.value("index", -1);
      if (k < 0 || k >= episodes || k % count != m.index) {
        throw RunError("'" + m.path.string() + "' lists episode " + std::to_string(k) +
                       ", which is not part of shard " + std::to_string(m.index) + "/" +
                       std::to_string(count) + " of " + std::to_string(episodes));
      }
      if (episode_at[k].first) {
        throw RunError("episode " + std::to_string(k) + " appears twice: in '" +
                       episode_at[k].first->path.string() + "' and '" + m.path.string() + "'");
      }
      // cut short by a signal: counted as missing (manifests from before "complete" existed
      // say it by their step count)
      if (!e.value("complete", e.value("steps", -1) == steps)) continue;
      bool files = true;
      // its video in every format (EpisodeVideos: "video" alone in older manifests)
      std::vector<std::pair<std::string, std::string>> needed;  // what, file
      for (const EpisodeVideo& v : EpisodeVideos(e)) needed.emplace_back("video", v.file);
      if (needed.empty()) needed.emplace_back("video", "");
      for (const char* kind : {"sheet", "trajectory"}) {
        needed.emplace_back(kind, e.value(kind, std::string()));
      }
      for (const auto& [what, name] : needed) {
        const fs::path file = m.path.parent_path() / name;
        if (name.empty() || !fs::is_regular_file(file)) {
          problems.push_back("episode " + std::to_string(k) + ": " + what + " '" + file.string() +
                             "' is missing");
          files = false;
        }
      }
      if (files) episode_at[k] = {&m, &e};
    }
  }
  for (int s = 0; s < count; ++s) {
    std::vector<int> missing;
    for (int k = s; k < episodes; k += count) {
      if (!episode_at[k].first) missing.push_back(k);
    }
    if (missing.empty()) continue;
    const std::string label = std::to_string(s) + "/" + std::to_string(count);
    auto it = by_shard.find(s);
    if (it == by_shard.end()) {
      problems.push_back("shard " + label + " has no manifest (episodes " + EpisodeList(missing) +
                         ")");
    } else if (it->second->data.value("interrupted", false)) {
      const json& sig = it->second->data["signal"];
      problems.push_back("shard " + label + " was interrupted" +
                         (sig.is_string() ? " by " + sig.get<std::string>() : "") + " (episodes " +
                         EpisodeList(missing) + " missing or incomplete)");
    } else {
      problems.push_back("shard " + label + " lacks episodes " + EpisodeList(missing));
    }
  }
  if (!problems.empty()) {
    std::string message = "the run is incomplete: ";
    for (size_t i = 0; i < problems.size(); ++i) message += (i ? "; " : "") + problems[i];
    throw RunError(message);
  }

  // the merged manifest: the run's settings, every episode in order, and each shard's record
  if (out.empty()) out = (fs::path(dirs.front()) / "manifest.json").string();
  const fs::path out_dir =
      fs::path(out).parent_path().empty() ? fs::path(".") : fs::path(out).parent_path();
  json merged = first.data;
  for (const char* per_shard :
       {"shard", "jobs", "backend", "timings_s", "frames", "signal", "command_line", "versions",
        "workers", "missing", "failures", "gpu", "worker_mode"}) {
    merged.erase(per_shard);
  }
  json list = json::array();
  int successes = 0;
  long frames = 0;
  for (int k = 0; k < episodes; ++k) {
    json e = *episode_at[k].second;
    const fs::path folder = episode_at[k].first->path.parent_path();
    RebaseFiles(&e, folder, out_dir);
    successes += e.value("is_success", false);
    list.push_back(std::move(e));
  }
  json shards = json::array();
  double wall_max = 0;
  json sums = {{"wall", 0.0}, {"sim", 0.0}, {"render", 0.0}, {"encode", 0.0}, {"write", 0.0}};
  for (const auto& [index, m] : by_shard) {
    const json& t = m->data.value("timings_s", json::object());
    for (auto& [key, value] : sums.items()) value = value.get<double>() + t.value(key, 0.0);
    wall_max = std::max(wall_max, t.value("wall", 0.0));
    frames += m->data.value("frames", 0L);
    shards.push_back({{"index", index},
                      {"count", count},
                      {"source", m->data["shard"].value("source", json(nullptr))},
                      {"manifest", RelativeTo(m->path, out_dir)},
                      {"episodes", m->data["episodes"].size()},
                      {"jobs", m->data.value("jobs", 1)},
                      {"workers", m->data.value("workers", json(nullptr))},
                      {"backend", m->data.value("backend", json(nullptr))},
                      {"timings_s", t},
                      {"frames", m->data.value("frames", 0L)},
                      {"command_line", m->data.value("command_line", json(nullptr))},
                      {"versions", m->data.value("versions", json(nullptr))}});
  }
  merged["episodes"] = std::move(list);
  merged["shards"] = std::move(shards);
  merged["frames"] = frames;
  // wall: the slowest shard (they run side by side); the others: summed over shards
  merged["timings_s"] = {{"wall", wall_max},         {"wall_sum", sums["wall"]},
                         {"sim", sums["sim"]},       {"render", sums["render"]},
                         {"encode", sums["encode"]}, {"write", sums["write"]}};
  merged["backend"] = first.data.value("backend", json(nullptr));
  merged["interrupted"] = false;
  merged["signal"] = nullptr;
  merged["merged"] = true;
  merged["command_line"] = CommandLine();
  merged["versions"] = VersionsJson();
  WriteJson(out, merged);
  if (!quiet) {
    std::printf("merge-manifests: %zu shard(s) of %d, %d episode(s), success %d/%d -> %s\n",
                by_shard.size(), count, episodes, successes, episodes, out.c_str());
  }
  if (report) WriteRunReportOrWarn(out, quiet);
  return 0;
}

}  // namespace

Command AddMergeManifests(CLI::App& app) {
  auto dirs = std::make_shared<std::vector<std::string>>();
  auto out = std::make_shared<std::string>();
  auto quiet = std::make_shared<bool>(false);
  auto no_report = std::make_shared<bool>(false);
  CLI::App* sub = app.add_subcommand(
      "merge-manifests",
      "Merge the shard manifests of a sharded record run into one manifest.json; exit 1 naming "
      "any missing, interrupted or duplicated shard or episode");
  sub->add_option("DIR", *dirs, "Folders holding manifest_shard_*.json (and the episodes' files)")
      ->required();
  sub->add_option("--out", *out,
                  "Merged manifest path (default: DIR/manifest.json of the first DIR)");
  sub->add_flag("-q,--quiet", *quiet, "No summary on stdout");
  sub->add_flag("--no-report", *no_report,
                "Do not write the run's HTML report (index.html beside the merged manifest)");
  return {sub, [=] { return Merge(*dirs, *out, *quiet, !*no_report); }};
}

}  // namespace fetchscope::cli
