#include "src/trajectory.h"

#include <cctype>
#include <cmath>
#include <filesystem>
#include <set>

#include "base/confined_file.h"
#include "base/errors.h"
#include "base/json_util.h"

namespace fetchscope {
namespace {

using nlohmann::json;

json FileJson(const std::string& env_id, uint64_t seed, const std::string& policy,
              const AssetSource& assets, json episodes) {
  std::string past;  // the note, when an episode ran past the TimeLimit
  for (const json& e : episodes) {
    if (!e.is_object() || !e.contains("past_time_limit")) continue;
    past = "steps after " + e["past_time_limit"]["max_episode_steps"].dump() +
           " run past the env's TimeLimit (--steps above max_episode_steps) and are marked "
           "\"past_time_limit\": true; gym.make's env sets truncated = True at step " +
           e["past_time_limit"]["max_episode_steps"].dump() +
           " and callers reset it there, so such steps are not in Gymnasium's episodes";
    break;
  }
  json file = {{"schema_version", kTrajectorySchemaVersion},
               {"env_id", env_id},
               {"seed", seed},
               {"policy", policy},
               {"assets", AssetsJson(assets)},
               {"episodes", std::move(episodes)}};
  if (!past.empty()) file["note"] = past;
  return file;
}

// The reader: walks the document and names the key of anything it refuses.
class TrajectoryReader {
 public:
  explicit TrajectoryReader(const std::string& file) : file_(file) {}

  Trajectory Read(const json& root) {
    Trajectory out;
    // the version first: a newer one may have moved anything else
    out.schema_version = 0;  // absent: written before versions existed, the same layout
    if (const json* version = root.is_object() ? Find(root, "schema_version") : nullptr) {
      if (!version->is_number_integer() || version->get<long long>() < 0) {
        Fail("schema_version", "expected an integer of at least 0, found " + version->dump());
      }
      if (version->get<long long>() > kTrajectorySchemaVersion) {
        Fail("", "has trajectory schema version " + version->dump() +
                     "; this fetchscope reads versions 0 to " +
                     std::to_string(kTrajectorySchemaVersion) + ": use a newer fetchscope");
      }
      out.schema_version = version->get<int>();
    }
    if (!root.is_object() || !root.contains("episodes")) {
      Fail("", "not a fetchscope trajectory (an object with env_id, seed and episodes)");
    }
    out.env_id = String(root, "env_id", "", /*required=*/true);
    try {
      FindEnvSpec(out.env_id);  // an edited id is named here, with the file and the key
    } catch (const UsageError& e) {
      Fail("env_id", e.what());
    }
    const json* seed = Find(root, "seed");
    if (!seed || !seed->is_number_unsigned()) {
      Fail("seed", "expected a non-negative integer below 2^64");
    }
    out.seed = seed->get<uint64_t>();
    out.policy = String(root, "policy", "", /*required=*/false);
    if (const json* assets = Find(root, "assets")) {
      if (!assets->is_object()) Fail("assets", "expected an object");
      out.assets.kind = String(*assets, "kind", "assets.", false);
      out.assets.root = String(*assets, "path", "assets.", false);
      out.assets.sha256 = String(*assets, "sha256", "assets.", false);
      out.assets.origin = String(*assets, "origin", "assets.", false);
    }
    const json& episodes = root["episodes"];
    if (!episodes.is_array()) Fail("episodes", "expected a list");
    std::set<int> seen;
    for (size_t i = 0; i < episodes.size(); ++i) {
      TrajectoryEpisode episode = Episode(episodes[i], "episodes[" + std::to_string(i) + "]");
      if (!seen.insert(episode.index).second) {
        Fail("episodes[" + std::to_string(i) + "].index",
             "episode " + std::to_string(episode.index) + " appears twice");
      }
      if (episode.index == 0) episode.seed = out.seed;
      out.episodes.push_back(std::move(episode));
    }
    return out;
  }

 private:
  [[noreturn]] void Fail(const std::string& key, const std::string& what) const {
    throw RunError(file_ + ": " + (key.empty() ? "" : key + ": ") + what);
  }

  static const json* Find(const json& object, const char* member) {
    const auto it = object.find(member);
    return it == object.end() ? nullptr : &*it;
  }

  std::string String(const json& object, const char* member, const std::string& prefix,
                     bool required) const {
    const json* value = Find(object, member);
    if (!value || value->is_null()) {
      if (required) Fail(prefix + member, "expected a string");
      return "";
    }
    if (!value->is_string()) Fail(prefix + member, "expected a string");
    return value->get<std::string>();
  }

  // A number, or one of the strings JsonDouble writes for non-finite values.
  double Number(const json& value, const std::string& key, const char* what) const {
    if (value.is_number()) return value.get<double>();
    if (value.is_string()) {
      const std::string& s = value.get_ref<const std::string&>();
      if (s == "inf") return HUGE_VAL;
      if (s == "-inf") return -HUGE_VAL;
      if (s == "nan") return std::nan("");
    }
    Fail(key, std::string("expected ") + what + ", found " + value.dump());
  }

  // A list of `want` numbers (any count when 0).
  std::vector<double> Numbers(const json& step, const char* member, size_t want,
                              const std::string& prefix) const {
    const std::string key = prefix + "." + member;
    const std::string expected =
        "expected " + (want ? std::to_string(want) + " numbers" : std::string("a list of numbers"));
    const json* value = Find(step, member);
    if (!value || !value->is_array() || (want && value->size() != want) ||
        (!want && value->empty())) {
      Fail(key, expected);
    }
    std::vector<double> out;
    out.reserve(value->size());
    for (size_t i = 0; i < value->size(); ++i) {
      out.push_back(Number((*value)[i], key + "[" + std::to_string(i) + "]", "a number"));
    }
    return out;
  }

  std::array<double, 3> Vector3(const json& step, const char* member,
                                const std::string& prefix) const {
    const std::vector<double> v = Numbers(step, member, 3, prefix);
    return {v[0], v[1], v[2]};
  }

  Action ReadAction(const json& step, const std::string& prefix, bool float32) const {
    const std::string key = prefix + ".action";
    const json* value = Find(step, "action");
    if (!value || !value->is_array() || value->size() != 4) Fail(key, "expected 4 numbers");
    Action action;
    action.is_float32 = float32;
    for (size_t c = 0; c < 4; ++c) {
      const json& v = (*value)[c];
      const std::string at = key + "[" + std::to_string(c) + "]";
      if (!v.is_number()) Fail(at, "expected a number, found " + v.dump());
      const double d = v.get<double>();
      if (!std::isfinite(d)) Fail(at, "expected a finite number, found " + v.dump());
      if (float32 && static_cast<double>(static_cast<float>(d)) != d) {
        Fail(at, v.dump() + " is not a float32 number although action_dtype is float32");
      }
      action.value[c] = d;
    }
    return action;
  }

  ContactSignals Contacts(const json& c, const std::string& step_key) const {
    const std::string key = step_key + ".contacts";
    if (!c.is_object()) Fail(key, "expected an object");
    ContactSignals out;
    const auto number = [&](const json& where, const char* member, const std::string& at) {
      const json* v = Find(where, member);
      if (!v) Fail(at + "." + member, "expected a number");
      return Number(*v, at + "." + member, "a number");
    };
    const auto boolean = [&](const json& where, const char* member, const std::string& at) {
      const json* v = Find(where, member);
      if (!v || !v->is_boolean()) Fail(at + "." + member, "expected true or false");
      return v->get<bool>();
    };
    out.left_finger_force = number(c, "left_finger_force", key);
    out.right_finger_force = number(c, "right_finger_force", key);
    out.object_on_table = boolean(c, "object_on_table", key);
    const json* list = Find(c, "list");
    if (!list || !list->is_array()) Fail(key + ".list", "expected a list");
    for (size_t i = 0; i < list->size(); ++i) {
      const json& k = (*list)[i];
      const std::string at = key + ".list[" + std::to_string(i) + "]";
      if (!k.is_object()) Fail(at, "expected an object");
      Contact contact;
      contact.index = static_cast<int>(i);
      const auto text = [&](const char* member) {
        const json* v = Find(k, member);
        if (!v || !v->is_string()) Fail(at + "." + member, "expected a string");
        return v->get<std::string>();
      };
      const std::string pair = text("pair");
      bool known = false;
      for (ContactPair p : {ContactPair::kFingerObject, ContactPair::kObjectTable,
                            ContactPair::kFingerTable, ContactPair::kOther}) {
        if (pair == ContactPairName(p)) {
          contact.pair = p;
          known = true;
        }
      }
      if (!known) Fail(at + ".pair", "unknown pair '" + pair + "'");
      contact.geom1 = text("geom1");
      contact.geom2 = text("geom2");
      contact.body1 = text("body1");
      contact.body2 = text("body2");
      contact.position = Vector3(k, "position", at);
      contact.normal = Vector3(k, "normal", at);
      contact.normal_force = number(k, "normal_force", at);
      contact.penetration = number(k, "penetration", at);
      out.contacts.push_back(std::move(contact));
    }
    return out;
  }

  TrajectoryStep Step(const json& s, size_t t, const std::string& key, bool float32) const {
    if (!s.is_object()) Fail(key, "expected an object");
    TrajectoryStep step;
    step.t = static_cast<int>(t);
    if (const json* at = Find(s, "t")) {
      if (!at->is_number_integer() || at->get<long long>() != static_cast<long long>(t)) {
        Fail(key + ".t", "expected " + std::to_string(t) + ", found " + at->dump());
      }
    }
    step.obs.observation = Numbers(s, "observation", 0, key);
    step.obs.achieved_goal = Vector3(s, "achieved_goal", key);
    step.obs.desired_goal = Vector3(s, "desired_goal", key);
    if (t == 0) {
      for (const char* member : {"action", "reward"}) {
        const json* v = Find(s, member);
        if (v && !v->is_null()) Fail(key + "." + member, "expected null at the reset (t = 0)");
      }
    } else {
      step.action = ReadAction(s, key, float32);
      const json* reward = Find(s, "reward");
      if (!reward) Fail(key + ".reward", "expected a number");
      step.reward = Number(*reward, key + ".reward", "a number");
    }
    const json* success = Find(s, "is_success");
    if (!success || !success->is_boolean()) Fail(key + ".is_success", "expected true or false");
    step.is_success = success->get<bool>();
    if (const json* past = Find(s, "past_time_limit")) {
      if (!past->is_boolean()) Fail(key + ".past_time_limit", "expected true or false");
      step.past_time_limit = past->get<bool>();
    }
    if (const json* contacts = Find(s, "contacts")) step.contacts = Contacts(*contacts, key);
    return step;
  }

  // a reset placed by hand: finite numbers, the object's position and angles together
  PlacedReset Placed(const json& r, const std::string& key) const {
    const json* rule = r.is_object() ? Find(r, "rule") : nullptr;
    if (!rule || *rule != "placed") Fail(key + ".rule", "expected \"placed\"");
    for (const auto& [member, value] : r.items()) {
      if (member != "rule" && member != "goal" && member != "object_position" &&
          member != "object_euler") {
        Fail(key + "." + member,
             "unknown member; accepted: rule, goal, object_position, "
             "object_euler");
      }
    }
    const auto finite = [&](const char* member) {
      const std::array<double, 3> v = Vector3(r, member, key);
      for (double x : v) {
        if (!std::isfinite(x)) Fail(key + "." + member, "expected 3 finite numbers");
      }
      return v;
    };
    PlacedReset placed;
    placed.goal = finite("goal");
    const bool position = r.contains("object_position"), euler = r.contains("object_euler");
    if (position != euler) {
      Fail(key, "expected object_position and object_euler together, or neither");
    }
    if (position) placed.object = ObjectPose{finite("object_position"), finite("object_euler")};
    return placed;
  }

  TrajectoryEpisode Episode(const json& e, const std::string& key) const {
    if (!e.is_object()) Fail(key, "expected an object");
    TrajectoryEpisode episode;
    episode.file = file_;
    const json* index = Find(e, "index");
    if (!index || !index->is_number_integer() || index->get<long long>() < 0 ||
        index->get<long long>() > 100000000) {
      Fail(key + ".index", "expected an integer from 0 to 100000000");
    }
    episode.index = index->get<int>();
    if (const json* complete = Find(e, "complete")) {  // absent before the flag: complete
      if (!complete->is_boolean()) Fail(key + ".complete", "expected true or false");
      episode.complete = complete->get<bool>();
    }
    std::string dtype = "float64";  // absent before the member: float64
    if (const json* d = Find(e, "action_dtype")) {
      if (!d->is_string()) Fail(key + ".action_dtype", "expected float32, float64 or none");
      dtype = d->get<std::string>();
      if (dtype != "float32" && dtype != "float64" && dtype != "none") {
        Fail(key + ".action_dtype", "'" + dtype + "' is not float32, float64 or none");
      }
    }
    const json* steps = Find(e, "steps");
    if (!steps || !steps->is_array() || steps->empty()) {
      Fail(key + ".steps", "expected a list starting with the reset (t = 0)");
    }
    double sum = 0;
    for (size_t t = 0; t < steps->size(); ++t) {
      episode.steps.push_back(
          Step((*steps)[t], t, key + ".steps[" + std::to_string(t) + "]", dtype == "float32"));
      if (t > 0) sum += *episode.steps.back().reward;
    }
    episode.episode_return = sum;
    if (const json* reset = Find(e, "reset")) episode.placed = Placed(*reset, key + ".reset");
    if (const json* look = Find(e, "look")) {  // its members are render/look.h's to check
      if (!look->is_object()) Fail(key + ".look", "expected an object");
      episode.look = *look;
    }
    if (const json* r = Find(e, "return"))
      episode.episode_return = Number(*r, key + ".return", "a number");
    return episode;
  }

  const std::string file_;
};

}  // namespace

std::string ActionDtype(const TrajectoryEpisode& episode) {
  if (episode.steps.size() < 2 || !episode.steps[1].action) return "none";
  return episode.steps[1].action->is_float32 ? "float32" : "float64";
}

nlohmann::json AssetsJson(const AssetSource& assets) {
  return {{"kind", assets.kind},
          {"path", assets.root},
          {"sha256", assets.sha256},
          {"origin", assets.origin}};
}

nlohmann::json ContactsJson(const ContactSignals& c) {
  json list = json::array();
  for (const Contact& k : c.contacts) {
    list.push_back({{"pair", ContactPairName(k.pair)},
                    {"geom1", k.geom1},
                    {"geom2", k.geom2},
                    {"body1", k.body1},
                    {"body2", k.body2},
                    {"position", JsonVector(k.position.data(), 3)},
                    {"normal", JsonVector(k.normal.data(), 3)},
                    {"normal_force", JsonDouble(k.normal_force)},
                    {"penetration", JsonDouble(k.penetration)}});
  }
  return {{"left_finger_force", JsonDouble(c.left_finger_force)},
          {"right_finger_force", JsonDouble(c.right_finger_force)},
          {"grasped", c.grasped()},
          {"object_on_table", c.object_on_table},
          {"list", std::move(list)}};
}

nlohmann::json StepsJson(const TrajectoryEpisode& episode) {
  json steps = json::array();
  for (const TrajectoryStep& s : episode.steps) {
    json row;
    row["t"] = s.t;
    row["observation"] = JsonVector(s.obs.observation.data(), s.obs.observation.size());
    row["achieved_goal"] = JsonVector(s.obs.achieved_goal.data(), 3);
    row["desired_goal"] = JsonVector(s.obs.desired_goal.data(), 3);
    row["action"] = s.action ? JsonVector(s.action->value.data(), 4) : json(nullptr);
    row["reward"] = s.reward ? JsonDouble(*s.reward) : json(nullptr);
    row["is_success"] = s.is_success;
    if (s.past_time_limit) row["past_time_limit"] = true;
    if (s.contacts) row["contacts"] = ContactsJson(*s.contacts);
    steps.push_back(std::move(row));
  }
  return steps;
}

nlohmann::json EpisodeJson(const TrajectoryEpisode& episode) {
  json steps = StepsJson(episode);
  json out = {{"index", episode.index},
              {"length", static_cast<int>(episode.steps.size()) - 1},
              {"complete", episode.complete},
              {"return", JsonDouble(episode.episode_return)},
              {"is_success", !episode.steps.empty() && episode.steps.back().is_success},
              {"action_dtype", ActionDtype(episode)},
              {"steps", std::move(steps)}};
  int past = 0, first = 0;  // steps past the TimeLimit, and the first of them
  for (const TrajectoryStep& s : episode.steps) {
    if (!s.past_time_limit) continue;
    if (past++ == 0) first = s.t;
  }
  if (episode.placed) {
    json& reset =
        out["reset"] = {{"rule", "placed"}, {"goal", JsonVector(episode.placed->goal.data(), 3)}};
    if (const auto& object = episode.placed->object) {
      reset["object_position"] = JsonVector(object->position.data(), 3);
      reset["object_euler"] = JsonVector(object->euler.data(), 3);
    }
  }
  if (!episode.look.is_null()) out["look"] = episode.look;
  if (past > 0) {
    out["past_time_limit"] = {
        {"max_episode_steps", first - 1}, {"first_step", first}, {"steps", past}};
  }
  return out;
}

nlohmann::json TrajectoryJson(const EnvSpec& spec, const AssetSource& assets, uint64_t seed,
                              const std::string& policy, nlohmann::json episodes) {
  return FileJson(spec.id, seed, policy, assets, std::move(episodes));
}

nlohmann::json TrajectoryJson(const Trajectory& trajectory) {
  json episodes = json::array();
  for (const TrajectoryEpisode& e : trajectory.episodes) episodes.push_back(EpisodeJson(e));
  return FileJson(trajectory.env_id, trajectory.seed, trajectory.policy, trajectory.assets,
                  std::move(episodes));
}

std::string TrajectoryText(const Trajectory& trajectory) {
  return DumpJson(TrajectoryJson(trajectory)) + "\n";
}

Trajectory ParseTrajectory(const std::string& text, const std::string& file) {
  json root;
  try {
    root = json::parse(text);
  } catch (const json::parse_error& e) {
    throw RunError(file + ": not JSON: " + DescribeJsonError(e, text.size()));
  }
  return TrajectoryReader(file).Read(root);
}

Trajectory ParseTrajectoryJson(const nlohmann::json& root, const std::string& file) {
  return TrajectoryReader(file).Read(root);
}

std::optional<Trajectory> ReadReplayTrajectory(const std::string& path) {
  if (path.size() < 5) return std::nullopt;
  std::string tail = path.substr(path.size() - 5);
  for (char& c : tail) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (tail != ".json") return std::nullopt;
  std::error_code ec;
  if (!std::filesystem::exists(path, ec) || std::filesystem::is_directory(path, ec)) {
    return std::nullopt;  // ReadReplayFile says why
  }
  std::string text;
  try {
    text = ReadFileCapped(path, kMaxJsonFileBytes);  // refuses a FIFO, a device, a huge file
  } catch (const RunError&) {
    return std::nullopt;  // it cannot be opened: ReadReplayFile says why
  }
  return ParseReplayTrajectory(text, path);
}

std::optional<Trajectory> ParseReplayTrajectory(const std::string& text, const std::string& path) {
  const json root = json::parse(text, nullptr, /*allow_exceptions=*/false);
  const bool versioned = root.is_object() && root.contains("schema_version");  // a newer one too
  if (!versioned &&
      (!root.is_object() || !root.contains("episodes") || !root["episodes"].is_array())) {
    return std::nullopt;  // bare action rows, or not JSON: ReadReplayFile says which
  }
  try {
    return TrajectoryReader(path).Read(root);
  } catch (const RunError& e) {
    throw RunError(std::string("replay file ") + e.what());
  }
}

Trajectory ReadTrajectory(const std::string& path) {
  return ParseTrajectory(ReadFileCapped(path, kMaxJsonFileBytes), path);
}

}  // namespace fetchscope
