// fetchscope rollout: episodes without rendering, written as trajectory JSON. --jobs runs them
// on the episode scheduler's worker processes; the JSON is byte-identical to --jobs 1.
#include <signal.h>

#include <cstdio>

#include "base/errors.h"
#include "base/json_util.h"
#include "cli/command.h"
#include "cli/common.h"
#include "cli/resolve.h"
#include "run/episode_scheduler.h"
#include "src/episode.h"
#include "src/fetch_env.h"

namespace fetchscope::cli {
namespace {

struct RolloutOptions {
  EnvOptions env;
  int episodes = 1;
  bool episodes_given = false;  // --episodes was on the command line
  int steps = 50;
  std::string policy = "random";
  std::string json_out;
  bool overwrite = false;  // replace a --json-out file of another env or seed
  double exec_timeout = 10.0;
  std::string replay_dtype;
  int jobs = 1;
  std::string worker_mode = "process";
};

// Plays episodes and reports each as its trajectory JSON entry.
class RolloutRunner : public EpisodeRunner {
 public:
  RolloutRunner(const EnvSpec& spec, const AssetSource& assets, const std::string& policy,
                const PolicyContext& context, int steps)
      : sequence_(std::make_unique<FetchEnv>(spec, assets), MakePolicy(policy, spec, context),
                  context.seed, steps) {}
  void Run(int k, WorkerChannel& channel) override {
    const EpisodeRecord episode = sequence_.Play(
        k, [&](const StepRecord&, const StepResult*) { return !channel.StopRequested(); });
    channel.Progress(static_cast<int>(episode.steps.size()) - 1);
    channel.Done(k, EpisodeJson(episode));
  }

 private:
  EpisodeSequence sequence_;
};

int RunRollout(const RolloutOptions& o) {
  EpisodeRequest request;
  request.policy = o.policy;
  request.episodes = o.episodes;
  request.episodes_given = o.episodes_given;
  request.steps = o.steps;
  request.exec_timeout_s = o.exec_timeout;
  request.replay_dtype = o.replay_dtype;
  const WorkerMode mode = ParseWorkerMode(o.worker_mode);
  // a trajectory JSON replays its own episodes, each under its own index (as record does)
  const ResolvedRun run = ResolveRun(o.env, request);
  const EnvSpec& spec = *run.env.spec;
  const uint64_t seed = run.env.seed;
  const AssetSource& assets = run.env.assets;
  const std::vector<int>& indices = run.episodes;
  const PolicyContext& context = run.policy_context;
  const std::string path = JsonOutPath(o.json_out, "rollout");
  CheckJsonOutReplaces(path, {{"env_id", spec.id}, {"seed", seed}}, o.overwrite);
  { FetchEnv check(spec, assets); }  // bad assets fail here, before any worker starts
  ScheduleOptions schedule;
  schedule.episodes = indices;
  const int count = static_cast<int>(indices.size());
  schedule.jobs = ResolveJobs(o.jobs, count);
  schedule.mode = mode;
  const ScheduleResult result = RunEpisodes(schedule, [&](int) {
    return std::make_unique<RolloutRunner>(spec, assets, o.policy, context, o.steps);
  });
  if (!result.failures.empty()) {
    if (result.failures.front().usage) throw UsageError(result.failures.front().message);
    throw RunError(DescribeFailures(result));
  }
  if (result.signal) {
    std::fprintf(stderr, "rollout: interrupted (%s); nothing written\n",
                 result.signal == SIGINT ? "SIGINT" : "SIGTERM");
    return 128 + result.signal;
  }
  nlohmann::json episodes = nlohmann::json::array();
  int successes = 0;
  for (const auto& [k, episode] : result.results) {
    successes += episode.at("is_success").get<bool>();
    episodes.push_back(episode);
  }
  const nlohmann::json j = TrajectoryJson(spec, assets, seed, o.policy, std::move(episodes));
  if (o.json_out.empty()) {
    std::printf("%s\n", DumpJson(j).c_str());
    return 0;
  }
  WriteJson(path, j);
  std::printf(
      "%s: %d episode(s) of %d steps, policy %s, seed %s: success %d/%d (%.0f%%)\nwrote %s\n",
      spec.id.c_str(), count, o.steps, o.policy.c_str(), o.env.seed.c_str(), successes, count,
      100.0 * successes / count, path.c_str());
  return 0;
}

}  // namespace

Command AddRollout(CLI::App& app) {
  auto o = std::make_shared<RolloutOptions>();
  CLI::App* sub =
      app.add_subcommand("rollout", "Run episodes without rendering and write the trajectory JSON");
  AddEnvOptions(sub, &o->env);
  sub->add_option("--episodes", o->episodes,
                  "Number of episodes (a replay:FILE.json trajectory plays its own episodes)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  sub->add_option("--steps", o->steps, "Steps per episode (TimeLimit is 50)")
      ->capture_default_str()
      ->check(CLI::Range(1, 50));
  sub->add_option("--policy", o->policy, kPolicyHelp)->capture_default_str();
  sub->add_option("--exec-timeout", o->exec_timeout, "Seconds an exec: policy may take per answer")
      ->capture_default_str()
      ->check(CLI::Range(0.001, 86400.0));
  sub->add_option("--replay-dtype", o->replay_dtype, kReplayDtypeHelp);
  sub->add_option("--json-out", o->json_out,
                  "Write F (.json), F/rollout.json if F ends in /, or F_rollout.json; without it "
                  "JSON goes to stdout");
  sub->add_flag("--overwrite", o->overwrite, kJsonOverwriteHelp);
  AddJobsOptions(sub, &o->jobs, &o->worker_mode);
  return {sub, [o, sub] {
            o->episodes_given = sub->count("--episodes") > 0;
            return RunRollout(*o);
          }};
}

}  // namespace fetchscope::cli
