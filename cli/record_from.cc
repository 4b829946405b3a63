#include "cli/record_from.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "base/errors.h"

namespace fetchscope::cli {
namespace {

namespace fs = std::filesystem;

std::string Num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

nlohmann::json ReadJsonFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw RunError("--from: cannot read '" + path + "'");
  std::stringstream ss;
  ss << in.rdbuf();
  try {
    return nlohmann::json::parse(ss.str());
  } catch (const nlohmann::json::exception& e) {
    throw RunError("--from: '" + path + "' is not JSON: " + e.what());
  }
}

// Reads a member of `j` as numbers; `where` names it in errors.
std::vector<double> Numbers(const nlohmann::json& j, const char* member, size_t want,
                            const std::string& where) {
  const auto it = j.find(member);
  if (it == j.end() || !it->is_array() || (want && it->size() != want)) {
    throw RunError(where + ": '" + member + "' is not an array of " +
                   (want ? std::to_string(want) + " " : std::string()) + "numbers");
  }
  std::vector<double> out;
  for (const auto& v : *it) {
    if (!v.is_number()) throw RunError(where + ": '" + member + "' holds a non-number");
    out.push_back(v.get<double>());
  }
  return out;
}

RecordedEpisode ParseEpisode(const nlohmann::json& e, const std::string& file) {
  RecordedEpisode out;
  out.file = file;
  if (!e.is_object() || !e.contains("index") || !e["index"].is_number_integer() ||
      !e.contains("steps") || !e["steps"].is_array() || e["steps"].empty()) {
    throw RunError("--from: " + file + ": an episode lacks an integer 'index' or its 'steps'");
  }
  out.index = e["index"].get<int>();
  if (out.index < 0)
    throw RunError("--from: " + file + ": episode index " + std::to_string(out.index) +
                   " is negative");
  if (e.contains("complete")) {  // absent in trajectories from before the flag: complete
    if (!e["complete"].is_boolean()) {
      throw RunError("--from: " + file + ": episode " + std::to_string(out.index) +
                     ": 'complete' is not true or false");
    }
    out.complete = e["complete"].get<bool>();
  }
  const bool f32 = e.value("action_dtype", std::string("float64")) == "float32";
  const auto& steps = e["steps"];
  for (size_t t = 0; t < steps.size(); ++t) {
    const std::string where =
        "--from: " + file + ": episode " + std::to_string(out.index) + " step " + std::to_string(t);
    const nlohmann::json& s = steps[t];
    if (!s.is_object()) throw RunError(where + ": not an object");
    StepRecord r;
    r.t = static_cast<int>(t);
    r.obs.observation = Numbers(s, "observation", 0, where);
    const auto ag = Numbers(s, "achieved_goal", 3, where);
    const auto dg = Numbers(s, "desired_goal", 3, where);
    std::copy(ag.begin(), ag.end(), r.obs.achieved_goal.begin());
    std::copy(dg.begin(), dg.end(), r.obs.desired_goal.begin());
    if (t > 0) {
      const auto a = Numbers(s, "action", 4, where);
      Action action;
      std::copy(a.begin(), a.end(), action.value.begin());
      action.is_float32 = f32;
      r.action = action;
      if (!s.contains("reward") || !s["reward"].is_number())
        throw RunError(where + ": 'reward' is not a number");
      r.reward = s["reward"].get<double>();
    }
    if (!s.contains("is_success") || !s["is_success"].is_boolean()) {
      throw RunError(where + ": 'is_success' is not true or false");
    }
    r.is_success = s["is_success"].get<bool>();
    out.steps.push_back(std::move(r));
  }
  return out;
}

void AddFile(const std::string& file, TrajectorySource* source, bool first) {
  const nlohmann::json j = ReadJsonFile(file);
  if (!j.is_object() || !j.contains("env_id") || !j["env_id"].is_string() || !j.contains("seed") ||
      !j["seed"].is_number_unsigned() || !j.contains("episodes") || !j["episodes"].is_array()) {
    throw RunError("--from: " + file +
                   " is not a fetchscope trajectory (env_id, seed and episodes wanted)");
  }
  const std::string env_id = j["env_id"].get<std::string>();
  const uint64_t seed = j["seed"].get<uint64_t>();
  if (first) {
    source->env_id = env_id;
    source->seed = seed;
    source->policy = j.value("policy", std::string());
    source->assets = j.value("assets", nlohmann::json::object());
  } else if (env_id != source->env_id || seed != source->seed) {
    throw RunError("--from: " + file + " is " + env_id + " seed " + std::to_string(seed) +
                   ", the other files " + source->env_id + " seed " + std::to_string(source->seed) +
                   ": one run at a time");
  }
  for (const auto& e : j["episodes"]) {
    RecordedEpisode episode = ParseEpisode(e, file);
    const int index = episode.index;
    if (source->episodes.count(index)) {
      throw RunError("--from: episode " + std::to_string(index) + " appears twice (" +
                     source->episodes[index].file + ", " + file + ")");
    }
    source->max_steps = std::max(source->max_steps, static_cast<int>(episode.steps.size()) - 1);
    source->episodes.emplace(index, std::move(episode));
  }
}

}  // namespace

TrajectorySource LoadTrajectorySource(const std::string& path) {
  TrajectorySource source;
  source.path = path;
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    std::vector<std::string> files;
    const std::regex name("episode_[0-9]+\\.json");
    for (const auto& entry : fs::directory_iterator(path, ec)) {
      if (entry.is_regular_file() && std::regex_match(entry.path().filename().string(), name)) {
        files.push_back(entry.path().string());
      }
    }
    std::sort(files.begin(), files.end());
    if (files.empty()) {
      throw UsageError("--from '" + path +
                       "' holds no episode_NNN.json; accepted: a run folder of record, or one "
                       "trajectory JSON file");
    }
    for (size_t i = 0; i < files.size(); ++i) AddFile(files[i], &source, i == 0);
  } else if (fs::is_regular_file(path, ec)) {
    AddFile(path, &source, true);
  } else {
    throw UsageError("--from '" + path +
                     "' does not exist; accepted: a run folder of record, or one trajectory JSON "
                     "file");
  }
  if (source.episodes.empty()) throw RunError("--from: " + path + " holds no episodes");
  return source;
}

std::string SourceAssets(const TrajectorySource& source) {
  const std::string kind = source.assets.value("kind", std::string("bundled"));
  if (kind == "bundled") return "bundled";
  return source.assets.value("path", std::string("bundled"));
}

std::string FirstDifference(const StepRecord& replayed, const StepRecord& recorded) {
  auto diff = [](const std::string& what, double a, double b) {
    if (a == b || (std::isnan(a) && std::isnan(b))) return std::string();
    return what + " recorded " + Num(b) + ", replayed " + Num(a) +
           " (difference replayed - recorded " + Num(a - b) + ")";
  };
  const auto& ro = replayed.obs.observation;
  const auto& co = recorded.obs.observation;
  if (ro.size() != co.size()) {
    return "observation has " + std::to_string(ro.size()) + " values replayed, " +
           std::to_string(co.size()) + " recorded";
  }
  for (size_t i = 0; i < ro.size(); ++i) {
    std::string d = diff("observation[" + std::to_string(i) + "]", ro[i], co[i]);
    if (!d.empty()) return d;
  }
  for (int i = 0; i < 3; ++i) {
    std::string d = diff("achieved_goal[" + std::to_string(i) + "]", replayed.obs.achieved_goal[i],
                         recorded.obs.achieved_goal[i]);
    if (!d.empty()) return d;
    d = diff("desired_goal[" + std::to_string(i) + "]", replayed.obs.desired_goal[i],
             recorded.obs.desired_goal[i]);
    if (!d.empty()) return d;
  }
  if (replayed.reward && recorded.reward) {
    std::string d = diff("reward", *replayed.reward, *recorded.reward);
    if (!d.empty()) return d;
  }
  if (replayed.is_success != recorded.is_success) {
    return std::string("is_success recorded ") + (recorded.is_success ? "true" : "false") +
           ", replayed " + (replayed.is_success ? "true" : "false");
  }
  return "";
}

EpisodeRecord EpisodeReplayer::Replay(int k, const std::vector<StepRecord>& recorded,
                                      bool recorded_complete, const std::string& check,
                                      const StepCallback& on_step) {
  if (k < next_) next_ = 0;  // start over from the seeded reset
  for (; next_ < k; ++next_) env_.Reset(next_ == 0 ? std::optional<uint64_t>(seed_) : std::nullopt);
  next_ = k + 1;
  EpisodeRecord episode;
  episode.index = k;
  episode.complete = false;  // until the last recorded step is replayed
  StepRecord row;
  row.obs = env_.Reset(k == 0 ? std::optional<uint64_t>(seed_) : std::nullopt);
  row.is_success = env_.IsSuccess(row.obs.achieved_goal, row.obs.desired_goal);
  auto verify = [&](const StepRecord& replayed, size_t t) {
    if (check.empty()) return;
    const std::string d = FirstDifference(replayed, recorded[t]);
    if (!d.empty()) {
      throw ReplayMismatch("record --from: " + check + ": episode " + std::to_string(k) + " step " +
                           std::to_string(t) + ": " + d + "; " +
                           (t == 0 ? "the reset differs: another env, seed, assets or "
                                     "fetchscope version?"
                                   : "the recording was edited, or the physics differs"));
    }
  };
  verify(row, 0);
  episode.steps.push_back(row);
  const bool whole = recorded_complete;
  if (recorded.size() == 1) episode.complete = whole;
  if (on_step && !on_step(episode.steps.back(), nullptr)) return episode;
  for (size_t t = 1; t < recorded.size(); ++t) {
    const Action& action = *recorded[t].action;
    StepResult result = env_.Step(action);
    StepRecord r;
    r.t = static_cast<int>(t);
    r.obs = result.obs;
    r.action = action;
    r.reward = result.reward;
    r.is_success = result.is_success;
    verify(r, t);
    episode.episode_return += result.reward;
    episode.steps.push_back(std::move(r));
    if (t + 1 == recorded.size()) episode.complete = whole;
    if (on_step && !on_step(episode.steps.back(), &result)) break;
  }
  return episode;
}

void VerifyRecording(FetchEnv& env, const TrajectorySource& source) {
  EpisodeReplayer replayer(env, source.seed);
  for (const auto& [k, episode] : source.episodes) {
    replayer.Replay(k, episode.steps, episode.complete, episode.file, nullptr);
  }
}

void AddFromOption(CLI::App* sub, std::string* from) {
  sub->add_option("--from", *from,
                  "Re-render recorded episodes: a run folder (its episode_NNN.json) or one "
                  "trajectory JSON. Env, seed, policy, steps and episodes come from it; camera, "
                  "overlay, size, --layers and the rest are free. Each replayed step is checked "
                  "against the recorded observation; the first difference stops the run, before "
                  "any file, with its episode, step and value. An episode recorded incomplete "
                  "(cut short by SIGINT) stays incomplete");
}

void CheckFromFlags(const CLI::App& sub, const std::string& from) {
  for (const char* flag :
       {"--env-id", "--seed", "--policy", "--episodes", "--steps", "--shard", "--shard-count"}) {
    if (sub.count(flag) > 0) {
      throw UsageError(std::string(flag) + " cannot be used with --from: the env, seed, policy, " +
                       "steps and episodes come from the trajectory '" + from + "'");
    }
  }
}

void ApplyFromSource(const TrajectorySource& source, const CLI::App& sub, std::string* env_id,
                     std::string* seed, std::string* policy, int* steps, int* episodes,
                     std::string* assets) {
  CheckFromFlags(sub, source.path);
  *env_id = source.env_id;
  *seed = std::to_string(source.seed);
  *policy = source.policy.empty() ? "unknown" : source.policy;
  *steps = std::max(1, source.max_steps);
  *episodes = source.episodes.rbegin()->first + 1;
  if (sub.count("--assets") == 0) *assets = SourceAssets(source);
}

}  // namespace fetchscope::cli
