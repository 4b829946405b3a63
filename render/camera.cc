#include "render/camera.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "base/errors.h"
#include "base/suggest.h"

namespace fetchscope {
namespace {

// "accepted: default, track, track:body=..., free:..., a camera named in the model, ..."
const std::string& Accepted() {
  static const std::string text = [] {
    std::string forms;
    for (const CameraKind& kind : CameraKinds()) {
      forms += (forms.empty() ? "" : ", ") + std::string(kind.forms);
    }
    return "accepted: " + forms + ", a camera named in the model, or a comma list of these";
  }();
  return text;
}

// The tracking camera's pose relative to the gripper: close enough to see the fingers and the
// object, from the same side as the default camera.
constexpr double kTrackDistance = 1.0;
constexpr double kTrackAzimuth = 132.0;
constexpr double kTrackElevation = -20.0;

std::vector<std::string> Split(const std::string& s, char sep) {
  std::vector<std::string> parts;
  size_t start = 0;
  while (true) {
    size_t end = s.find(sep, start);
    parts.push_back(s.substr(start, end == std::string::npos ? std::string::npos : end - start));
    if (end == std::string::npos) return parts;
    start = end + 1;
  }
}

bool ParseNumber(const std::string& s, double* value) {
  if (s.empty()) return false;
  char* end = nullptr;
  *value = std::strtod(s.c_str(), &end);
  return *end == '\0' && std::isfinite(*value);
}

std::string ModelCameraNames(const mjModel* model) {
  if (!model || model->ncam == 0) return "this model names none";
  std::string names;
  for (int i = 0; i < model->ncam; ++i) {
    if (i) names += ", ";
    names += mj_id2name(model, mjOBJ_CAMERA, i);
  }
  return names;
}

[[noreturn]] void Fail(const std::string& what) {
  throw UsageError("camera " + what + "; " + Accepted());
}

// Parses the text after "free:" or "track:" (keys and their comma-separated values) into `cam`;
// a track camera takes `body` (the body followed, into *track_body) instead of lookat.
void ParseKeys(const std::string& token, const std::string& body, FreeCamera* out,
               std::string* track_body) {
  FreeCamera& cam = *out;
  bool seen[5] = {false, false, false, false, false};  // lookat, distance, azimuth, elevation, body
  std::vector<std::string> parts = Split(body, ',');
  for (size_t i = 0; i < parts.size(); ++i) {
    size_t eq = parts[i].find('=');
    if (eq == std::string::npos) {
      Fail("'" + token + "': expected key=value, got '" + parts[i] + "'");
    }
    std::string key = parts[i].substr(0, eq);
    std::string value = parts[i].substr(eq + 1);
    int index = key == "lookat" && !track_body ? 0
                : key == "distance"            ? 1
                : key == "azimuth"             ? 2
                : key == "elevation"           ? 3
                : key == "body" && track_body  ? 4
                                               : -1;
    if (index < 0) {
      Fail("'" + token + "': unknown key '" + key + "' (keys: " + (track_body ? "body" : "lookat") +
           ", distance, azimuth, elevation)");
    }
    if (seen[index]) Fail("'" + token + "': key '" + key + "' given twice");
    seen[index] = true;
    if (index == 4) {
      if (value.empty()) Fail("'" + token + "': body needs a body's name");
      *track_body = value;
      continue;
    }
    if (index == 0) {
      // lookat takes this value and the next two parts
      if (i + 2 >= parts.size()) Fail("'" + token + "': lookat needs three numbers x,y,z");
      const std::string xyz[3] = {value, parts[i + 1], parts[i + 2]};
      for (int k = 0; k < 3; ++k) {
        if (!ParseNumber(xyz[k], &cam.lookat[k])) {
          Fail("'" + token + "': lookat needs three numbers x,y,z, got '" + xyz[k] + "'");
        }
      }
      i += 2;
      continue;
    }
    double number = 0;
    if (!ParseNumber(value, &number)) {
      Fail("'" + token + "': " + key + " needs a number, got '" + value + "'");
    }
    if (index == 1) {
      if (number <= 0) Fail("'" + token + "': distance must be > 0, got '" + value + "'");
      cam.distance = number;
    } else if (index == 2) {
      cam.azimuth = number;
    } else {
      if (number < -90 || number > 90) {
        Fail("'" + token + "': elevation must be within -90..90 degrees, got '" + value + "'");
      }
      cam.elevation = number;
    }
  }
}

FreeCamera ParseFree(const std::string& token, const std::string& body) {
  FreeCamera cam = DefaultFreeCamera();
  ParseKeys(token, body, &cam, nullptr);
  return cam;
}

// A track camera's body, checked against the model (where there is one).
void CheckTrackBody(const mjModel* model, const std::string& body) {
  if (!model || mj_name2id(model, mjOBJ_BODY, body.c_str()) >= 0) return;
  std::vector<std::string> bodies;
  for (int i = 0; i < model->nbody; ++i) {
    const char* n = mj_id2name(model, mjOBJ_BODY, i);
    if (n) bodies.push_back(n);
  }
  Fail("'track' follows body " + body + ", which this model lacks" + DidYouMean(body, bodies));
}

CameraSpec ParseOne(const std::string& token, const mjModel* model) {
  CameraSpec spec{CameraSpec::kDefault, token, DefaultFreeCamera()};
  if (token == "default") return spec;
  if (token == "track" || token.rfind("track:", 0) == 0) {
    spec.kind = CameraSpec::kTrack;
    spec.free.distance = kTrackDistance;
    spec.free.azimuth = kTrackAzimuth;
    spec.free.elevation = kTrackElevation;
    if (token != "track") ParseKeys(token, token.substr(6), &spec.free, &spec.body);
    CheckTrackBody(model, spec.body);
    return spec;
  }
  if (token == "free") {
    spec.kind = CameraSpec::kFree;
    return spec;
  }
  if (token.rfind("free:", 0) == 0) {
    spec.kind = CameraSpec::kFree;
    spec.free = ParseFree(token, token.substr(5));
    return spec;
  }
  if (model && mj_name2id(model, mjOBJ_CAMERA, token.c_str()) >= 0) {
    spec.kind = CameraSpec::kNamed;
    return spec;
  }
  std::vector<std::string> names;
  for (const CameraKind& kind : CameraKinds()) names.emplace_back(kind.name);
  for (int i = 0; model && i < model->ncam; ++i)
    names.push_back(mj_id2name(model, mjOBJ_CAMERA, i));
  throw UsageError("camera '" + token + "' is not known" + DidYouMean(token, names) + "; " +
                   Accepted() + " (model cameras: " + ModelCameraNames(model) + ")");
}

}  // namespace

FreeCamera DefaultFreeCamera() { return FreeCamera{{1.3, 0.75, 0.55}, 2.5, 132.0, -14.0}; }

const std::vector<CameraKind>& CameraKinds() {
  static const std::vector<CameraKind> kKinds = {
      {"default", "default", "default",
       "Gymnasium's free camera: distance 2.5, azimuth 132, elevation -14, lookat 1.3 0.75 0.55",
       "default"},
      {"track", "track", "track", "follows robot0:gripper_link",
       "track, track:body=NAME,distance=d,azimuth=a,elevation=e (any subset)"},
      {"free", "free:", "free:...",
       "free:lookat=x,y,z,distance=d,azimuth=a,elevation=e (any subset)",
       "free:lookat=x,y,z,distance=d,azimuth=a,elevation=e (any subset of keys)"},
  };
  return kKinds;
}

std::string CameraText(const CameraSpec& spec) {
  const auto number = [](double v) {
    char text[32];
    std::snprintf(text, sizeof(text), "%.6g", v);
    return std::string(std::strcmp(text, "-0") == 0 ? "0" : text);
  };
  const FreeCamera& f = spec.free;
  const std::string pose = "distance=" + number(f.distance) + ",azimuth=" + number(f.azimuth) +
                           ",elevation=" + number(f.elevation);
  switch (spec.kind) {
    case CameraSpec::kNamed:
      return spec.name;
    case CameraSpec::kDefault:
      return "default";
    case CameraSpec::kTrack:
      if (spec.body == kTrackBody && f.distance == kTrackDistance && f.azimuth == kTrackAzimuth &&
          f.elevation == kTrackElevation) {
        return "track";
      }
      return "track:body=" + spec.body + "," + pose;
    case CameraSpec::kFree:
      break;
  }
  return "free:lookat=" + number(f.lookat[0]) + "," + number(f.lookat[1]) + "," +
         number(f.lookat[2]) + "," + pose;
}

std::vector<CameraSpec> ParseCameraList(const std::string& spec, const mjModel* model) {
  // Regroup the comma-separated parts: a part holding '=' or a bare number continues the free
  // camera before it (its keys and lookat values); anything else, "free..." included, starts
  // a new camera.
  std::vector<std::string> tokens;
  for (const std::string& part : SplitCommaList(spec)) {  // "default, track" as "default,track"
    double unused;
    bool continues = part.rfind("free", 0) != 0 && part.rfind("track", 0) != 0 &&
                     (part.find('=') != std::string::npos || ParseNumber(part, &unused));
    if (continues && !tokens.empty() &&
        (tokens.back().rfind("free:", 0) == 0 || tokens.back().rfind("track:", 0) == 0)) {
      tokens.back() += "," + part;
    } else {
      tokens.push_back(part);
    }
  }
  std::vector<CameraSpec> cameras;
  for (const std::string& token : tokens) {
    if (token.empty()) Fail("list '" + spec + "' has an empty entry");
    cameras.push_back(ParseOne(token, model));
  }
  return cameras;
}

mjvCamera ToMjvCamera(const CameraSpec& spec, const mjModel* model) {
  mjvCamera cam;
  mjv_defaultCamera(&cam);
  switch (spec.kind) {
    case CameraSpec::kNamed:
      cam.type = mjCAMERA_FIXED;
      cam.fixedcamid = mj_name2id(model, mjOBJ_CAMERA, spec.name.c_str());
      if (cam.fixedcamid < 0) {
        throw UsageError("camera '" + spec.name +
                         "' is not in this model (model cameras: " + ModelCameraNames(model) + ")");
      }
      return cam;
    case CameraSpec::kTrack:
      cam.type = mjCAMERA_TRACKING;
      cam.trackbodyid = mj_name2id(model, mjOBJ_BODY, spec.body.c_str());
      if (cam.trackbodyid < 0) {
        throw UsageError("camera 'track' follows body " + spec.body + ", which this model lacks");
      }
      break;
    case CameraSpec::kDefault:
    case CameraSpec::kFree:
      cam.type = mjCAMERA_FREE;
      break;
  }
  for (int k = 0; k < 3; ++k) cam.lookat[k] = spec.free.lookat[k];
  cam.distance = spec.free.distance;
  cam.azimuth = spec.free.azimuth;
  cam.elevation = spec.free.elevation;
  return cam;
}

}  // namespace fetchscope
