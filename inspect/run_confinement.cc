// A run folder's files, read only where they should be: the folders a run's files may lie in, and
// the check that every file its manifest names lies there and is a regular file (report, compare,
// serve and record --from read runs through it).
#include "inspect/run_confinement.h"

#include <nlohmann/json.hpp>
#include <system_error>
#include <utility>
#include <vector>

#include "base/confined_file.h"
#include "run/run_files.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Every file an entry names, with what it is: {"trajectory", "episode_000.json"}, ...
std::vector<std::pair<std::string, std::string>> NamedFiles(const ManifestEpisode& e) {
  std::vector<std::pair<std::string, std::string>> files;
  auto add = [&files](const std::string& what, const std::string& name) {
    if (!name.empty()) files.emplace_back(what, name);
  };
  add("video", e.video);
  for (const auto& [format, v] : e.videos) add(format + " video", v.file);
  add("sheet", e.sheet);
  add("trajectory", e.trajectory);
  for (const auto& [name, layer] : e.layers) {
    add(name + " video", layer.video);
    for (const auto& [format, v] : layer.videos) add(name + " " + format + " video", v.file);
    add(name + " legend", layer.legend);
  }
  return files;
}

}  // namespace

// The folders a run's files may lie in: its own, and a merged run's shard folders: those holding
// the shard manifests its "shards" names, resolved, where such a file is there.
std::vector<fs::path> RunFolders(const fs::path& dir, const Manifest& m) {
  std::vector<fs::path> folders = {dir};
  if (!m.merged || !m.shards.is_array()) return folders;
  for (const json& shard : m.shards) {
    if (!shard.is_object() || !shard.contains("manifest") || !shard["manifest"].is_string()) {
      continue;
    }
    std::error_code ec;
    const fs::path resolved =
        fs::weakly_canonical(fs::absolute(dir / shard["manifest"].get<std::string>(), ec), ec);
    if (ec || !IsShardManifestFileName(resolved.filename().string()) ||
        !fs::is_regular_file(resolved, ec)) {
      continue;
    }
    folders.push_back(resolved.parent_path());
  }
  return folders;
}

// Refuses a manifest that names a file outside its folder (symbolic links and '..' followed),
// or one that is there but is not a regular file (a FIFO, a device, a folder): what reads the
// run (report, compare, serve) then reads only the run's own files.
void CheckNamedFiles(const RecordedRun& run) {
  const std::string manifest = run.manifest_path.filename().string();
  for (const ManifestEpisode& e : run.manifest.episodes) {
    for (const auto& [what, name] : NamedFiles(e)) {
      RunFile(run, name, manifest + " names episode " + std::to_string(e.index) + "'s " + what);
    }
  }
}

fs::path RunFile(const RecordedRun& run, const std::string& entry, const std::string& named_by) {
  const fs::path path = run.dir / entry;
  bool inside = false;
  for (const fs::path& folder : run.folders) inside = inside || LiesInside(folder, path);
  if (!inside) ResolveInside(run.dir, entry, named_by);  // throws, naming the run folder
  RequireRegularIfPresent(path, entry, named_by);
  return path;
}

}  // namespace fetchscope
