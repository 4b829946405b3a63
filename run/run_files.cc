#include "run/run_files.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "base/confined_file.h"
#include "encode/video_format.h"

namespace fetchscope {
namespace {

constexpr const char kShardManifestPrefix[] = "manifest_shard_";
constexpr const char kEpisodePrefix[] = "episode_";
constexpr const char kSheetTail[] = "_sheet.png";
constexpr const char kLegendTail[] = "_segmentation_legend.json";

bool EndsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

bool AllDigits(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) {
    return std::isdigit(static_cast<unsigned char>(c));
  });
}

// What may follow episode_NNN in an episode's file names: the videos (one per
// --format), the contact sheet, the trajectory, and the --layers videos and legend.
bool EpisodeFileTail(const std::string& tail) {
  static const std::set<std::string> tails = [] {
    std::set<std::string> t = {kSheetTail, ".json", kLegendTail};
    for (const VideoFormat& format : VideoFormats()) {
      for (const char* layer : {"", "_depth", "_segmentation"}) {
        t.insert(std::string(layer) + "." + std::string(format.extension));
      }
    }
    return t;
  }();
  return tails.count(tail) > 0;
}

// A visible name as record writes it.
std::optional<RunFileName> ParseVisible(const std::string& name) {
  RunFileName parsed;
  if (IsManifestFileName(name)) {
    parsed.manifest = true;
    return parsed;
  }
  if (name == kReportFileName) {
    parsed.report = true;
    return parsed;
  }
  const size_t start = sizeof(kEpisodePrefix) - 1;
  if (name.rfind(kEpisodePrefix, 0) != 0) return std::nullopt;
  size_t end = start;
  while (end < name.size() && std::isdigit(static_cast<unsigned char>(name[end]))) ++end;
  const std::string digits = name.substr(start, end - start);
  if (!AllDigits(digits) || digits.size() > 9 || !EpisodeFileTail(name.substr(end))) {
    return std::nullopt;
  }
  parsed.episode = std::stoi(digits);
  return parsed;
}

}  // namespace

std::string EpisodeStem(int k) {
  char name[32];
  std::snprintf(name, sizeof(name), "%s%03d", kEpisodePrefix, k);
  return name;
}

std::string EpisodeVideoFileName(int k, const std::string& extension) {
  return EpisodeStem(k) + "." + extension;
}

std::string EpisodeLayerVideoFileName(int k, const std::string& layer,
                                      const std::string& extension) {
  return EpisodeStem(k) + "_" + layer + "." + extension;
}

std::string EpisodeLegendFileName(int k) { return EpisodeStem(k) + kLegendTail; }

std::string EpisodeSheetFileName(int k) { return EpisodeStem(k) + kSheetTail; }

std::string EpisodeTrajectoryFileName(int k) { return EpisodeStem(k) + ".json"; }

std::string ManifestFileName(int shard_index, int shard_count) {
  if (shard_count <= 1) return kManifestFileName;
  char name[64];
  std::snprintf(name, sizeof(name), "%s%04d_of_%04d.json", kShardManifestPrefix, shard_index,
                shard_count);
  return name;
}

bool IsShardManifestFileName(const std::string& name) {
  return name.rfind(kShardManifestPrefix, 0) == 0 && EndsWith(name, ".json");
}

bool IsManifestFileName(const std::string& name) {
  return name == kManifestFileName || IsShardManifestFileName(name);
}

std::optional<RunFileName> ParseRunFileName(const std::string& name) {
  if (name.empty()) return std::nullopt;
  if (name[0] != '.') return ParseVisible(name);
  // .STEM.partial-PID.EXT (VideoWriter; .STEM.partial.EXT before the PID was added) and
  // .NAME.tmp-XXXX (WriteFileAtomically)
  std::string inner = name.substr(1);
  const size_t tmp = inner.find(".tmp-");
  const size_t partial = inner.rfind(".partial");
  const size_t extension = partial == std::string::npos ? partial : inner.find('.', partial + 8);
  if (tmp != std::string::npos) {
    inner = inner.substr(0, tmp);
  } else if (extension != std::string::npos) {
    inner = inner.substr(0, partial) + inner.substr(extension);
  } else {
    return std::nullopt;
  }
  std::optional<RunFileName> parsed = ParseVisible(inner);
  if (parsed) parsed->hidden = true;
  return parsed;
}

namespace fs = std::filesystem;

bool IsFetchscopeTrajectory(const fs::path& path) {
  std::string text;
  try {
    text = ReadFileCapped(path, kMaxJsonFileBytes);  // never a FIFO, a device, a huge file
  } catch (const std::exception&) {
    return false;
  }
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  return j.is_object() && j.contains("env_id") && j.contains("seed") && j.contains("episodes");
}

bool IsFetchscopeVideo(const fs::path& path, int k, const std::string& title) {
  const std::string marks[] = {"fetchscope_version",
                               title.empty() ? " episode " + std::to_string(k) + " (" : title,
                               "FETCHSCOPE_VERSION"};
  bool found[2] = {false, false};
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return false;  // a FIFO would block, a device never end
  std::ifstream in(path, std::ios::binary);
  constexpr size_t kPiece = 1 << 20;
  const size_t kOverlap = std::max<size_t>(64, marks[1].size());  // longer than either mark
  std::string buffer;
  std::string piece(kPiece, '\0');
  while (in) {
    in.read(&piece[0], static_cast<std::streamsize>(piece.size()));
    const size_t n = static_cast<size_t>(in.gcount());
    if (n == 0) break;
    buffer.append(piece, 0, n);
    for (int i = 0; i < 2; ++i) found[i] = found[i] || buffer.find(marks[i]) != std::string::npos;
    found[0] = found[0] || buffer.find(marks[2]) != std::string::npos;
    if (found[0] && found[1]) return true;
    if (buffer.size() > kOverlap) buffer.erase(0, buffer.size() - kOverlap);
  }
  return false;
}

bool EpisodeHasFetchscopeVideo(const fs::path& out, int k, const std::vector<std::string>& names,
                               std::map<int, bool>* videos) {
  const auto known = videos->find(k);
  if (known != videos->end()) return known->second;
  bool found = false;
  for (const std::string& name : names) {
    const std::optional<RunFileName> parsed = ParseRunFileName(name);
    if (found || !parsed || parsed->episode != k || !IsVideoFileName(name)) continue;
    found = IsFetchscopeVideo(out / name, k);
  }
  (*videos)[k] = found;
  return found;
}

bool IsFetchscopeReport(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return false;  // a FIFO would block
  std::ifstream in(path, std::ios::binary);
  std::string head(4096, '\0');
  in.read(&head[0], static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  return head.find("<meta name=\"generator\" content=\"fetchscope ") != std::string::npos;
}

}  // namespace fetchscope
