#include "run/shard.h"

#include <filesystem>

#include "run/manifest.h"
#include "run/run_files.h"

namespace fetchscope {

int RunShardCount(const std::string& out) {
  namespace fs = std::filesystem;
  std::error_code ec;
  int n = 0;
  for (const auto& entry : fs::directory_iterator(out.empty() ? "." : out, ec)) {
    const std::string name = entry.path().filename().string();
    if (!IsShardManifestFileName(name)) continue;
    int count = 0;
    try {
      const Manifest m = ReadManifest(entry.path());
      if (m.shard && m.parameters.recorded) count = m.shard->count;
    } catch (const ManifestError&) {
      continue;  // not a record manifest: the run folder says so
    }
    if (count < 2 || (n && count != n)) return 0;
    n = count;
  }
  return n;
}

std::vector<int> ShardEpisodes(const Shard& shard, int episodes) {
  std::vector<int> mine;
  for (int k = shard.index; k < episodes; k += shard.count) mine.push_back(k);
  return mine;
}

std::vector<int> ShardEpisodes(const Shard& shard, const std::vector<int>& episodes) {
  std::vector<int> mine;
  for (int k : episodes) {
    if (shard.Owns(k)) mine.push_back(k);
  }
  return mine;
}

std::string ShardManifestName(const Shard& shard) {
  return ManifestFileName(shard.index, shard.count);
}

std::string ShardLabel(const Shard& shard) {
  return std::to_string(shard.index) + "/" + std::to_string(shard.count);
}

}  // namespace fetchscope
