// A look's JSON form (render/look.h: LookJson, ParseLookJson). Layout:
//   {"seed": N, "kinds": ["colors", ...],
//    "colors": {"object": [r, g, b, a], ...},
//    "textures": {"table": {"kind": "checker", "rgb1": [..], "rgb2": [..], "scale": S,
//                           "noise_seed": N}, ...},
//    "lights": {"0": {"pos": [..], "dir": [..], "ambient": [..], "diffuse": [..],
//                     "specular": [..]}, ...},
//    "cameras": {"default": {"dpos": [..], "drot": [..], "fovy": F}, ...}}
// Every field of a light and a camera's fovy may be missing (the plain value); maps may be empty.
#include <algorithm>
#include <string>

#include "base/errors.h"
#include "base/json_util.h"
#include "render/look.h"

namespace fetchscope {
namespace {

using nlohmann::json;

template <size_t N>
json Vec(const std::array<double, N>& v) {
  return JsonVector(v.data(), N);
}

[[noreturn]] void Fail(const std::string& where, const std::string& path, const std::string& what) {
  throw UsageError(where + ": " + path + " " + what);
}

void RequireObject(const json& j, const std::string& where, const std::string& path,
                   const std::vector<std::string>& keys) {
  if (!j.is_object()) Fail(where, path, "must be a JSON object");
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (std::find(keys.begin(), keys.end(), it.key()) == keys.end()) {
      std::string list;
      for (const std::string& k : keys) list += (list.empty() ? "" : ", ") + k;
      Fail(where, path + "." + it.key(), "is not a known key; accepted: " + list);
    }
  }
}

double Number(const json& j, const std::string& where, const std::string& path) {
  if (!j.is_number()) Fail(where, path, "must be a number");
  return j.get<double>();
}

template <size_t N>
std::array<double, N> ReadVec(const json& j, const std::string& where, const std::string& path) {
  if (!j.is_array() || j.size() != N) {
    Fail(where, path, "must be an array of " + std::to_string(N) + " numbers");
  }
  std::array<double, N> v{};
  for (size_t k = 0; k < N; ++k) v[k] = Number(j[k], where, path + "[" + std::to_string(k) + "]");
  return v;
}

uint64_t ReadUint64(const json& j, const std::string& where, const std::string& path) {
  if (!j.is_number_unsigned() && !(j.is_number_integer() && j.get<int64_t>() >= 0)) {
    Fail(where, path, "must be a non-negative integer");
  }
  return j.get<uint64_t>();
}

const json& Field(const json& j, const char* key, const std::string& where,
                  const std::string& path) {
  if (!j.contains(key)) Fail(where, path + "." + key, "is missing");
  return j.at(key);
}

SurfaceTexture ReadTexture(const json& j, const std::string& where, const std::string& path) {
  RequireObject(j, where, path, {"kind", "rgb1", "rgb2", "scale", "noise_seed"});
  SurfaceTexture t;
  const json& kind = Field(j, "kind", where, path);
  if (!kind.is_string() || (kind != "checker" && kind != "gradient" && kind != "noise")) {
    Fail(where, path + ".kind", "must be checker, gradient or noise");
  }
  t.kind = kind.get<std::string>();
  t.rgb1 = ReadVec<3>(Field(j, "rgb1", where, path), where, path + ".rgb1");
  t.rgb2 = ReadVec<3>(Field(j, "rgb2", where, path), where, path + ".rgb2");
  t.scale = Number(Field(j, "scale", where, path), where, path + ".scale");
  t.noise_seed = ReadUint64(Field(j, "noise_seed", where, path), where, path + ".noise_seed");
  return t;
}

LightLook ReadLight(const json& j, const std::string& where, const std::string& path) {
  RequireObject(j, where, path, {"pos", "dir", "ambient", "diffuse", "specular"});
  LightLook l;
  const auto opt = [&](const char* key, std::optional<std::array<double, 3>>* out) {
    if (j.contains(key)) *out = ReadVec<3>(j.at(key), where, path + "." + key);
  };
  opt("pos", &l.pos);
  opt("dir", &l.dir);
  opt("ambient", &l.ambient);
  opt("diffuse", &l.diffuse);
  opt("specular", &l.specular);
  return l;
}

CameraJitter ReadCamera(const json& j, const std::string& where, const std::string& path) {
  RequireObject(j, where, path, {"dpos", "drot", "fovy"});
  CameraJitter c;
  if (j.contains("dpos")) c.dpos = ReadVec<3>(j.at("dpos"), where, path + ".dpos");
  if (j.contains("drot")) c.drot = ReadVec<3>(j.at("drot"), where, path + ".drot");
  if (j.contains("fovy")) c.fovy = Number(j.at("fovy"), where, path + ".fovy");
  return c;
}

}  // namespace

json LookJson(const LookDraw& draw) {
  json kinds = json::array();
  const bool on[] = {draw.colors, draw.textures, draw.lighting, draw.camera};
  for (size_t k = 0; k < 4; ++k) {
    if (on[k]) kinds.push_back(kLookKinds[k]);
  }
  json colors = json::object(), textures = json::object(), lights = json::object(),
       cameras = json::object();
  for (const auto& [part, rgba] : draw.colors_by_part) colors[part] = Vec(rgba);
  for (const auto& [surface, t] : draw.textures_by_surface) {
    textures[surface] = {{"kind", t.kind},
                         {"rgb1", Vec(t.rgb1)},
                         {"rgb2", Vec(t.rgb2)},
                         {"scale", JsonDouble(t.scale)},
                         {"noise_seed", t.noise_seed}};
  }
  for (const auto& [id, l] : draw.lights) {
    json o = json::object();
    if (l.pos) o["pos"] = Vec(*l.pos);
    if (l.dir) o["dir"] = Vec(*l.dir);
    if (l.ambient) o["ambient"] = Vec(*l.ambient);
    if (l.diffuse) o["diffuse"] = Vec(*l.diffuse);
    if (l.specular) o["specular"] = Vec(*l.specular);
    lights[std::to_string(id)] = o;
  }
  for (const auto& [key, c] : draw.cameras) {
    json o = {{"dpos", Vec(c.dpos)}, {"drot", Vec(c.drot)}};
    if (c.fovy) o["fovy"] = JsonDouble(*c.fovy);
    cameras[key] = o;
  }
  return {{"seed", draw.seed},    {"kinds", kinds},   {"colors", colors},
          {"textures", textures}, {"lights", lights}, {"cameras", cameras}};
}

LookDraw ParseLookJson(const json& j, const std::string& where) {
  RequireObject(j, where, "look", {"seed", "kinds", "colors", "textures", "lights", "cameras"});
  LookDraw d;
  d.seed = ReadUint64(Field(j, "seed", where, "look"), where, "look.seed");
  const json& kinds = Field(j, "kinds", where, "look");
  if (!kinds.is_array()) Fail(where, "look.kinds", "must be an array of kinds");
  for (const json& k : kinds) {
    const std::string name = k.is_string() ? k.get<std::string>() : "";
    if (name == "colors")
      d.colors = true;
    else if (name == "textures")
      d.textures = true;
    else if (name == "lighting")
      d.lighting = true;
    else if (name == "camera")
      d.camera = true;
    else
      Fail(where, "look.kinds",
           "holds " + k.dump() + "; accepted: colors, textures, lighting, camera");
  }
  const auto each = [&](const char* key, auto&& read) {
    if (!j.contains(key)) return;
    const json& m = j.at(key);
    const std::string path = std::string("look.") + key;
    if (!m.is_object()) Fail(where, path, "must be a JSON object");
    for (auto it = m.begin(); it != m.end(); ++it)
      read(it.key(), it.value(), path + "." + it.key());
  };
  each("colors", [&](const std::string& k, const json& v, const std::string& p) {
    d.colors_by_part[k] = ReadVec<4>(v, where, p);
  });
  each("textures", [&](const std::string& k, const json& v, const std::string& p) {
    d.textures_by_surface[k] = ReadTexture(v, where, p);
  });
  each("lights", [&](const std::string& k, const json& v, const std::string& p) {
    const bool digits = !k.empty() && k.size() < 9 && std::all_of(k.begin(), k.end(), [](char c) {
      return c >= '0' && c <= '9';
    });
    if (!digits) Fail(where, p, "is not a light id (a non-negative integer)");
    d.lights[std::stoi(k)] = ReadLight(v, where, p);
  });
  each("cameras", [&](const std::string& k, const json& v, const std::string& p) {
    d.cameras[k] = ReadCamera(v, where, p);
  });
  return d;
}

}  // namespace fetchscope
