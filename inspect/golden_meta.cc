#include "inspect/golden_meta.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include "base/errors.h"
#include "src/observation_layout.h"
#include "src/versions.h"

namespace fetchscope {
namespace {

// A number of the state with its label and unit.
struct Quantity {
  std::string label;
  std::string unit;  // "m", "m/step", "rad", "rad/step" or ""
};

const char* const kAxes[3] = {"x", "y", "z"};

// The label and unit of member `key`[i] of a step row whose observation has `obs_size` numbers;
// empty label for one to leave out (achieved_goal repeats grip_pos or object_pos).
Quantity Label(const std::string& key, size_t i, size_t obs_size) {
  if (key == "observation") {
    if (const std::optional<bool> object = LayoutHasObject(obs_size)) {
      const std::vector<LayoutLabel>& labels = ObservationLabels(*object);
      if (i < labels.size()) return {labels[i].name, labels[i].unit};
    }
    return {"observation[" + std::to_string(i) + "]", ""};
  }
  if (key == "achieved_goal") return {"", ""};
  if (key == "desired_goal") return {"desired_goal." + std::string(i < 3 ? kAxes[i] : "?"), "m"};
  if (key == "action") return {"action[" + std::to_string(i) + "]", ""};
  return {key, ""};
}

std::string FormatDelta(double d, const std::string& unit) {
  char buf[64];
  if (unit == "m" || unit == "m/step") {
    std::snprintf(buf, sizeof(buf), "%+.2f mm%s", d * 1000, unit == "m" ? "" : "/step");
  } else if (unit == "rad" || unit == "rad/step") {
    std::snprintf(buf, sizeof(buf), "%+.2f mrad%s", d * 1000, unit == "rad" ? "" : "/step");
  } else {
    std::snprintf(buf, sizeof(buf), "%+.3g", d);
  }
  return buf;
}

GoldenTolerance ParseExplicit(const std::string& text) {
  const std::string accepted =
      "; accepted: auto, same, cross, or threshold=N[,max_fraction=F][,max_rms=R]";
  GoldenTolerance t;
  std::stringstream ss(text);
  bool threshold = false;
  for (std::string part; std::getline(ss, part, ',');) {
    const size_t eq = part.find('=');
    const std::string key = part.substr(0, eq);
    const std::string value = eq == std::string::npos ? "" : part.substr(eq + 1);
    char* end = nullptr;
    const double v = std::strtod(value.c_str(), &end);
    if (value.empty() || *end != '\0' || !(v >= 0) || !std::isfinite(v)) {
      throw UsageError("--tolerance '" + text + "': '" + part +
                       "' needs a non-negative number after '='" + accepted);
    }
    if (key == "threshold") {
      if (v > 255 || v != std::floor(v)) {
        throw UsageError("--tolerance '" + text + "': threshold must be an integer 0..255");
      }
      t.threshold = static_cast<int>(v);
      threshold = true;
    } else if (key == "max_fraction") {
      t.max_fraction = v;
    } else if (key == "max_rms") {
      t.max_rms = v;
    } else {
      throw UsageError("--tolerance '" + text + "': unknown member '" + key + "'" + accepted);
    }
  }
  if (!threshold) {
    throw UsageError("--tolerance '" + text + "': explicit numbers need threshold=N" + accepted);
  }
  return t;
}

}  // namespace

nlohmann::json GoldenMetaJson(const GoldenScene& scene, const SceneResult& result,
                              const GlInfo& gl) {
  return {{"backend", gl.backend},
          {"gl_renderer", gl.renderer},
          {"versions", VersionsJson()},
          {"assets_sha256", result.assets_sha256},
          {"msaa", {{"asked", scene.msaa}, {"used", result.msaa_used}}},
          {"segmentation_sha256", result.segmentation_sha256}};
}

nlohmann::json ReadGoldenMeta(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return nullptr;
  std::stringstream text;
  text << in.rdbuf();
  const nlohmann::json meta = nlohmann::json::parse(text.str(), nullptr, false);
  if (!meta.is_object()) {
    throw RunError("golden meta '" + path +
                   "' is not a JSON object: remove it, or run golden update to write it again");
  }
  return meta;
}

std::string MadeOn(const nlohmann::json& meta) {
  if (!meta.is_object() || !meta.contains("backend") || !meta.contains("gl_renderer") ||
      !meta["backend"].is_string() || !meta["gl_renderer"].is_string()) {
    return "";
  }
  return meta["backend"].get<std::string>() + " / " + meta["gl_renderer"].get<std::string>();
}

std::string RunningOn(const GlInfo& gl) { return gl.backend + " / " + gl.renderer; }

ToleranceOverride ParseToleranceOverride(const std::string& text) {
  ToleranceOverride o;
  if (text == "auto" || text == "same" || text == "cross") {
    o.mode = text;
  } else {
    o.mode = "explicit";
    o.numbers = ParseExplicit(text);
  }
  return o;
}

ToleranceChoice ChooseTolerance(const GoldenScene& scene, const nlohmann::json& meta,
                                const GlInfo& gl, const ToleranceOverride& override_) {
  ToleranceChoice c;
  const std::string made = MadeOn(meta);
  c.same_backend = !made.empty() && made == RunningOn(gl);
  if (override_.mode == "explicit") {
    c.tolerance = override_.numbers;
    c.why = "--tolerance";
  } else if (override_.mode == "same" || (override_.mode == "auto" && c.same_backend)) {
    c.tolerance = scene.same_tolerance;
    c.why = override_.mode == "same" ? "--tolerance same" : "same backend";
  } else {
    c.tolerance = scene.tolerance;
    c.why = override_.mode == "cross" ? "--tolerance cross"
            : made.empty() ? "cross-backend (the goldens do not say where they were made)"
                           : "cross-backend (goldens made on " + made + ")";
  }
  return c;
}

std::vector<NamedDifference> NamedStateDifferences(const nlohmann::json& golden,
                                                   const nlohmann::json& actual, double atol,
                                                   size_t limit) {
  std::vector<NamedDifference> all;
  if (!golden.contains("steps") || !actual.contains("steps")) return all;
  const nlohmann::json& gs = golden["steps"];
  const nlohmann::json& as = actual["steps"];
  std::map<std::string, NamedDifference> largest;  // by label
  for (size_t t = 0; t < std::min(gs.size(), as.size()); ++t) {
    const size_t obs_size = gs[t].value("observation", nlohmann::json::array()).size();
    for (const auto& item : gs[t].items()) {
      const nlohmann::json& g = item.value();
      if (!as[t].contains(item.key())) continue;
      const nlohmann::json& a = as[t][item.key()];
      const bool array = g.is_array() && a.is_array();
      const size_t n = array ? std::min(g.size(), a.size()) : 1;
      for (size_t i = 0; i < n; ++i) {
        const nlohmann::json& gv = array ? g[i] : g;
        const nlohmann::json& av = array ? a[i] : a;
        if (!gv.is_number() || !av.is_number() || item.key() == "t") continue;
        const double d = av.get<double>() - gv.get<double>();
        if (!(std::fabs(d) > atol)) continue;
        const Quantity q = Label(item.key(), i, obs_size);
        if (q.label.empty()) continue;
        NamedDifference& best = largest[q.label];
        if (best.label.empty() || std::fabs(d) > std::fabs(best.delta)) {
          best = {q.label, d, static_cast<int>(t), "", q.unit};
        }
      }
    }
  }
  for (auto& [label, d] : largest) {
    d.text = label + " " + FormatDelta(d.delta, d.unit) + " at t=" + std::to_string(d.t);
    all.push_back(d);
  }
  // positions first (what moved), then angles, velocities, and unitless numbers (actions, reward)
  auto rank = [](const std::string& unit) {
    return unit == "m" ? 0 : unit == "rad" ? 1 : unit.empty() ? 3 : 2;
  };
  std::stable_sort(all.begin(), all.end(), [&](const NamedDifference& a, const NamedDifference& b) {
    if (rank(a.unit) != rank(b.unit)) return rank(a.unit) < rank(b.unit);
    return std::fabs(a.delta) > std::fabs(b.delta);
  });
  if (all.size() > limit) all.resize(limit);
  return all;
}

std::string JoinDifferences(const std::vector<NamedDifference>& differences) {
  std::string out;
  for (const NamedDifference& d : differences) out += (out.empty() ? "" : ", ") + d.text;
  return out;
}

}  // namespace fetchscope
