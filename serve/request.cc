#include "serve/request.h"

#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <set>
#include <vector>

#include "base/errors.h"
#include "render/frame_limits.h"

namespace fetchscope::serve {
namespace {

[[noreturn]] void Bad(const std::string& message, int status = 400) {
  throw RequestError(status, message);
}

// The parameters of one request: every name known to it, none repeated, no value too long.
class Params {
 public:
  Params(const Query& query, std::initializer_list<const char*> accepted) : query_(query) {
    std::set<std::string> known = {"session", "token"};
    for (const char* name : accepted) known.insert(name);
    for (auto it = query.begin(); it != query.end(); ++it) {
      if (!known.count(it->first)) {
        std::string list;
        for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
        Bad("unknown parameter '" + Printable(it->first) + "'; accepted: " + list);
      }
      if (query.count(it->first) > 1) Bad("parameter '" + it->first + "' is given twice");
      if (it->second.size() > kMaxParameterBytes) {
        Bad("parameter '" + it->first + "' is " + std::to_string(it->second.size()) +
                " bytes long; accepted: at most " + std::to_string(kMaxParameterBytes),
            413);
      }
    }
  }

  const std::string* Find(const char* name) const {
    const auto it = query_.find(name);
    return it == query_.end() ? nullptr : &it->second;
  }

  std::string Text(const char* name, const std::string& fallback) const {
    const std::string* v = Find(name);
    return v ? *v : fallback;
  }

  // A whole number within [low, high]; `fallback` where absent (nullopt: required).
  int Int(const char* name, int low, int high, std::optional<int> fallback) const {
    const std::string* v = Find(name);
    if (!v) {
      if (!fallback) Bad("parameter '" + std::string(name) + "' is missing");
      return *fallback;
    }
    const std::string& s = *v;
    const size_t digits_at = !s.empty() && s[0] == '-' ? 1 : 0;
    bool whole = s.size() > digits_at && s.size() - digits_at <= 9;
    for (size_t i = digits_at; whole && i < s.size(); ++i) whole = s[i] >= '0' && s[i] <= '9';
    if (!whole) {
      Bad("parameter " + std::string(name) + " '" + Printable(s) +
          "' is not a whole number; accepted: " + Range(low, high));
    }
    const long value = std::strtol(s.c_str(), nullptr, 10);
    if (value < low || value > high) {
      Bad("parameter " + std::string(name) + " " + s +
          " is out of range; accepted: " + Range(low, high));
    }
    return static_cast<int>(value);
  }

  // One of `choices`; the first where absent.
  int Choice(const char* name, const std::vector<const char*>& choices) const {
    const std::string* v = Find(name);
    if (!v) return 0;
    std::string list;
    for (size_t i = 0; i < choices.size(); ++i) {
      if (*v == choices[i]) return static_cast<int>(i);
      list += (i ? ", " : "") + std::string(choices[i]);
    }
    Bad("parameter " + std::string(name) + " '" + Printable(*v) +
        "' is not known; accepted: " + list);
  }

  // A value as a message may quote it: control characters and non-ASCII bytes as '?', cut at 80.
  static std::string Printable(const std::string& s) {
    std::string out;
    for (char c : s.substr(0, 80)) out += (c >= 0x20 && c < 0x7f) ? c : '?';
    return s.size() > 80 ? out + "..." : out;
  }

 private:
  static std::string Range(int low, int high) {
    return std::to_string(low) + ".." + std::to_string(high);
  }
  const Query& query_;
};

StepRef ParseStepRef(const Params& p) {
  StepRef at;
  const std::string source = p.Text("source", "");
  if (source == "live") {
    at.source = kLiveSource;
  } else {
    at.source = p.Int("source", 0, 9999, std::nullopt);
    at.episode = p.Int("episode", 0, 99999999, std::nullopt);
  }
  at.step = p.Int("t", 0, 100000, 0);
  return at;
}

ViewRequest ParseView(const Params& p) {
  ViewRequest v;
  v.at = ParseStepRef(p);
  v.camera = p.Text("camera", v.camera);
  if (v.camera.empty()) Bad("parameter camera is empty; accepted: a --camera value");
  v.width = p.Int("width", 1, kMaxFrameSideLive, v.width);
  v.height = p.Int("height", 1, kMaxFrameSideLive, v.height);
  if (static_cast<int64_t>(v.width) * v.height > kMaxFramePixels) {
    Bad("frame " + std::to_string(v.width) + "x" + std::to_string(v.height) +
            " is too large; accepted: at most " + std::to_string(kMaxFramePixels) +
            " pixels (as render)",
        413);
  }
  v.overlay_text = p.Text("overlay", v.overlay_text);
  try {
    v.overlays = ParseOverlays(v.overlay_text);
  } catch (const UsageError& e) {
    Bad(std::string("parameter overlay: ") + e.what());
  }
  v.layer = static_cast<Layer>(p.Choice("layer", {"rgb", "depth", "segmentation"}));
  v.format = static_cast<ImageFormat>(p.Choice("format", {"jpeg", "png"}));
  v.quality = p.Int("quality", 1, 100, v.quality);
  v.look = p.Text("look", "");
  const bool digits = !v.look.empty() && v.look.size() <= 18 &&
                      v.look.find_first_not_of("0123456789") == std::string::npos;
  if (!v.look.empty() && v.look != "plain" && v.look != "recorded" && !digits) {
    Bad("parameter look '" + Params::Printable(v.look) +
        "' is not a look; accepted: plain, recorded, or a draw's seed (0..10^18)");
  }
  return v;
}

constexpr std::initializer_list<const char*> kViewNames = {"source", "episode", "t",       "camera",
                                                           "width",  "height",  "overlay", "layer",
                                                           "format", "quality", "look"};

}  // namespace

std::string SessionParam(const Query& query) {
  const auto it = query.find("session");
  if (it == query.end()) Bad("parameter 'session' is missing");
  if (query.count("session") > 1) Bad("parameter 'session' is given twice");
  return it->second;
}

ViewRequest ParseViewRequest(const Query& query) { return ParseView(Params(query, kViewNames)); }

PickRequest ParsePickRequest(const Query& query) {
  const Params p(query, {"source", "episode", "t", "camera", "width", "height", "overlay", "layer",
                         "format", "quality", "look", "x", "y"});
  PickRequest pick;
  pick.view = ParseView(p);
  pick.x = p.Int("x", 0, pick.view.width - 1, std::nullopt);
  pick.y = p.Int("y", 0, pick.view.height - 1, std::nullopt);
  return pick;
}

void CheckNoParameters(const Query& query) { Params(query, {}); }

StepRequest ParseStepRequest(const Query& query) {
  const Params p(query, {"action"});
  StepRequest r;
  const std::string* text = p.Find("action");
  if (!text) return r;  // the policy acts
  std::array<double, 4> a{};
  size_t at = 0;
  for (int i = 0; i < 4; ++i) {
    const size_t comma = text->find(',', at);
    const std::string part = text->substr(at, comma == std::string::npos ? comma : comma - at);
    char* end = nullptr;
    a[i] = std::strtod(part.c_str(), &end);
    const bool number = !part.empty() && end && *end == '\0' && std::isfinite(a[i]);
    if (!number || (comma == std::string::npos) != (i == 3)) {
      Bad("parameter action '" + Params::Printable(*text) +
          "' is not 4 comma-separated numbers; accepted: dx,dy,dz,gripper each within -1..1");
    }
    if (a[i] < -1 || a[i] > 1) {
      Bad("parameter action '" + Params::Printable(*text) + "': " + part +
          " is out of range; accepted: dx,dy,dz,gripper each within -1..1");
    }
    at = comma + 1;
  }
  r.action = a;
  return r;
}

namespace {

// The comma-separated finite numbers of parameter `name`, `low` to `high` of them.
std::vector<double> Coordinates(const Params& p, const char* name, size_t low, size_t high) {
  const std::string& text = *p.Find(name);
  const std::string accepted = std::string("; accepted: ") +
                               (low == high ? "x,y,z" : "x,y or x,y,z") +
                               ", metres in world coordinates";
  std::vector<double> out;
  size_t at = 0;
  while (true) {
    const size_t comma = text.find(',', at);
    const std::string part = text.substr(at, comma == std::string::npos ? comma : comma - at);
    char* end = nullptr;
    const double v = std::strtod(part.c_str(), &end);
    if (part.empty() || !end || *end != '\0' || !std::isfinite(v) || out.size() == high) {
      Bad("parameter " + std::string(name) + " '" + Params::Printable(text) + "' is not " +
          std::to_string(low) + (low == high ? "" : " or " + std::to_string(high)) +
          " comma-separated finite numbers" + accepted);
    }
    out.push_back(v);
    if (comma == std::string::npos) break;
    at = comma + 1;
  }
  if (out.size() < low) {
    Bad("parameter " + std::string(name) + " '" + Params::Printable(text) + "' has " +
        std::to_string(out.size()) + " numbers" + accepted);
  }
  return out;
}

}  // namespace

StartRequest ParseStartRequest(const Query& query) {
  const Params p(query, {"env", "source", "episode", "t", "goal", "object"});
  StartRequest r;
  if (p.Find("env")) {
    if (p.Find("source") || p.Find("episode") || p.Find("t")) {
      Bad("parameter env starts a live env from its reset: give it alone, or source, episode "
          "and t to continue a served episode");
    }
    r.env = p.Int("env", 0, 9999, std::nullopt);
    if (p.Find("goal")) {
      const std::vector<double> g = Coordinates(p, "goal", 3, 3);
      r.goal = std::array<double, 3>{g[0], g[1], g[2]};
    }
    if (p.Find("object")) r.object = Coordinates(p, "object", 2, 3);
    return r;
  }
  if (p.Find("goal") || p.Find("object")) {
    Bad("parameters goal and object place a live env's reset: give them with env, not with a "
        "served episode's step");
  }
  r.from = ParseStepRef(p);
  if (r.from.source == kLiveSource) Bad("parameter source 'live': continue from a served episode");
  return r;
}

int ParseSourceRequest(const Query& query) {
  const Params p(query, {"source"});
  return p.Int("source", 0, 9999, std::nullopt);
}

StepRef ParseEpisodeRequest(const Query& query) {
  const Params p(query, {"source", "episode"});
  StepRef at;
  at.source = p.Int("source", 0, 9999, std::nullopt);
  at.episode = p.Int("episode", 0, 99999999, std::nullopt);
  return at;
}

}  // namespace fetchscope::serve
