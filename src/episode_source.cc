#include "src/episode_source.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <regex>
#include <tuple>

#include "base/confined_file.h"
#include "base/errors.h"
#include "src/observation_layout.h"
#include "src/policy.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;

std::string Num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

void AddFile(const std::string& file, TrajectorySource* source, bool first) {
  Trajectory trajectory;
  try {
    trajectory = ReadTrajectory(file);
  } catch (const RunError& e) {
    throw RunError(std::string("--from: ") + e.what());
  } catch (const UsageError& e) {  // not a regular file, or too large
    throw UsageError(std::string("--from: ") + e.what());
  }
  if (first) {
    source->env_id = trajectory.env_id;
    source->seed = trajectory.seed;
    source->policy = trajectory.policy;
    source->assets = trajectory.assets;
  } else if (trajectory.env_id != source->env_id || trajectory.seed != source->seed) {
    throw RunError("--from: " + file + " is " + trajectory.env_id + " seed " +
                   std::to_string(trajectory.seed) + ", the other files " + source->env_id +
                   " seed " + std::to_string(source->seed) + ": one run at a time");
  }
  for (TrajectoryEpisode& episode : trajectory.episodes) {
    const int index = episode.index;
    if (source->episodes.count(index)) {
      throw RunError("--from: episode " + std::to_string(index) + " appears twice (" +
                     source->episodes[index].file + ", " + file + ")");
    }
    source->max_steps = std::max(source->max_steps, static_cast<int>(episode.steps.size()) - 1);
    if (episode.placed) {
      EpisodeStart& start = source->starts[index];
      start.goal = episode.placed->goal;
      start.object = episode.placed->object;
      start.placed = true;
    }
    source->episodes.emplace(index, std::move(episode));
  }
}

}  // namespace

EpisodeSequence::~EpisodeSequence() = default;
EpisodeSequence::EpisodeSequence(EpisodeSequence&&) noexcept = default;
EpisodeSequence& EpisodeSequence::operator=(EpisodeSequence&&) noexcept = default;

EpisodeSequence::EpisodeSequence(std::unique_ptr<FetchEnv> env, std::unique_ptr<Policy> policy,
                                 uint64_t seed, int steps)
    : env_(std::move(env)), policy_(std::move(policy)), seed_(seed), steps_(steps) {}

EpisodeRecord EpisodeSequence::Play(int k, const StepCallback& on_step) {
  for (; next_ < k; ++next_) {
    env_->Reset(next_ == 0 ? std::optional<uint64_t>(seed_) : std::nullopt);
    policy_->SkipEpisode(steps_);
  }
  next_ = k + 1;
  const std::optional<uint64_t> seed = k == 0 ? std::optional<uint64_t>(seed_) : std::nullopt;
  if (stop_after_success_ < 0) return RunEpisode(*env_, *policy_, k, seed, steps_, on_step);
  int first_success = -1;
  bool cut = false;
  const StepCallback until_success = [&](const StepRecord& r, const StepResult* result) {
    const bool go_on = !on_step || on_step(r, result);
    if (r.t >= 1 && r.is_success && first_success < 0) first_success = r.t;
    if (go_on && first_success >= 0 && r.t >= first_success + stop_after_success_ && r.t < steps_) {
      cut = true;
      return false;
    }
    return go_on;
  };
  EpisodeRecord episode = RunEpisode(*env_, *policy_, k, seed, steps_, until_success);
  if (cut) {
    episode.complete = true;
    policy_->SkipEpisode(steps_ - (static_cast<int>(episode.steps.size()) - 1));
  }
  return episode;
}

TrajectorySource LoadTrajectorySource(const std::string& path) {
  TrajectorySource source;
  source.path = path;
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    std::vector<std::string> files;
    const std::regex name("episode_[0-9]+\\.json");
    for (const auto& entry : fs::directory_iterator(path, ec)) {
      // every one, whatever it is: one that leads outside the folder, or is not a regular file
      // (a FIFO, a device), is refused rather than read or passed over
      const std::string file = entry.path().filename().string();
      if (std::regex_match(file, name)) {
        files.push_back(ResolveInside(path, file, "--from " + Quoted(path) + " holds").string());
      }
    }
    std::sort(files.begin(), files.end());
    if (files.empty()) {
      throw UsageError("--from '" + path +
                       "' holds no episode_NNN.json; accepted: a run folder of record, one "
                       "trajectory JSON file, or a Minari dataset (its id, folder or "
                       "main_data.hdf5)");
    }
    for (size_t i = 0; i < files.size(); ++i) AddFile(files[i], &source, i == 0);
  } else if (fs::exists(path, ec)) {
    AddFile(path, &source, true);  // refused unless a regular file (ReadTrajectory)
  } else {
    throw UsageError("--from '" + path +
                     "' does not exist; accepted: a run folder of record, or one trajectory JSON "
                     "file");
  }
  if (source.episodes.empty()) throw RunError("--from: " + path + " holds no episodes");
  return source;
}

std::string SourceAssets(const TrajectorySource& source) {
  const std::string& kind = source.assets.kind;
  if (kind.empty() || kind == "bundled") return "bundled";
  return source.assets.root.empty() ? "bundled" : source.assets.root;
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

EpisodeRecord EpisodeReplayer::ReplaySource(const TrajectorySource& source, int k,
                                            const StepCallback& on_step) {
  const TrajectoryEpisode& recorded = source.episodes.at(k);
  const auto start = source.starts.find(k);
  if (start == source.starts.end()) {
    return Replay(k, recorded.steps, recorded.complete, source.dataset ? "" : recorded.file,
                  on_step);
  }
  next_ = 0;  // the generator no longer stands where a sequential run's would
  EpisodeRecord episode =
      ReplayFrom(k, ResetForStart(env_, start->second), recorded.steps, recorded.complete,
                 source.dataset ? "" : recorded.file, on_step);
  episode.placed = recorded.placed;  // written again where the recording had it
  return episode;
}

EpisodeRecord EpisodeReplayer::ReplayEpisode(int k, const TrajectoryEpisode& recorded,
                                             const std::string& check,
                                             const StepCallback& on_step) {
  if (!recorded.placed) return Replay(k, recorded.steps, recorded.complete, check, on_step);
  next_ = 0;  // the generator no longer stands where a sequential run's would
  EpisodeRecord episode =
      ReplayFrom(k, env_.ResetTo(recorded.placed->goal, recorded.placed->object), recorded.steps,
                 recorded.complete, check, on_step);
  episode.placed = recorded.placed;
  return episode;
}

EpisodeRecord EpisodeReplayer::Replay(int k, const std::vector<StepRecord>& recorded,
                                      bool recorded_complete, const std::string& check,
                                      const StepCallback& on_step) {
  if (k < next_) next_ = 0;  // start over from the seeded reset
  for (; next_ < k; ++next_) env_.Reset(next_ == 0 ? std::optional<uint64_t>(seed_) : std::nullopt);
  next_ = k + 1;
  return ReplayFrom(k, env_.Reset(k == 0 ? std::optional<uint64_t>(seed_) : std::nullopt), recorded,
                    recorded_complete, check, on_step);
}

EpisodeRecord EpisodeReplayer::ReplayFrom(int k, const Observation& reset,
                                          const std::vector<StepRecord>& recorded,
                                          bool recorded_complete, const std::string& check,
                                          const StepCallback& on_step) {
  EpisodeRecord episode;
  episode.index = k;
  episode.complete = false;  // until the last recorded step is replayed
  StepRecord row;
  row.obs = reset;
  row.is_success = env_.IsSuccess(row.obs.achieved_goal, row.obs.desired_goal);
  row.contacts = env_.Contacts();
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
    r.past_time_limit = r.t > env_.spec().max_episode_steps;
    r.contacts = env_.Contacts();
    verify(r, t);
    episode.episode_return += result.reward;
    episode.steps.push_back(std::move(r));
    if (t + 1 == recorded.size()) episode.complete = whole;
    if (on_step && !on_step(episode.steps.back(), &result)) break;
  }
  return episode;
}

Observation ResetForStart(FetchEnv& env, const EpisodeStart& start) {
  if (start.seed) return env.Reset(start.seed);
  if (start.generator) {
    env.set_generator(*start.generator);
    return env.Reset();
  }
  return env.ResetTo(start.goal, start.object);
}

namespace {

// the label and unit of value i of `name` ("observation", "achieved_goal", "desired_goal"), from
// the observation's layout (src/observation_layout.h); an observation of neither layout's length
// has only its index
std::pair<std::string, std::string> Component(const char* name, size_t n, size_t i) {
  if (std::string(name) == "observation") {
    const std::optional<bool> has_object = LayoutHasObject(n);
    if (has_object && i < n) {
      return {ObservationIndexName(*has_object, i), ObservationIndexUnit(*has_object, i)};
    }
    return {"observation[" + std::to_string(i) + "]", ""};
  }
  return {GoalIndexName(name, i), kGoalUnit};
}

// compares one row; keeps the first value beyond the tolerance and the largest difference,
// each with its place
void CompareValues(const char* name, const std::vector<double>& recorded, const double* replayed,
                   size_t n, int t, EpisodeDivergence& d) {
  if (recorded.size() != n) {
    throw RunError("the dataset's " + std::string(name) + " has " +
                   std::to_string(recorded.size()) + " values, the env's " + std::to_string(n));
  }
  for (size_t i = 0; i < n; ++i) {
    const double diff = replayed[i] - recorded[i];
    const double size = std::isnan(diff) ? HUGE_VAL : std::fabs(diff);
    if (size > d.max_difference) {
      d.max_difference = size;
      d.max_step = t;
      d.max_where = std::string(name) + "[" + std::to_string(i) + "]";
      std::tie(d.max_component, d.max_unit) = Component(name, n, i);
      d.max_signed = diff;
    }
    if (d.first_step < 0 && size > d.tolerance) {
      d.first_step = t;
      d.where = std::string(name) + "[" + std::to_string(i) + "]";
      std::tie(d.component, d.unit) = Component(name, n, i);
      d.difference = diff;
    }
  }
}

// |replayed - recorded| of observation[at:at+3], a position, in metres
double PositionError(const std::vector<double>& recorded, const std::vector<double>& replayed,
                     size_t at) {
  double sum = 0;
  for (size_t i = at; i < at + 3 && i < recorded.size() && i < replayed.size(); ++i) {
    sum += (replayed[i] - recorded[i]) * (replayed[i] - recorded[i]);
  }
  return std::sqrt(sum);
}

void CompareRow(const StepRecord& recorded, const Observation& obs, int t, EpisodeDivergence& d) {
  CompareValues("observation", recorded.obs.observation, obs.observation.data(),
                obs.observation.size(), t, d);
  // the gripper's (grip_pos) and the object's (object_pos) positions, where the layout has them
  const std::optional<bool> has_object = LayoutHasObject(obs.observation.size());
  if (has_object) {
    const size_t grip = FindObservationSlice(*has_object, "grip_pos")->first;
    d.gripper_error.push_back(PositionError(recorded.obs.observation, obs.observation, grip));
  }
  if (has_object.value_or(false)) {
    const size_t object = FindObservationSlice(true, "object_pos")->first;
    d.object_error.push_back(PositionError(recorded.obs.observation, obs.observation, object));
  }
  const auto& a = recorded.obs.achieved_goal;
  const auto& g = recorded.obs.desired_goal;
  CompareValues("achieved_goal", {a.begin(), a.end()}, obs.achieved_goal.data(), 3, t, d);
  CompareValues("desired_goal", {g.begin(), g.end()}, obs.desired_goal.data(), 3, t, d);
}

}  // namespace

namespace {

// the reset gives the recorded first row bit for bit (-0.0 and 0.0 alike)
bool SameRow(const Observation& a, const Observation& b) {
  return a.observation == b.observation && a.achieved_goal == b.achieved_goal &&
         a.desired_goal == b.desired_goal;
}

}  // namespace

void ResolveStarts(FetchEnv& env, TrajectorySource* source) {
  std::optional<NumpyGenerator> chain;  // after the previous episode's reset, where it was exact
  int chain_from = -1, previous = -2;
  for (const auto& [k, episode] : source->episodes) {
    EpisodeStart& start = source->starts.at(k);
    if (!start.seed && chain && k == previous + 1) {  // try the generator continued
      env.set_generator(*chain);
      if (SameRow(env.Reset(), episode.steps.at(0).obs)) {
        start.generator = chain;
        start.continued_from = chain_from;
      }
    }
    previous = k;
    ResetForStart(env, start);
    if (start.seed) chain_from = k;
    if (start.seed || start.generator) {
      chain = env.generator();
    } else {
      chain.reset();
    }
  }
}

EpisodeDivergence CompareReplay(const TrajectorySource& source, int k,
                                const std::vector<Observation>& replayed) {
  const TrajectoryEpisode& episode = source.episodes.at(k);
  const EpisodeStart& start = source.starts.at(k);
  EpisodeDivergence d;
  d.reset = start.Rule();
  d.continued_from = start.continued_from;
  d.tolerance = source.tolerance;
  for (size_t t = 0; t < episode.steps.size() && t < replayed.size(); ++t) {
    CompareRow(episode.steps[t], replayed[t], static_cast<int>(t), d);
  }
  return d;
}

void MeasureDivergence(FetchEnv& env, TrajectorySource* source) {
  ResolveStarts(env, source);
  for (const auto& [k, episode] : source->episodes) {
    std::vector<Observation> replayed = {ResetForStart(env, source->starts.at(k))};
    for (size_t t = 1; t < episode.steps.size(); ++t) {
      replayed.push_back(env.Step(*episode.steps[t].action).obs);
    }
    source->divergence[k] = CompareReplay(*source, k, replayed);
  }
}

std::optional<std::array<double, 3>> RecordedAchieved(const TrajectorySource& source, int k,
                                                      int t) {
  if (!source.dataset || t < 0) return std::nullopt;
  const auto it = source.episodes.find(k);
  if (it == source.episodes.end() || t >= static_cast<int>(it->second.steps.size())) {
    return std::nullopt;
  }
  return it->second.steps[t].obs.achieved_goal;
}

void VerifyRecording(FetchEnv& env, const TrajectorySource& source) {
  if (source.dataset) return;  // a dataset may drift: MeasureDivergence reports it
  EpisodeReplayer replayer(env, source.seed);
  for (const auto& entry : source.episodes) replayer.ReplaySource(source, entry.first, nullptr);
}

std::optional<std::vector<int>> ReplayedEpisodes(const PolicySpec& policy, int episodes,
                                                 const std::string& env_id, uint64_t seed) {
  const Trajectory* read = policy.replay_trajectory();
  if (!read) return std::nullopt;
  const std::string& path = policy.replay()->path;
  if (read->episodes.empty()) throw RunError("replay file " + path + ": holds no episodes");
  std::vector<int> indices;
  for (const TrajectoryEpisode& e : read->episodes) indices.push_back(e.index);
  std::sort(indices.begin(), indices.end());
  if (episodes > 0 && episodes != static_cast<int>(indices.size())) {
    throw UsageError("--episodes " + std::to_string(episodes) + " disagrees with " + policy.text +
                     ", which holds " + std::to_string(indices.size()) +
                     " episode(s): a trajectory JSON replays all its episodes; drop --episodes");
  }
  // a different env or seed changes the result: refused, never a warning
  if (read->env_id != env_id || read->seed != seed) {
    throw UsageError(path + " was recorded on " + read->env_id + " with --seed " +
                     std::to_string(read->seed) + ", but this run names --env-id " + env_id +
                     " --seed " + std::to_string(seed) +
                     ": a trajectory JSON replays its own env and seed; drop --env-id and --seed "
                     "(or name the file's)");
  }
  return indices;
}

}  // namespace fetchscope
