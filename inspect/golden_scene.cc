#include "inspect/golden_scene.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "base/errors.h"
#include "base/json_util.h"
#include "base/suggest.h"
#include "render/camera.h"
#include "render/overlay.h"
#include "render/renderer.h"
#include "render/view.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/episode.h"
#include "src/fetch_env.h"
#include "src/policy.h"

namespace fs = std::filesystem;

namespace fetchscope {
namespace {

// The manifest's members, read with one clear line per mistake.
class ManifestReader {
 public:
  explicit ManifestReader(std::string path) : path_(std::move(path)) {}

  [[noreturn]] void Fail(const std::string& where, const std::string& what) const {
    throw RunError("golden manifest '" + path_ + "': " + where + ": " + what);
  }

  std::string String(const nlohmann::json& obj, const char* key, const std::string& where,
                     const std::string* fallback = nullptr) const {
    if (!obj.contains(key)) {
      if (fallback) return *fallback;
      Fail(where, std::string("\"") + key + "\" is missing");
    }
    if (!obj[key].is_string()) Fail(where, std::string("\"") + key + "\" must be a string");
    return obj[key].get<std::string>();
  }

  int64_t Integer(const nlohmann::json& obj, const char* key, const std::string& where, int64_t low,
                  int64_t high, const int64_t* fallback = nullptr) const {
    if (!obj.contains(key)) {
      if (fallback) return *fallback;
      Fail(where, std::string("\"") + key + "\" is missing");
    }
    const nlohmann::json& v = obj[key];
    if (!v.is_number_integer() || v.get<int64_t>() < low || v.get<int64_t>() > high) {
      Fail(where, std::string("\"") + key + "\" must be an integer in " + std::to_string(low) +
                      ".." + std::to_string(high));
    }
    return v.get<int64_t>();
  }

  double Number(const nlohmann::json& obj, const char* key, const std::string& where,
                double fallback) const {
    if (!obj.contains(key)) return fallback;
    const nlohmann::json& v = obj[key];
    if (!v.is_number() || !(v.get<double>() >= 0)) {
      Fail(where, std::string("\"") + key + "\" must be a non-negative number");
    }
    return v.get<double>();
  }

  GoldenTolerance Tolerance(const nlohmann::json& obj, const std::string& where,
                            const GoldenTolerance& fallback) const {
    GoldenTolerance t = fallback;
    if (!obj.contains("tolerance")) return t;
    const nlohmann::json& tol = obj["tolerance"];
    if (!tol.is_object()) Fail(where, "\"tolerance\" must be an object");
    for (const auto& item : tol.items()) {
      if (item.key() != "threshold" && item.key() != "max_fraction" && item.key() != "max_rms") {
        Fail(where,
             "unknown tolerance \"" + item.key() + "\": use threshold, max_fraction, max_rms");
      }
    }
    const int64_t threshold = t.threshold;
    t.threshold =
        static_cast<int>(Integer(tol, "threshold", where + " tolerance", 0, 255, &threshold));
    t.max_fraction = Number(tol, "max_fraction", where + " tolerance", t.max_fraction);
    t.max_rms = Number(tol, "max_rms", where + " tolerance", t.max_rms);
    return t;
  }

 private:
  std::string path_;
};

bool ValidName(const std::string& name) {
  if (name.empty()) return false;
  for (char c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-') return false;
  }
  return true;
}

// The trajectory numbers up to the frame: what the state golden holds.
nlohmann::json StateJson(const GoldenScene& scene, const EpisodeRecord& episode) {
  const nlohmann::json steps = StepsJson(episode);  // the trajectory JSON's step rows
  return {{"scene", scene.name},
          {"env_id", scene.env_id},
          {"seed", scene.seed},
          {"policy", scene.policy.text},
          {"steps", std::move(steps)}};
}

std::string Describe(const nlohmann::json& v) {
  if (v.is_number_float()) return FormatDouble(v.get<double>());
  return v.dump();
}

void Compare(const nlohmann::json& g, const nlohmann::json& a, double atol, const std::string& path,
             StateComparison* out) {
  auto differ = [&](const std::string& what) {
    if (out->equal) out->first = (path.empty() ? std::string("(top)") : path) + ": " + what;
    out->equal = false;
  };
  if (g.is_number() && a.is_number()) {
    const double d = std::fabs(g.get<double>() - a.get<double>());
    if (std::isnan(d) || d > atol) {
      if (!std::isnan(d)) out->max_abs = std::max(out->max_abs, d);
      char buf[64];
      std::snprintf(buf, sizeof(buf), " (|diff| %.3g > %.3g)", d, atol);
      differ("golden " + Describe(g) + ", actual " + Describe(a) + buf);
    } else {
      out->max_abs = std::max(out->max_abs, d);
    }
    return;
  }
  if (g.type() != a.type()) {
    differ("golden " + Describe(g) + ", actual " + Describe(a));
    return;
  }
  if (g.is_array()) {
    if (g.size() != a.size()) {
      differ("golden has " + std::to_string(g.size()) + " entries, actual " +
             std::to_string(a.size()));
    }
    for (size_t i = 0; i < std::min(g.size(), a.size()); ++i) {
      Compare(g[i], a[i], atol, path + "[" + std::to_string(i) + "]", out);
    }
    return;
  }
  if (g.is_object()) {
    for (const auto& item : g.items()) {
      const std::string child = path.empty() ? item.key() : path + "." + item.key();
      if (!a.contains(item.key())) {
        differ("actual lacks \"" + item.key() + "\"");
        continue;
      }
      Compare(item.value(), a[item.key()], atol, child, out);
    }
    for (const auto& item : a.items()) {
      if (!g.contains(item.key())) differ("golden lacks \"" + item.key() + "\"");
    }
    return;
  }
  if (g != a) differ("golden " + Describe(g) + ", actual " + Describe(a));
}

// The manifest.json of the golden folder `dir`, parsed; `path` gets its path.
nlohmann::json ReadManifestJson(const std::string& dir, std::string* path) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw UsageError("golden folder '" + dir +
                     "' does not exist: pass --golden-dir with the folder holding manifest.json");
  }
  *path = (fs::path(dir) / "manifest.json").string();
  std::ifstream in(*path, std::ios::binary);
  if (!in) {
    throw UsageError("golden folder '" + dir + "' has no manifest.json");
  }
  std::stringstream text;
  text << in.rdbuf();
  try {
    return nlohmann::json::parse(text.str());
  } catch (const nlohmann::json::parse_error& e) {
    throw RunError("golden manifest '" + *path + "' is not valid JSON: " + e.what());
  }
}

// The manifest's "defaults", over the built-in ones.
GoldenScene ReadDefaults(ManifestReader& r, const nlohmann::json& root) {
  GoldenScene defaults;
  if (root.contains("defaults")) {
    const nlohmann::json& d = root["defaults"];
    if (!d.is_object()) r.Fail("defaults", "must be an object");
    const int64_t msaa = defaults.msaa;
    defaults.msaa = static_cast<int>(r.Integer(d, "msaa", "defaults", 0, 16, &msaa));
    defaults.state_atol = r.Number(d, "state_atol", "defaults", defaults.state_atol);
    defaults.tolerance = r.Tolerance(d, "defaults", defaults.tolerance);
  }
  return defaults;
}

// Scene `i` of the manifest in the golden folder `dir`, its name not in `names` (and then
// added to it).
GoldenScene ReadScene(ManifestReader& r, const nlohmann::json& s, size_t i,
                      const GoldenScene& defaults, const std::string& dir,
                      std::set<std::string>* names) {
  static const std::set<std::string> kKnown = {
      "name",    "env_id", "assets", "seed", "policy",    "steps",      "camera",
      "overlay", "width",  "height", "msaa", "tolerance", "state_atol", "note"};
  std::string where = "scenes[" + std::to_string(i) + "]";
  if (!s.is_object()) r.Fail(where, "must be an object");
  GoldenScene scene;
  scene.name = r.String(s, "name", where);
  if (!ValidName(scene.name))
    r.Fail(where, "name '" + scene.name + "' must be letters, digits, _ or -");
  where = "scene '" + scene.name + "'";
  if (!names->insert(scene.name).second) r.Fail(where, "the name is used twice");
  for (const auto& item : s.items()) {
    if (!kKnown.count(item.key())) r.Fail(where, "unknown member \"" + item.key() + "\"");
  }
  scene.env_id = r.String(s, "env_id", where);
  try {
    FindEnvSpec(scene.env_id);
  } catch (const UsageError& e) {
    r.Fail(where, e.what());
  }
  const std::string bundled = "bundled";
  scene.assets = r.String(s, "assets", where, &bundled);
  if (!s.contains("seed") || !s["seed"].is_number_unsigned()) {
    r.Fail(where, "\"seed\" must be a non-negative integer");
  }
  scene.seed = s["seed"].get<uint64_t>();
  try {  // a replay file lives beside the manifest, and is read here
    scene.policy =
        ParsePolicySpec(r.String(s, "policy", where, &defaults.policy.text), {10.0, "", dir});
  } catch (const UsageError& e) {
    r.Fail(where, e.what());
  }
  scene.steps = static_cast<int>(r.Integer(s, "steps", where, 0, 50));
  scene.camera = r.String(s, "camera", where, &defaults.camera);
  scene.overlay = r.String(s, "overlay", where, &defaults.overlay);
  scene.width = static_cast<int>(r.Integer(s, "width", where, 16, 2048));
  scene.height = static_cast<int>(r.Integer(s, "height", where, 16, 2048));
  const int64_t msaa = defaults.msaa;
  scene.msaa = static_cast<int>(r.Integer(s, "msaa", where, 0, 16, &msaa));
  scene.tolerance = r.Tolerance(s, where, defaults.tolerance);
  scene.state_atol = r.Number(s, "state_atol", where, defaults.state_atol);
  try {
    ParseOverlays(scene.overlay);
  } catch (const UsageError& e) {
    r.Fail(where, e.what());
  }
  return scene;
}

}  // namespace

GoldenManifest ReadGoldenManifest(const std::string& dir) {
  std::string path;
  const nlohmann::json root = ReadManifestJson(dir, &path);
  ManifestReader r(path);
  if (!root.is_object() || !root.contains("scenes") || !root["scenes"].is_array()) {
    r.Fail("top level", "expected an object with a \"scenes\" array");
  }
  const GoldenScene defaults = ReadDefaults(r, root);
  GoldenManifest manifest;
  manifest.dir = dir;
  std::set<std::string> names;
  for (size_t i = 0; i < root["scenes"].size(); ++i) {
    manifest.scenes.push_back(ReadScene(r, root["scenes"][i], i, defaults, dir, &names));
  }
  if (manifest.scenes.empty()) r.Fail("scenes", "lists no scene");
  return manifest;
}

std::vector<const GoldenScene*> SelectScenes(const GoldenManifest& manifest,
                                             const std::vector<std::string>& only) {
  std::vector<const GoldenScene*> selected;
  if (only.empty()) {
    for (const GoldenScene& s : manifest.scenes) selected.push_back(&s);
    return selected;
  }
  std::set<std::string> wanted;
  for (const std::string& entry : only) {
    std::stringstream ss(entry);
    for (std::string name; std::getline(ss, name, ',');) {
      if (name.empty()) continue;
      bool found = false;
      for (const GoldenScene& s : manifest.scenes) found = found || s.name == name;
      if (!found) {
        std::string valid;
        std::vector<std::string> names;
        for (const GoldenScene& s : manifest.scenes) {
          valid += (valid.empty() ? "" : ", ") + s.name;
          names.push_back(s.name);
        }
        throw UsageError("--only: no scene named '" + name + "' in " + manifest.dir +
                         "/manifest.json" + DidYouMean(name, names) + "; valid names: " + valid);
      }
      wanted.insert(name);
    }
  }
  for (const GoldenScene& s : manifest.scenes) {
    if (wanted.count(s.name)) selected.push_back(&s);
  }
  return selected;
}

std::string SceneAssets(const GoldenScene& scene, const std::string& golden_dir,
                        const std::string& genuine_dir) {
  if (scene.assets == "bundled") return "bundled";
  if (scene.assets == "genuine") return genuine_dir;
  return (fs::path(golden_dir) / scene.assets).string();
}

SceneResult RenderScene(GlContext& gl, const GoldenScene& scene, const std::string& assets_root) {
  const EnvSpec& spec = FindEnvSpec(scene.env_id);
  PolicyContext context;
  context.seed = scene.seed;
  context.steps_per_episode = scene.steps;
  auto policy = MakePolicy(scene.policy, spec, context);
  FetchEnv env(spec, ResolveAssets(assets_root));
  // the scene's own cameras and overlays (golden/scenes.json, checked when it was read)
  RenderOptions options;
  options.width = scene.width;
  options.height = scene.height;
  options.cameras = ParseCameraList(scene.camera, env.model());
  options.overlays = ParseOverlays(scene.overlay);
  // pinned per scene: goldens must not follow whatever default --msaa has
  options.msaa_samples = scene.msaa;
  CheckRenderFrame(options);
  gl.MakeCurrent();
  Renderer renderer(gl, env.model(), options);

  SceneResult result;
  result.width = renderer.width();
  result.height = renderer.height();
  result.rgb.resize(static_cast<size_t>(result.width) * result.height * 3);
  // the trail overlay grows one point per rendered step: render every step for it
  StepCallback on_step;
  if (options.overlays.trail) {
    on_step = [&](const StepRecord& record, const StepResult*) {
      renderer.Render(env.data(), MakeFrameInfo(env, record), result.rgb.data());
      return true;
    };
  }
  const EpisodeRecord episode = RunEpisode(env, *policy, 0, scene.seed, scene.steps, on_step);
  if (!options.overlays.trail) {
    renderer.Render(env.data(), MakeFrameInfo(env, episode.steps.back()), result.rgb.data());
  }
  result.state = StateJson(scene, episode);
  return result;
}

StateComparison CompareStates(const nlohmann::json& golden, const nlohmann::json& actual,
                              double atol) {
  StateComparison out;
  Compare(golden, actual, atol, "", &out);
  return out;
}

}  // namespace fetchscope
