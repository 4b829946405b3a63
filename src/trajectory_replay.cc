#include "src/trajectory_replay.h"

#include <cctype>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "base/errors.h"

namespace fetchscope {
namespace {

[[noreturn]] void Bad(const std::string& name, const std::string& where, const std::string& what) {
  throw RunError("replay file " + name + (where.empty() ? "" : " " + where) + ": " + what);
}

bool EndsWithJson(const std::string& path) {
  if (path.size() < 5) return false;
  std::string tail = path.substr(path.size() - 5);
  for (char& c : tail) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return tail == ".json";
}

}  // namespace

bool IsTrajectoryJson(const std::string& text) {
  const size_t first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos || text[first] != '{') return false;
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  return j.is_object() && j.contains("episodes") && j["episodes"].is_array();
}

TrajectoryReplay ParseTrajectoryReplay(const std::string& text, const std::string& name) {
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object() || !j.contains("episodes") || !j["episodes"].is_array()) {
    Bad(name, "", "not a trajectory JSON (an object with an \"episodes\" list)");
  }
  TrajectoryReplay replay;
  if (j.contains("env_id") && j["env_id"].is_string())
    replay.env_id = j["env_id"].get<std::string>();
  if (j.contains("seed") && j["seed"].is_number_unsigned())
    replay.seed = std::to_string(j["seed"].get<uint64_t>());
  if (j["episodes"].empty()) Bad(name, "", "holds no episodes");
  for (size_t i = 0; i < j["episodes"].size(); ++i) {
    const nlohmann::json& e = j["episodes"][i];
    const std::string where_e = "episode list entry " + std::to_string(i);
    if (!e.is_object() || !e.contains("index") || !e["index"].is_number_integer() ||
        e["index"].get<long long>() < 0 || e["index"].get<long long>() > 100000000) {
      Bad(name, where_e, "has no valid \"index\" (a non-negative integer)");
    }
    const int index = e["index"].get<int>();
    const std::string where = "episode " + std::to_string(index);
    if (replay.episodes.count(index)) Bad(name, where, "appears twice");
    TrajectoryEpisode episode;
    episode.dtype = e.value("action_dtype", std::string("float64"));
    if (episode.dtype != "float32" && episode.dtype != "float64" && episode.dtype != "none") {
      Bad(name, where, "action_dtype '" + episode.dtype + "' is not float32 or float64");
    }
    episode.complete = e.value("complete", true);
    if (!e.contains("steps") || !e["steps"].is_array()) Bad(name, where, "has no \"steps\" list");
    const nlohmann::json& steps = e["steps"];
    for (size_t t = 1; t < steps.size(); ++t) {
      const std::string at = where + " step " + std::to_string(t);
      const nlohmann::json* action =
          steps[t].is_object() && steps[t].contains("action") ? &steps[t]["action"] : nullptr;
      if (!action || !action->is_array() || action->size() != 4) {
        Bad(name, at, "has no \"action\" of 4 numbers");
      }
      Action a;
      a.is_float32 = episode.dtype == "float32";
      for (size_t c = 0; c < 4; ++c) {
        if (!(*action)[c].is_number())
          Bad(name, at, "action value " + (*action)[c].dump() + " is not a number");
        const double v = (*action)[c].get<double>();
        if (!std::isfinite(v)) Bad(name, at, "action value is not finite");
        if (a.is_float32 && static_cast<double>(static_cast<float>(v)) != v) {
          Bad(name, at,
              "action value " + (*action)[c].dump() +
                  " is not a float32 number although action_dtype is float32");
        }
        a.value[c] = v;
      }
      episode.actions.push_back(a);
    }
    replay.episodes.emplace(index, std::move(episode));
  }
  return replay;
}

std::optional<TrajectoryReplay> ReadTrajectoryReplay(const std::string& path) {
  if (!EndsWithJson(path)) return std::nullopt;
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;  // ReadReplayFile says why
  std::ostringstream text;
  text << in.rdbuf();
  if (!IsTrajectoryJson(text.str())) return std::nullopt;
  return ParseTrajectoryReplay(text.str(), path);
}

}  // namespace fetchscope
