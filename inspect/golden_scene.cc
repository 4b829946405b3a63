#include "inspect/golden_scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>

#include "base/errors.h"
#include "base/json_util.h"
#include "base/sha256.h"
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
                            const GoldenTolerance& fallback, const char* key = "tolerance") const {
    GoldenTolerance t = fallback;
    if (!obj.contains(key)) return t;
    const nlohmann::json& tol = obj[key];
    if (!tol.is_object()) Fail(where, std::string("\"") + key + "\" must be an object");
    for (const auto& item : tol.items()) {
      if (item.key() != "threshold" && item.key() != "max_fraction" && item.key() != "max_rms") {
        Fail(where,
             "unknown tolerance \"" + item.key() + "\": use threshold, max_fraction, max_rms");
      }
    }
    const int64_t threshold = t.threshold;
    const std::string in = where + " " + key;
    t.threshold = static_cast<int>(Integer(tol, "threshold", in, 0, 255, &threshold));
    t.max_fraction = Number(tol, "max_fraction", in, t.max_fraction);
    t.max_rms = Number(tol, "max_rms", in, t.max_rms);
    return t;
  }

  // "mask": [[x, y, width, height], ...]; whether each lies in the frame is checked with the
  // frame (MaskOutsideFrame).
  std::vector<GoldenMask> Masks(const nlohmann::json& obj, const std::string& where) const {
    std::vector<GoldenMask> masks;
    if (!obj.contains("mask")) return masks;
    const nlohmann::json& list = obj["mask"];
    const std::string accepted =
        "a list of [x, y, width, height] rectangles, non-negative integers, width and height > 0";
    if (!list.is_array()) Fail(where, "\"mask\" must be " + accepted);
    for (size_t i = 0; i < list.size(); ++i) {
      const nlohmann::json& r = list[i];
      bool ok = r.is_array() && r.size() == 4;
      for (size_t k = 0; ok && k < 4; ++k) {
        ok = r[k].is_number_integer() && r[k].get<int64_t>() >= 0 && r[k].get<int64_t>() <= 65536;
      }
      const std::string bad =
          "\"mask\"[" + std::to_string(i) + "] " + (ok ? r.dump() : "") + " must be " + accepted;
      if (!ok) Fail(where, bad);
      GoldenMask m{r[0].get<int>(), r[1].get<int>(), r[2].get<int>(), r[3].get<int>()};
      if (m.width == 0 || m.height == 0) Fail(where, bad);
      masks.push_back(m);
    }
    return masks;
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
    defaults.same_tolerance =
        r.Tolerance(d, "defaults", defaults.same_tolerance, "same_backend_tolerance");
  }
  return defaults;
}

// "randomize" and "look_seed": the scene's fixed look, if any.
void ReadLook(ManifestReader& r, const nlohmann::json& s, const std::string& where,
              GoldenScene* scene) {
  const std::string none;
  scene->randomize = r.String(s, "randomize", where, &none);
  try {
    scene->look = ParseRandomize(scene->randomize);
  } catch (const UsageError& e) {
    std::string what = e.what();  // "--randomize: 'x' is not a kind ...": named as the member
    if (what.rfind("--randomize: ", 0) == 0) what.erase(0, 13);
    r.Fail(where, "\"randomize\": " + what);
  }
  scene->look_seed = scene->seed;
  if (!s.contains("look_seed")) return;
  if (!scene->look.any()) {
    r.Fail(where,
           "\"look_seed\" needs \"randomize\" (a comma list of colors, textures, "
           "lighting, camera)");
  }
  if (!s["look_seed"].is_number_unsigned()) {
    r.Fail(where, "\"look_seed\" must be a non-negative integer");
  }
  scene->look_seed = s["look_seed"].get<uint64_t>();
}

// Scene `i` of the manifest in the golden folder `dir`, its name not in `names` (and then
// added to it).
GoldenScene ReadScene(ManifestReader& r, const nlohmann::json& s, size_t i,
                      const GoldenScene& defaults, const std::string& dir,
                      std::set<std::string>* names) {
  static const std::set<std::string> kKnown = {
      "name",  "env_id",    "assets",     "seed",  "policy",
      "steps", "camera",    "overlay",    "width", "height",
      "msaa",  "tolerance", "state_atol", "note",  "same_backend_tolerance",
      "mask",  "randomize", "look_seed"};
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
  scene.same_tolerance = r.Tolerance(s, where, defaults.same_tolerance, "same_backend_tolerance");
  scene.state_atol = r.Number(s, "state_atol", where, defaults.state_atol);
  scene.masks = r.Masks(s, where);
  try {
    ParseOverlays(scene.overlay);
  } catch (const UsageError& e) {
    r.Fail(where, e.what());
  }
  ReadLook(r, s, where, &scene);
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
  const AssetSource assets = ResolveAssets(assets_root);
  FetchEnv env(spec, assets);
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
  std::optional<LookDraw> look;
  if (scene.look.any()) {  // episode 0's draw of `render --seed look_seed --randomize ...`
    look = DrawLook(scene.look, LookSeed(scene.look_seed, 0), renderer.camera_keys(), env.model());
    renderer.SetLook(&*look);
  }

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
  result.assets_sha256 = assets.sha256;
  result.msaa_used = renderer.msaa_samples();
  result.msaa_reason = renderer.msaa_reason();
  // the objects each pixel shows: unchanged by a material or colour, changed by a camera,
  // a pose or a shape
  std::vector<int32_t> segments;
  renderer.RenderSegmentIndices(env.data(), MakeFrameInfo(env, episode.steps.back()), &segments);
  result.segmentation_sha256 = Sha256Hex(std::string(reinterpret_cast<const char*>(segments.data()),
                                                     segments.size() * sizeof(int32_t)));
  return result;
}

std::string MaskOutsideFrame(const GoldenScene& scene, int width, int height) {
  for (size_t i = 0; i < scene.masks.size(); ++i) {
    const GoldenMask& m = scene.masks[i];
    if (m.x + m.width > width || m.y + m.height > height) {
      return "scene '" + scene.name + "': \"mask\"[" + std::to_string(i) + "] [" +
             std::to_string(m.x) + ", " + std::to_string(m.y) + ", " + std::to_string(m.width) +
             ", " + std::to_string(m.height) + "] reaches outside the " + std::to_string(width) +
             "x" + std::to_string(height) + " frame: give rectangles inside it";
    }
  }
  return "";
}

void ApplyMasks(const std::vector<GoldenMask>& masks, const uint8_t* golden, uint8_t* actual,
                int width, int height) {
  for (const GoldenMask& m : masks) {
    for (int y = m.y; y < std::min(height, m.y + m.height); ++y) {
      const int x1 = std::min(width, m.x + m.width);
      if (x1 <= m.x) continue;
      const size_t at = (static_cast<size_t>(y) * width + m.x) * 3;
      std::copy(golden + at, golden + at + static_cast<size_t>(x1 - m.x) * 3, actual + at);
    }
  }
}

StateComparison CompareStates(const nlohmann::json& golden, const nlohmann::json& actual,
                              double atol) {
  StateComparison out;
  Compare(golden, actual, atol, "", &out);
  return out;
}

}  // namespace fetchscope
