#include "src/policy.h"

#include "src/errors.h"
#include "src/replay_file.h"
#include "src/rng.h"
#include "src/scripted_policy.h"
#include "src/exec_policy.h"

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

}  // namespace

std::unique_ptr<Policy> MakePolicy(const std::string& spec, const EnvSpec& env,
                                   const PolicyContext& context) {
  if (spec == "random") return std::make_unique<RandomPolicy>(context.seed);
  if (spec == "zero") return std::make_unique<ZeroPolicy>();
  if (spec == "scripted") return MakeScriptedPolicy(env);
  if (spec.rfind("replay:", 0) == 0) {
    const std::string path = spec.substr(7);
    if (path.empty()) throw UsageError("--policy replay: needs a file, e.g. replay:actions.csv");
    std::vector<Action> rows = ReadReplayFile(path);
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
    if (command.empty()) throw UsageError("--policy exec: needs a command, e.g. exec:'python3 my_policy.py'");
    return MakeExecPolicy(command, context.exec_timeout_s);
  }
  throw UsageError("unknown policy '" + spec + "': use " + kPolicyHelp);
}

}  // namespace fetchscope
