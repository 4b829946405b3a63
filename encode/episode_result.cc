#include "encode/episode_result.h"

#include <cmath>
#include <tuple>

namespace fetchscope {
namespace {

bool SameDouble(const std::optional<double>& a, const std::optional<double>& b) {
  if (a.has_value() != b.has_value()) return false;
  if (!a) return true;
  return *a == *b || (std::isnan(*a) && std::isnan(*b));
}

}  // namespace

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
                  layers, hindsight, extra) ==
             std::tie(o.index, o.video, o.videos, o.sheet, o.trajectory, o.frames, o.steps,
                      o.complete, o.is_success, o.layers, o.hindsight, o.extra) &&
         SameDouble(episode_return, o.episode_return);
}

}  // namespace fetchscope
