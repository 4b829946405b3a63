// fetchscope rollout: episodes without rendering, written as trajectory JSON. --jobs runs them
// on the episode scheduler's worker processes; the JSON is byte-identical to --jobs 1.
#include <signal.h>

#include <cstdio>

#include "base/errors.h"
#include "base/json_util.h"
#include "cli/command.h"
#include "cli/common.h"
#include "cli/jobs_options.h"
#include "cli/resolve.h"
#include "dataset/minari_trajectory.h"
#include "dataset/minari_writer.h"
#include "run/episode_scheduler.h"
#include "src/episode.h"
#include "src/fetch_env.h"
#include "src/observation_layout.h"
#include "src/trajectory.h"

namespace fetchscope::cli {
namespace {

struct RolloutOptions {
  EnvOptions env;
  int episodes = 1;
  bool episodes_given = false;  // --episodes was on the command line
  int steps = 50;
  std::string policy = "random";
  std::string json_out;
  double exec_timeout = 10.0;
  std::string replay_dtype;
  int jobs = 1;
  std::string worker_mode = "process";
  std::string minari;       // --minari: a Minari dataset id to write
  std::string minari_root;  // --minari-root
  bool overwrite =
      false;  // replace an existing Minari dataset, or a --json-out file of another env or seed
  DatasetAuthor author;  // --minari-author, --minari-author-email
};

// The played episodes as a Minari dataset, added as they arrive (in index order: the scheduler
// reports them as workers finish), so that writing overlaps the simulation instead of following
// it. Each goes through the trajectory reader on its own. Nothing is left behind unless Commit.
class MinariSink {
 public:
  MinariSink(const RolloutOptions& o, const MinariWriteOptions& options, const AssetSource& assets,
             uint64_t seed, std::vector<int> indices)
      : o_(o), assets_(assets), seed_(seed), writer_(options), indices_(std::move(indices)) {
    width_ = ObservationSize(options.spec->has_object);
    spec_ = options.spec;
  }

  void Done(int k, const nlohmann::json& episode) {
    if (stopped_) return;  // SIGINT/SIGTERM: the run ends as interrupted, the dataset unwritten
    pending_.emplace(k, episode);
    while (next_ < indices_.size()) {
      const auto it = pending_.find(indices_[next_]);
      if (it == pending_.end()) break;
      const Trajectory one = ParseTrajectoryJson(
          TrajectoryJson(*spec_, assets_, seed_, o_.policy, nlohmann::json::array({it->second})),
          "rollout");
      // episode 0 was reset with the run's seed; the others continued its generator
      try {
        writer_.Add(ToMinariEpisode(one.episodes.front(),
                                    it->first == 0 ? std::optional<uint64_t>(seed_) : std::nullopt,
                                    width_));
      } catch (const MinariInterrupted&) {  // the scheduler reports the signal when it returns
        stopped_ = true;
        pending_.clear();
        return;
      }
      pending_.erase(it);
      ++next_;
    }
  }

  /// Every episode added: renames the dataset into place and returns its folder.
  std::string Commit() { return writer_.Commit().string(); }

 private:
  const RolloutOptions& o_;
  const AssetSource& assets_;
  uint64_t seed_;
  MinariWriter writer_;
  const EnvSpec* spec_ = nullptr;
  int width_ = 10;
  std::vector<int> indices_;
  size_t next_ = 0;  // indices_[next_] is the next episode to add
  std::map<int, nlohmann::json> pending_;
  bool stopped_ = false;  // a stop signal arrived while adding: add nothing more
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
  const int count = static_cast<int>(indices.size());
  MinariWriteOptions minari;
  if (!o.minari.empty()) {
    minari.dataset_id = o.minari;
    minari.root = MinariRoot(o.minari_root);
    minari.overwrite = o.overwrite;
    minari.spec = &spec;
    minari.algorithm_name = o.policy;
    minari.code_permalink = DatasetPermalink("rollout", spec.id, o.policy, seed, count, o.steps);
    minari.max_episode_steps = o.steps;  // gym.make(id, max_episode_steps=--steps)
    if (!o.author.name.empty()) minari.author = o.author.name;
    minari.author_email = o.author.email;
    minari.description = spec.id + " episodes played by fetchscope's " + o.policy + " policy";
    CheckMinariDestination(minari);  // an existing id fails now, not after the run
  }
  std::unique_ptr<MinariSink> sink;
  if (!o.minari.empty()) sink = std::make_unique<MinariSink>(o, minari, assets, seed, indices);
  ScheduleOptions schedule;
  schedule.episodes = indices;
  if (sink) schedule.on_done = [&](int k, const nlohmann::json& e) { sink->Done(k, e); };
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
  std::string dataset;
  try {
    if (sink) dataset = sink->Commit();
  } catch (const MinariInterrupted& e) {  // a signal after the last episode: still nothing
    std::fprintf(stderr, "rollout: %s; nothing written\n", e.what());
    return 128 + e.signal;
  }
  nlohmann::json episodes = nlohmann::json::array();
  int successes = 0;
  for (const auto& [k, episode] : result.results) {
    successes += episode.at("is_success").get<bool>();
    episodes.push_back(episode);
  }
  if (o.json_out.empty() && dataset.empty()) {
    const nlohmann::json j = TrajectoryJson(spec, assets, seed, o.policy, std::move(episodes));
    std::printf("%s\n", DumpJson(j).c_str());
    return 0;
  }
  std::string wrote;
  if (!o.json_out.empty()) {
    WriteJson(path, TrajectoryJson(spec, assets, seed, o.policy, std::move(episodes)));
    wrote += "wrote " + path + "\n";
  }
  if (!dataset.empty()) wrote += "wrote Minari dataset " + o.minari + " at " + dataset + "\n";
  std::printf("%s: %d episode(s) of %d steps, policy %s, seed %s: success %d/%d (%.0f%%)\n%s",
              spec.id.c_str(), count, o.steps, o.policy.c_str(), o.env.seed.c_str(), successes,
              count, 100.0 * successes / count, wrote.c_str());
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
  sub->add_option("--steps", o->steps, kStepsHelp)
      ->capture_default_str()
      ->check(CLI::Range(1, kMaxSteps));
  sub->add_option("--policy", o->policy, kPolicyHelp)->capture_default_str();
  sub->add_option("--exec-timeout", o->exec_timeout, "Seconds an exec: policy may take per answer")
      ->capture_default_str()
      ->check(CLI::Range(0.001, 86400.0));
  sub->add_option("--replay-dtype", o->replay_dtype, kReplayDtypeHelp);
  sub->add_option("--json-out", o->json_out,
                  "Write F (.json), F/rollout.json if F ends in /, or F_rollout.json; without it "
                  "JSON goes to stdout");
  sub->add_option(
      "--minari", o->minari,
      "Also write the episodes as a Minari dataset of this id, e.g. "
      "fetchscope/FetchPush/scripted-v0 (docs/guide/datasets.md); without --json-out no "
      "JSON is printed");
  sub->add_option("--minari-root", o->minari_root,
                  "Datasets root (default $MINARI_DATASETS_PATH, else ~/.minari/datasets)");
  sub->add_flag("--overwrite", o->overwrite,
                "Replace an existing Minari dataset of that id, and let --json-out replace a "
                "result file of another env, seed or task");
  AddDatasetAuthorOptions(sub, &o->author);
  AddJobsOptions(sub, &o->jobs, &o->worker_mode);
  return {sub, [o, sub] {
            o->episodes_given = sub->count("--episodes") > 0;
            return RunRollout(*o);
          }};
}

}  // namespace fetchscope::cli
