#include "src/assets.h"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <vector>

#include "base/errors.h"
#include "base/sha256.h"
#include "fetchscope/paths.h"

namespace fs = std::filesystem;

namespace fetchscope {
namespace {

bool HoldsFetchModels(const fs::path& fetch_dir) {
  std::error_code ec;
  return fs::is_regular_file(fetch_dir / "reach.xml", ec) &&
         fs::is_regular_file(fetch_dir / "push.xml", ec);
}

AssetSource FromDir(const fs::path& dir, const std::string& origin) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw UsageError("assets folder '" + dir.string() +
                     "' does not exist: use bundled, auto, or a Gymnasium-Robotics envs/assets "
                     "folder holding fetch/, stls/ and textures/");
  }
  if (!HoldsFetchModels(dir / "fetch")) {
    throw UsageError("assets folder '" + dir.string() +
                     "' has no fetch/reach.xml: give a Gymnasium-Robotics envs/assets folder "
                     "(holding fetch/, stls/, textures/)");
  }
  AssetSource a;
  a.kind = "dir";
  a.root = fs::canonical(dir).string();
  a.fetch_dir = (fs::path(a.root) / "fetch").string();
  a.sha256 = Sha256OfTree(a.root, {"fetch", "stls/fetch", "textures"});
  a.origin = origin;
  return a;
}

AssetSource Bundled(const std::string& origin) {
  AssetSource a;
  a.kind = "bundled";
  a.root = BundledModelsDir();
  a.fetch_dir = a.root;
  a.sha256 = Sha256OfTree(a.root, {"."});
  a.origin = origin;
  return a;
}

// Installed gymnasium_robotics packages: system, /usr/local, user site and a virtualenv.
std::string FindInstalledGymnasiumRobotics() {
  std::vector<fs::path> bases = {"/usr/lib/python3/dist-packages"};
  std::vector<fs::path> prefixes = {"/usr/local/lib", "/usr/lib"};
  if (const char* venv = std::getenv("VIRTUAL_ENV")) prefixes.push_back(fs::path(venv) / "lib");
  if (const char* conda = std::getenv("CONDA_PREFIX")) prefixes.push_back(fs::path(conda) / "lib");
  if (const char* home = std::getenv("HOME")) prefixes.push_back(fs::path(home) / ".local/lib");
  std::error_code ec;
  for (const fs::path& prefix : prefixes) {
    if (!fs::is_directory(prefix, ec)) continue;
    for (const auto& entry : fs::directory_iterator(prefix, ec)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("python3", 0) != 0) continue;
      bases.push_back(entry.path() / "site-packages");
      bases.push_back(entry.path() / "dist-packages");
    }
  }
  for (const fs::path& base : bases) {
    fs::path assets = base / "gymnasium_robotics" / "envs" / "assets";
    if (HoldsFetchModels(assets / "fetch")) return assets.string();
  }
  return "";
}

}  // namespace

std::string InstalledDataDir(const std::string& name) {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return "";
  for (const fs::path& dir : {exe.parent_path() / name,
                              exe.parent_path().parent_path() / "share" / "fetchscope" / name}) {
    if (fs::is_directory(dir, ec)) return dir.string();
  }
  return "";
}

std::string BundledModelsDir() {
  std::error_code ec;
  fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    fs::path beside = exe.parent_path() / "models";
    if (HoldsFetchModels(beside)) return beside.string();
    fs::path installed = exe.parent_path().parent_path() / "share" / "fetchscope" / "models";
    if (HoldsFetchModels(installed)) return installed.string();
  }
#ifdef FETCHSCOPE_SOURCE_MODELS
  if (HoldsFetchModels(FETCHSCOPE_SOURCE_MODELS)) return FETCHSCOPE_SOURCE_MODELS;
#endif
  throw RunError("the bundled models are missing: expected reach.xml etc. in '" +
                 (exe.parent_path() / "models").string() +
                 "' (rebuild, or pass --assets DIR with a Gymnasium-Robotics assets folder)");
}

AssetSource ResolveAssets(const std::string& spec) {
  if (spec.empty() || spec == "bundled") return Bundled("--assets bundled");
  if (spec == "auto") {
    if (const char* env = std::getenv("FETCHSCOPE_ASSETS"); env && *env) {
      return FromDir(env, "--assets auto: $FETCHSCOPE_ASSETS");
    }
    std::string installed = FindInstalledGymnasiumRobotics();
    if (!installed.empty())
      return FromDir(installed, "--assets auto: installed gymnasium_robotics");
    return Bundled("--assets auto: bundled (no $FETCHSCOPE_ASSETS, no gymnasium_robotics found)");
  }
  return FromDir(spec, "--assets " + spec);
}

std::string ModelPath(const AssetSource& assets, const EnvSpec& spec) {
  return (fs::path(assets.fetch_dir) / spec.model_file).string();
}

}  // namespace fetchscope
