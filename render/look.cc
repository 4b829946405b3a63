// Randomized looks: --randomize and --randomize-config parsing, the seed rule, the draw and
// the object's contrast rule (render/look.h). The JSON form of a draw is in look_json.cc.
#include "render/look.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "base/confined_file.h"
#include "base/errors.h"
#include "base/json_util.h"
#include "base/suggest.h"
#include "src/rng.h"

namespace fetchscope {
namespace {

std::string JoinList(const std::vector<std::string>& items) {
  std::string out;
  for (size_t i = 0; i < items.size(); ++i) out += (i ? ", " : "") + items[i];
  return out;
}

uint64_t SplitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// FNV-1a: a camera key's own stream.
uint64_t HashText(const std::string& text) {
  uint64_t h = 0xCBF29CE484222325ull;
  for (unsigned char c : text) h = (h ^ c) * 0x100000001B3ull;
  return h;
}

// The seed of one kind's stream within a look.
uint64_t StreamSeed(uint64_t seed, uint64_t tag) { return SplitMix64(SplitMix64(seed) ^ tag); }

constexpr uint64_t kTagColors = 0x636F6C6F7273ull;    // "colors"
constexpr uint64_t kTagTextures = 0x74657874ull;      // "text"
constexpr uint64_t kTagLights = 0x6C69676874ull;      // "light"
constexpr uint64_t kTagCamera = 0x63616D657261ull;    // "camera"
constexpr uint64_t kTagLook = 0x6C6F6F6B2D736565ull;  // "look-see"

double Draw(NumpyGenerator& g, const LookRange& r) { return g.Uniform(r.min, r.max); }

std::array<double, 3> DrawRgb(NumpyGenerator& g, const LookRange& r) {
  return {Draw(g, r), Draw(g, r), Draw(g, r)};
}

double Clamp01(double v) { return std::min(1.0, std::max(0.0, v)); }

// A unit axis uniform on the sphere.
std::array<double, 3> DrawAxis(NumpyGenerator& g) {
  const double z = g.Uniform(-1.0, 1.0), phi = g.Uniform(0.0, 2.0 * mjPI);
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

struct RangeField {
  const char* key;
  LookRange LookConfig::*member;
};

constexpr RangeField kRangeFields[] = {
    {"color_rgb", &LookConfig::color_rgb},
    {"texture_rgb", &LookConfig::texture_rgb},
    {"texture_scale", &LookConfig::texture_scale},
    {"light_pos", &LookConfig::light_pos},
    {"light_dir_angle", &LookConfig::light_dir_angle},
    {"light_ambient", &LookConfig::light_ambient},
    {"light_diffuse", &LookConfig::light_diffuse},
    {"light_specular", &LookConfig::light_specular},
    {"camera_pos", &LookConfig::camera_pos},
    {"camera_angle", &LookConfig::camera_angle},
    {"camera_fovy", &LookConfig::camera_fovy},
};

}  // namespace

bool SurfaceTexture::operator==(const SurfaceTexture& o) const {
  return kind == o.kind && rgb1 == o.rgb1 && rgb2 == o.rgb2 && scale == o.scale &&
         noise_seed == o.noise_seed;
}

LookConfig ParseRandomize(const std::string& list) {
  LookConfig config;
  const std::string trimmed = TrimSpaces(list);
  if (trimmed.empty() || trimmed == "none") return config;
  std::vector<std::string> accepted(std::begin(kLookKinds), std::end(kLookKinds));
  const std::string accepted_text = JoinList(accepted) + " (a comma list), or none";
  bool seen[4] = {false, false, false, false};
  for (const std::string& raw : SplitCommaList(list)) {
    const std::string token = TrimSpaces(raw);
    const auto it = std::find(accepted.begin(), accepted.end(), token);
    if (it == accepted.end()) {
      const std::string what = token.empty() ? "an empty entry" : "'" + token + "'";
      throw UsageError("--randomize: " + what + " is not a kind" + DidYouMean(token, accepted) +
                       "; accepted: " + accepted_text);
    }
    const size_t k = static_cast<size_t>(it - accepted.begin());
    if (seen[k]) throw UsageError("--randomize: '" + token + "' is listed twice");
    seen[k] = true;
  }
  config.colors = seen[0];
  config.textures = seen[1];
  config.lighting = seen[2];
  config.camera = seen[3];
  return config;
}

std::vector<std::string> LookConfigKeys() {
  std::vector<std::string> keys = {"robot_colors"};
  for (const RangeField& f : kRangeFields) keys.emplace_back(f.key);
  return keys;
}

void ApplyLookConfig(const nlohmann::json& doc, const std::string& where, LookConfig* config) {
  if (!doc.is_object()) throw UsageError(where + ": expected a JSON object of ranges");
  LookConfig out = *config;
  for (auto it = doc.begin(); it != doc.end(); ++it) {
    const std::string& key = it.key();
    const nlohmann::json& v = it.value();
    if (key == "robot_colors") {
      if (!v.is_boolean()) throw UsageError(where + ": robot_colors must be true or false");
      out.robot_colors = v.get<bool>();
      continue;
    }
    const RangeField* field = nullptr;
    for (const RangeField& f : kRangeFields) {
      if (key == f.key) field = &f;
    }
    if (!field) {
      throw UsageError(where + ": unknown key '" + key + "'" + DidYouMean(key, LookConfigKeys()) +
                       "; accepted: " + JoinList(LookConfigKeys()));
    }
    const bool pair = v.is_array() && v.size() == 2 && v[0].is_number() && v[1].is_number();
    if (!pair || !std::isfinite(v[0].get<double>()) || !std::isfinite(v[1].get<double>())) {
      throw UsageError(where + ": " + key + " must be a pair of numbers [min, max]");
    }
    const LookRange r{v[0].get<double>(), v[1].get<double>()};
    if (r.min > r.max) {
      throw UsageError(where + ": range " + key + " has min " + FormatDouble(r.min) + " > max " +
                       FormatDouble(r.max) + "; accepted: min <= max");
    }
    out.*(field->member) = r;
  }
  const auto check_within = [&](const char* key, const LookRange& r, double lo, double hi) {
    if (r.min < lo || r.max > hi) {
      throw UsageError(where + ": range " + key + " [" + FormatDouble(r.min) + ", " +
                       FormatDouble(r.max) + "] leaves [" + FormatDouble(lo) + ", " +
                       FormatDouble(hi) + "]; accepted: within it");
    }
  };
  check_within("color_rgb", out.color_rgb, 0, 1);
  check_within("texture_rgb", out.texture_rgb, 0, 1);
  check_within("texture_scale", out.texture_scale, 0.01, 1000);
  check_within("light_dir_angle", out.light_dir_angle, 0, mjPI);
  check_within("camera_angle", out.camera_angle, 0, mjPI);
  check_within("camera_fovy", out.camera_fovy, -170, 170);
  *config = out;
}

void ReadLookConfig(const std::string& path, LookConfig* config) {
  const std::string where = "--randomize-config '" + path + "'";
  const std::string text = ReadFileCapped(path, uint64_t{1} << 20);
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw UsageError(where + ": " + DescribeJsonError(e, text.size()));
  }
  ApplyLookConfig(doc, where, config);
}

uint64_t LookSeed(uint64_t seed, int episode) {
  return SplitMix64(SplitMix64(seed ^ kTagLook) + static_cast<uint64_t>(episode));
}

double RelativeLuminance(const std::array<double, 3>& rgb) {
  const auto lin = [](double c) {
    c = Clamp01(c);
    return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
  };
  return 0.2126 * lin(rgb[0]) + 0.7152 * lin(rgb[1]) + 0.0722 * lin(rgb[2]);
}

namespace {

// The plain rgb of a named geom (its material's colour where it has one), or of the first geom
// of a named body; grey when the model lacks both.
std::array<double, 3> PlainRgb(const mjModel* model, const char* geom, const char* body) {
  int id = mj_name2id(model, mjOBJ_GEOM, geom);
  if (id < 0) {
    const int b = mj_name2id(model, mjOBJ_BODY, body);
    for (int i = 0; b >= 0 && i < model->ngeom && id < 0; ++i) {
      if (model->geom_bodyid[i] == b) id = i;
    }
  }
  if (id < 0) return {0.5, 0.5, 0.5};
  const int mat = model->geom_matid[id];
  const float* c = mat >= 0 ? model->mat_rgba + 4 * mat : model->geom_rgba + 4 * id;
  return {c[0], c[1], c[2]};
}

std::array<double, 3> Times(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return {a[0] * b[0], a[1] * b[1], a[2] * b[2]};
}

}  // namespace

double ObjectContrast(const LookDraw& draw, const mjModel* model) {
  std::array<double, 3> object = PlainRgb(model, "object0", "object0");
  std::array<double, 3> table = PlainRgb(model, "table0", "table0");
  if (auto it = draw.colors_by_part.find("object"); it != draw.colors_by_part.end()) {
    object = {it->second[0], it->second[1], it->second[2]};
  }
  if (auto it = draw.colors_by_part.find("table"); it != draw.colors_by_part.end()) {
    table = {it->second[0], it->second[1], it->second[2]};
  }
  std::vector<std::array<double, 3>> shown = {table};
  if (auto it = draw.textures_by_surface.find("table"); it != draw.textures_by_surface.end()) {
    // a textured surface shows its rgba times the texture's texels (white rgb when colours
    // are off: see Renderer::SetLook)
    const bool coloured = draw.colors_by_part.count("table") > 0;
    const std::array<double, 3> base = coloured ? table : std::array<double, 3>{1, 1, 1};
    shown = {Times(base, it->second.rgb1), Times(base, it->second.rgb2)};
  }
  const double lo = RelativeLuminance(object);
  double contrast = 1.0;
  for (const auto& c : shown) contrast = std::min(contrast, std::fabs(lo - RelativeLuminance(c)));
  return contrast;
}

namespace {

void DrawColours(const LookConfig& config, NumpyGenerator& g, const mjModel* model,
                 LookDraw* draw) {
  const auto rgba = [&] {
    const std::array<double, 3> c = DrawRgb(g, config.color_rgb);
    return std::array<double, 4>{c[0], c[1], c[2], 1.0};
  };
  for (const char* part : {"object", "table", "floor"}) draw->colors_by_part[part] = rgba();
  if (!config.robot_colors) return;
  for (int b = 0; b < model->nbody; ++b) {
    const char* name = mj_id2name(model, mjOBJ_BODY, b);
    if (name && std::string(name).rfind("robot0:", 0) == 0) draw->colors_by_part[name] = rgba();
  }
}

void DrawTextures(const LookConfig& config, NumpyGenerator& g, LookDraw* draw) {
  static const char* const kKinds[] = {"checker", "gradient", "noise"};
  for (const char* surface : {"table", "floor"}) {
    SurfaceTexture t;
    t.kind = kKinds[std::min<int>(2, static_cast<int>(g.NextDouble() * 3))];
    t.rgb1 = DrawRgb(g, config.texture_rgb);
    t.rgb2 = DrawRgb(g, config.texture_rgb);
    t.scale = Draw(g, config.texture_scale);
    t.noise_seed = g.NextUint64();
    draw->textures_by_surface[surface] = t;
  }
}

// Turns unit vector `v` by `angle` about a random axis perpendicular to it.
std::array<double, 3> TurnBy(const std::array<double, 3>& v, double angle, NumpyGenerator& g) {
  const std::array<double, 3> a = DrawAxis(g);
  double p[3] = {a[1] * v[2] - a[2] * v[1], a[2] * v[0] - a[0] * v[2], a[0] * v[1] - a[1] * v[0]};
  if (mju_normalize3(p) < 1e-9) return v;  // axis along v: leave it (measure zero)
  const double c = std::cos(angle), s = std::sin(angle);
  // p is perpendicular to v: Rodrigues' formula reduces to v cos + (p x v) sin
  const double pxv[3] = {p[1] * v[2] - p[2] * v[1], p[2] * v[0] - p[0] * v[2],
                         p[0] * v[1] - p[1] * v[0]};
  std::array<double, 3> out = {c * v[0] + s * pxv[0], c * v[1] + s * pxv[1], c * v[2] + s * pxv[2]};
  mju_normalize3(out.data());
  return out;
}

void DrawLights(const LookConfig& config, NumpyGenerator& g, const mjModel* model, LookDraw* draw) {
  for (int i = 0; i < model->nlight; ++i) {
    LightLook l;
    std::array<double, 3> pos, dir, amb, dif, spec;
    for (int k = 0; k < 3; ++k) pos[k] = model->light_pos[3 * i + k] + Draw(g, config.light_pos);
    for (int k = 0; k < 3; ++k) dir[k] = model->light_dir[3 * i + k];
    mju_normalize3(dir.data());
    dir = TurnBy(dir, Draw(g, config.light_dir_angle), g);
    for (int k = 0; k < 3; ++k) {
      amb[k] = Clamp01(model->light_ambient[3 * i + k] + Draw(g, config.light_ambient));
    }
    for (int k = 0; k < 3; ++k) {
      dif[k] = Clamp01(model->light_diffuse[3 * i + k] + Draw(g, config.light_diffuse));
    }
    for (int k = 0; k < 3; ++k) {
      spec[k] = Clamp01(model->light_specular[3 * i + k] + Draw(g, config.light_specular));
    }
    l.pos = pos;
    l.dir = dir;
    l.ambient = amb;
    l.diffuse = dif;
    l.specular = spec;
    draw->lights[i] = l;
  }
}

// The fovy a view's camera has without a look: a model camera's own, else the free camera's.
double BaseFovy(const std::string& key, const mjModel* model) {
  const int id = mj_name2id(model, mjOBJ_CAMERA, key.c_str());
  return id >= 0 ? model->cam_fovy[id] : model->vis.global.fovy;
}

void DrawCameras(const LookConfig& config, uint64_t seed, const std::vector<std::string>& keys,
                 const mjModel* model, LookDraw* draw) {
  for (const std::string& key : keys) {
    NumpyGenerator g(StreamSeed(seed, kTagCamera ^ HashText(key)));
    CameraJitter j;
    for (int k = 0; k < 3; ++k) j.dpos[k] = Draw(g, config.camera_pos);
    const std::array<double, 3> axis = DrawAxis(g);
    const double angle = Draw(g, config.camera_angle);
    for (int k = 0; k < 3; ++k) j.drot[k] = axis[k] * angle;
    const double fovy = BaseFovy(key, model) + Draw(g, config.camera_fovy);
    j.fovy = std::min(170.0, std::max(1.0, fovy));
    draw->cameras[key] = j;
  }
}

// The contrast fallback (see DrawLook in look.h).
void ContrastFallback(const mjModel* model, LookDraw* draw) {
  const bool coloured = draw->colors_by_part.count("object") > 0;
  if (!coloured) {
    draw->textures_by_surface.erase("table");
    return;
  }
  std::array<double, 4>& object = draw->colors_by_part["object"];
  object = {0, 0, 0, 1};
  const double black = ObjectContrast(*draw, model);
  object = {1, 1, 1, 1};
  if (black > ObjectContrast(*draw, model)) object = {0, 0, 0, 1};
  if (ObjectContrast(*draw, model) >= kMinObjectContrast) return;
  auto it = draw->textures_by_surface.find("table");
  if (it != draw->textures_by_surface.end()) it->second.rgb2 = it->second.rgb1;
  object = {0, 0, 0, 1};
  const double solid_black = ObjectContrast(*draw, model);
  object = {1, 1, 1, 1};
  if (solid_black > ObjectContrast(*draw, model)) object = {0, 0, 0, 1};
}

}  // namespace

LookDraw DrawLook(const LookConfig& config, uint64_t seed,
                  const std::vector<std::string>& camera_keys, const mjModel* model) {
  LookDraw draw;
  draw.seed = seed;
  draw.colors = config.colors;
  draw.textures = config.textures;
  draw.lighting = config.lighting;
  draw.camera = config.camera;
  if (config.colors || config.textures) {
    NumpyGenerator colours(StreamSeed(seed, kTagColors));
    NumpyGenerator textures(StreamSeed(seed, kTagTextures));
    bool ok = false;
    for (int attempt = 0; attempt < kLookContrastTries && !ok; ++attempt) {
      draw.colors_by_part.clear();
      draw.textures_by_surface.clear();
      if (config.colors) DrawColours(config, colours, model, &draw);
      if (config.textures) DrawTextures(config, textures, &draw);
      ok = ObjectContrast(draw, model) >= kMinObjectContrast;
    }
    if (!ok) ContrastFallback(model, &draw);
  }
  if (config.lighting) {
    NumpyGenerator g(StreamSeed(seed, kTagLights));
    DrawLights(config, g, model, &draw);
  }
  if (config.camera) DrawCameras(config, seed, camera_keys, model, &draw);
  return draw;
}

std::vector<uint8_t> TexturePixels(const SurfaceTexture& texture, int size) {
  std::vector<uint8_t> out(static_cast<size_t>(size) * size * 3);
  uint64_t noise = texture.noise_seed;
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      double t = 0;  // 0: rgb1, 1: rgb2
      if (texture.kind == "checker") {
        t = ((2 * x / size) + (2 * y / size)) % 2 == 0 ? 0.0 : 1.0;
      } else if (texture.kind == "gradient") {
        t = static_cast<double>(y) / std::max(1, size - 1);
      } else {
        noise = SplitMix64(noise);
        t = static_cast<double>(noise >> 11) * 0x1.0p-53;
      }
      uint8_t* p = &out[(static_cast<size_t>(y) * size + x) * 3];
      for (int k = 0; k < 3; ++k) {
        const double c = (1 - t) * texture.rgb1[k] + t * texture.rgb2[k];
        p[k] = static_cast<uint8_t>(std::lround(255.0 * Clamp01(c)));
      }
    }
  }
  return out;
}

}  // namespace fetchscope
