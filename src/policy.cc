#include "src/policy.h"

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
  ReplayPolicy(std::string spec, std::vector<Action> rows, int steps)
      : spec_(std::move(spec)), rows_(std::move(rows)), steps_(steps) {}
  void BeginEpisode(int episode, const Observation&) override { episode_ = episode; }
  Action Act(const Observation&, int t) override {
    return rows_.at(static_cast<size_t>(episode_) * steps_ + t);
  }
  std::string name() const override { return spec_; }

 private:
  std::string spec_;
  std::vector<Action> rows_;
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

std::unique_ptr<Policy> MakeTrajectoryReplay(const std::string& spec, const std::string& path,
                                             std::shared_ptr<const Trajectory> trajectory,
                                             const PolicyContext& context) {
  if (trajectory->episodes.empty()) {
    throw RunError("replay file " + path + ": holds no episodes");
  }
  std::map<int, const TrajectoryEpisode*> episodes;
  for (const TrajectoryEpisode& e : trajectory->episodes) episodes[e.index] = &e;
  if (!context.replay_dtype.empty()) {
    for (const auto& [k, e] : episodes) {
      const std::string dtype = ActionDtype(*e);
      if (dtype != "none" && dtype != context.replay_dtype) {
        throw UsageError("--replay-dtype " + context.replay_dtype + ": replay file " + path +
                         " records episode " + std::to_string(k) + " in " + dtype +
                         " (its action_dtype); drop --replay-dtype, a trajectory JSON carries its "
                         "own precision");
      }
    }
  }
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

// --replay-dtype on rows read from a file: float32 rounds CSV/JSON-lines values to float32;
// a .npy carries its dtype.
void ApplyReplayDtype(std::vector<Action>* rows, const std::string& dtype,
                      const std::string& path) {
  if (dtype.empty()) return;
  if (dtype != "float32" && dtype != "float64") {
    throw UsageError("--replay-dtype '" + dtype + "' is not known; accepted: float32, float64");
  }
  const bool npy = path.size() >= 4 && (path.compare(path.size() - 4, 4, ".npy") == 0 ||
                                        path.compare(path.size() - 4, 4, ".NPY") == 0);
  if (npy) {
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

}  // namespace

std::unique_ptr<Policy> MakePolicy(const std::string& spec, const EnvSpec& env,
                                   const PolicyContext& context) {
  if (!context.replay_dtype.empty()) {
    if (context.replay_dtype != "float32" && context.replay_dtype != "float64") {
      throw UsageError("--replay-dtype '" + context.replay_dtype +
                       "' is not known; accepted: float32, float64");
    }
    if (spec.rfind("replay:", 0) != 0) {
      throw UsageError("--replay-dtype applies to --policy replay:FILE only, not to '" + spec +
                       "'");
    }
  }
  if (spec == "random") return std::make_unique<RandomPolicy>(context.seed);
  if (spec == "zero") return std::make_unique<ZeroPolicy>();
  if (spec == "scripted") return MakeScriptedPolicy(env);
  if (spec.rfind("replay:", 0) == 0) {
    const std::string path = spec.substr(7);
    if (path.empty()) throw UsageError("--policy replay: needs a file, e.g. replay:actions.csv");
    if (context.replay_trajectory) {  // read once already (ReadReplayedEpisodes)
      return MakeTrajectoryReplay(spec, path, context.replay_trajectory, context);
    }
    if (std::optional<Trajectory> trajectory = ReadReplayTrajectory(path)) {
      return MakeTrajectoryReplay(
          spec, path, std::make_shared<const Trajectory>(std::move(*trajectory)), context);
    }
    std::vector<Action> rows = ReadReplayFile(path);
    ApplyReplayDtype(&rows, context.replay_dtype, path);
    const size_t need = static_cast<size_t>(context.steps_per_episode) * context.episodes;
    if (rows.size() < need) {
      throw RunError("replay file '" + path + "' has " + std::to_string(rows.size()) +
                     " action rows but " + std::to_string(context.episodes) + " episode(s) of " +
                     std::to_string(context.steps_per_episode) + " steps need " +
                     std::to_string(need) + ": add rows, or pass --steps " +
                     std::to_string(rows.size() / std::max(1, context.episodes)));
    }
    return std::make_unique<ReplayPolicy>(spec, std::move(rows), context.steps_per_episode);
  }
  if (spec.rfind("exec:", 0) == 0) {
    const std::string command = spec.substr(5);
    if (command.empty())
      throw UsageError("--policy exec: needs a command, e.g. exec:'python3 my_policy.py'");
    return MakeExecPolicy(command, context.exec_timeout_s, context.stop_requested);
  }

  // the name before a ':' is what gets mistyped ("scriptd", "replya:a.csv")
  const size_t colon = spec.find(':');
  const std::string name = colon == std::string::npos ? spec : spec.substr(0, colon + 1);
  throw UsageError("unknown policy '" + spec + "'" +
                   DidYouMean(name, {"random", "zero", "scripted", "replay:", "exec:"}) + ": use " +
                   kPolicyHelp);
}

}  // namespace fetchscope
