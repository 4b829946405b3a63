#include "src/policy.h"

#include <filesystem>
#include <map>

#include "base/errors.h"
#include "base/suggest.h"
#include "src/exec_policy.h"
#include "src/replay_file.h"
#include "src/rng.h"
#include "src/scripted_policy.h"
#include "src/trajectory.h"

namespace fetchscope {
namespace {

// action_space.seed(S) + sample(): an independent generator, continued across episodes.
class RandomPolicy : public Policy {
 public:
  explicit RandomPolicy(uint64_t seed) : rng_(seed) {}
  Action Act(const Observation&, int) override {
    const std::array<float, 4> a = rng_.SampleActionBox();
    Action action;
    action.is_float32 = true;
    for (int i = 0; i < 4; ++i) action.value[i] = a[i];
    return action;
  }
  std::string name() const override { return "random"; }
  void SkipEpisode(int steps) override {
    for (int t = 0; t < steps; ++t) rng_.SampleActionBox();  // the same draws Act would make
  }

 private:
  NumpyGenerator rng_;
};

class ZeroPolicy : public Policy {
 public:
  Action Act(const Observation&, int) override { return Action{}; }
  std::string name() const override { return "zero"; }
};

// Rows are consumed in order across episodes: episode e step t uses row e * steps + t.
class ReplayPolicy : public Policy {
 public:
  ReplayPolicy(std::string spec, std::shared_ptr<const std::vector<Action>> rows, int steps)
      : spec_(std::move(spec)), rows_(std::move(rows)), steps_(steps) {}
  void BeginEpisode(int episode, const Observation&) override { episode_ = episode; }
  Action Act(const Observation&, int t) override {
    return rows_->at(static_cast<size_t>(episode_) * steps_ + t);
  }
  std::string name() const override { return spec_; }

 private:
  std::string spec_;
  std::shared_ptr<const std::vector<Action>> rows_;  // the spec's, shared by every worker
  int steps_;
  int episode_ = 0;
};

// A trajectory JSON's episodes, each played by its own index.
class TrajectoryReplayPolicy : public Policy {
 public:
  TrajectoryReplayPolicy(std::string spec, std::shared_ptr<const Trajectory> trajectory)
      : spec_(std::move(spec)), trajectory_(std::move(trajectory)) {
    for (const TrajectoryEpisode& e : trajectory_->episodes) episodes_[e.index] = &e;
  }
  void BeginEpisode(int episode, const Observation&) override { episode_ = episodes_.at(episode); }
  Action Act(const Observation&, int t) override {
    return *episode_->steps.at(static_cast<size_t>(t) + 1).action;
  }
  std::string name() const override { return spec_; }

 private:
  std::string spec_;
  std::shared_ptr<const Trajectory> trajectory_;
  std::map<int, const TrajectoryEpisode*> episodes_;  // into trajectory_, by index
  const TrajectoryEpisode* episode_ = nullptr;
};

std::string IndexList(const std::map<int, const TrajectoryEpisode*>& episodes) {
  std::string s;
  int shown = 0;
  for (const auto& [k, e] : episodes) {
    if (shown++ == 10) return s + ", ...";
    s += (s.empty() ? "" : ", ") + std::to_string(k);
  }
  return s;
}

// A trajectory JSON's episodes against the run: every episode it plays is there, with enough
// actions for --steps.
std::unique_ptr<Policy> MakeTrajectoryReplay(const std::string& spec, const std::string& path,
                                             std::shared_ptr<const Trajectory> trajectory,
                                             const PolicyContext& context) {
  if (trajectory->episodes.empty()) {
    throw RunError("replay file " + path + ": holds no episodes");
  }
  std::map<int, const TrajectoryEpisode*> episodes;
  for (const TrajectoryEpisode& e : trajectory->episodes) episodes[e.index] = &e;
  std::vector<int> wanted = context.episode_indices;
  if (wanted.empty()) {
    for (int k = 0; k < context.episodes; ++k) wanted.push_back(k);
  }
  const size_t steps = static_cast<size_t>(context.steps_per_episode);
  for (int k : wanted) {
    const auto it = episodes.find(k);
    if (it == episodes.end()) {
      throw RunError("replay file " + path + " holds episode(s) " + IndexList(episodes) +
                     " but this run plays episode " + std::to_string(k) +
                     " (a trajectory's episodes replay under their own index)");
    }
    const TrajectoryEpisode& e = *it->second;
    const size_t actions = e.steps.size() - 1;
    if (actions < steps) {
      throw RunError("replay file " + path + ": episode " + std::to_string(k) + " has " +
                     std::to_string(actions) + " actions" +
                     (e.complete ? "" : " (it is incomplete: interrupted while recording)") +
                     " but --steps " + std::to_string(steps) + " needs " + std::to_string(steps) +
                     ": pass --steps " + std::to_string(actions) +
                     (e.complete ? "" : ", or record that episode again"));
    }
  }
  return std::make_unique<TrajectoryReplayPolicy>(spec, std::move(trajectory));
}

std::unique_ptr<Policy> MakeReplay(const std::string& spec, const policy_spec::Replay& replay,
                                   const PolicyContext& context) {
  if (replay.trajectory) {
    return MakeTrajectoryReplay(spec, replay.path, replay.trajectory, context);
  }
  const size_t rows = replay.rows->size();
  const size_t need = static_cast<size_t>(context.steps_per_episode) * context.episodes;
  if (rows < need) {
    throw RunError("replay file '" + replay.path + "' has " + std::to_string(rows) +
                   " action rows but " + std::to_string(context.episodes) + " episode(s) of " +
                   std::to_string(context.steps_per_episode) + " steps need " +
                   std::to_string(need) + ": add rows, or pass --steps " +
                   std::to_string(rows / std::max(1, context.episodes)));
  }
  return std::make_unique<ReplayPolicy>(spec, replay.rows, context.steps_per_episode);
}

// A trajectory JSON carries its precision: --replay-dtype must agree with every episode's.
void CheckTrajectoryDtype(const Trajectory& trajectory, const std::string& dtype,
                          const std::string& path) {
  if (trajectory.episodes.empty()) {
    throw RunError("replay file " + path + ": holds no episodes");
  }
  if (dtype.empty()) return;
  std::map<int, const TrajectoryEpisode*> episodes;
  for (const TrajectoryEpisode& e : trajectory.episodes) episodes[e.index] = &e;
  for (const auto& [k, e] : episodes) {
    const std::string own = ActionDtype(*e);
    if (own != "none" && own != dtype) {
      throw UsageError("--replay-dtype " + dtype + ": replay file " + path + " records episode " +
                       std::to_string(k) + " in " + own +
                       " (its action_dtype); drop --replay-dtype, a trajectory JSON carries its "
                       "own precision");
    }
  }
}

// --replay-dtype on rows read from a file: float32 rounds CSV/JSON-lines values to float32;
// a .npy carries its dtype.
void ApplyReplayDtype(std::vector<Action>* rows, const std::string& dtype,
                      const std::string& format, const std::string& path) {
  if (dtype.empty()) return;
  if (format == "npy") {
    const bool f32 = !rows->empty() && rows->front().is_float32;
    if (f32 != (dtype == "float32")) {
      throw UsageError("--replay-dtype " + dtype + ": replay file " + path + " holds " +
                       (f32 ? "float32" : "float64") +
                       " (its .npy dtype); drop --replay-dtype, a .npy carries its own precision");
    }
    return;
  }
  if (dtype == "float64") return;
  for (Action& a : *rows) {
    for (double& v : a.value) v = static_cast<double>(static_cast<float>(v));
    a.is_float32 = true;
  }
}

// replay:FILE: the file read once, whatever its format; a .json is a trajectory when it holds
// one, else rows.
policy_spec::Replay ReadReplay(const std::string& path, const std::string& dtype) {
  policy_spec::Replay replay;
  replay.path = path;
  replay.dtype = dtype;
  std::string format;
  const std::string bytes = ReadReplayBytes(path, &format);
  if (format == "json") {
    if (std::optional<Trajectory> trajectory = ParseReplayTrajectory(bytes, path)) {
      CheckTrajectoryDtype(*trajectory, dtype, path);
      replay.trajectory = std::make_shared<const Trajectory>(std::move(*trajectory));
      return replay;
    }
  }
  std::vector<Action> rows = ParseReplayText(bytes, format, path);
  ApplyReplayDtype(&rows, dtype, format, path);
  replay.rows = std::make_shared<const std::vector<Action>>(std::move(rows));
  return replay;
}

template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};
template <class... F>
Overloaded(F...) -> Overloaded<F...>;

}  // namespace

PolicySpec ParsePolicySpec(const std::string& text, const PolicyOptions& options) {
  // the name, with its ':' for the policies that take an argument ("replay:", "exec:"): what
  // gets mistyped ("scriptd", "replya:a.csv")
  const size_t colon = text.find(':');
  const std::string name = colon == std::string::npos ? text : text.substr(0, colon + 1);
  const std::string argument = colon == std::string::npos ? "" : text.substr(colon + 1);
  const bool replay = name == "replay:";  // the one place that tells a replay by its prefix
  const std::string& dtype = options.replay_dtype;
  if (!dtype.empty()) {
    if (dtype != "float32" && dtype != "float64") {
      throw UsageError("--replay-dtype '" + dtype + "' is not known; accepted: float32, float64");
    }
    if (!replay) {
      throw UsageError("--replay-dtype applies to --policy replay:FILE only, not to '" + text +
                       "'");
    }
  }
  if (text == "random") return PolicySpec::Random();
  if (text == "zero") return PolicySpec::Zero();
  if (text == "scripted") return PolicySpec::Scripted();
  if (replay) {
    if (argument.empty()) {
      throw UsageError("--policy replay: needs a file, e.g. replay:actions.csv");
    }
    const std::string path = options.base_dir.empty()
                                 ? argument
                                 : (std::filesystem::path(options.base_dir) / argument).string();
    return {ReadReplay(path, dtype), text};
  }
  if (name == "exec:") {
    if (argument.empty()) {
      throw UsageError("--policy exec: needs a command, e.g. exec:'python3 my_policy.py'");
    }
    return {policy_spec::Exec{argument, options.exec_timeout_s, {}}, text};
  }
  throw UsageError(
      "unknown policy '" + text + "'" +
      DidYouMean(name, std::vector<std::string>(std::begin(kPolicyNames), std::end(kPolicyNames))) +
      ": use " + kPolicyHelp);
}

std::unique_ptr<Policy> MakePolicy(const PolicySpec& spec, const EnvSpec& env,
                                   const PolicyContext& context) {
  using Made = std::unique_ptr<Policy>;
  return std::visit(
      Overloaded{
          [&](const policy_spec::Random&) -> Made {
            return std::make_unique<RandomPolicy>(context.seed);
          },
          [&](const policy_spec::Zero&) -> Made { return std::make_unique<ZeroPolicy>(); },
          [&](const policy_spec::Scripted&) -> Made { return MakeScriptedPolicy(env); },
          [&](const policy_spec::Replay& replay) -> Made {
            return MakeReplay(spec.text, replay, context);
          },
          [&](const policy_spec::Exec& exec) -> Made {
            return MakeExecPolicy(exec, context.stop_requested, context.images);
          },
      },
      spec.value);
}

}  // namespace fetchscope
