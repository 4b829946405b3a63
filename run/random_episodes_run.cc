#include "run/random_episodes_run.h"

#include <cmath>
#include <memory>

#include "base/errors.h"
#include "base/json_util.h"
#include "src/episode.h"
#include "src/fetch_env.h"
#include "src/policy.h"
#include "src/trajectory.h"
#include "src/versions.h"

namespace fetchscope {
namespace {

// Plays random episodes and reports each one's row of the metrics.
class RandomEpisodeRunner : public EpisodeRunner {
 public:
  RandomEpisodeRunner(const EnvSpec& spec, const AssetSource& assets, const PolicyContext& context)
      : sequence_(std::make_unique<FetchEnv>(spec, assets),
                  MakePolicy(PolicySpec::Random(), spec, context), context.seed,
                  spec.max_episode_steps) {}
  void Run(int k, WorkerChannel& channel) override {
    const EpisodeRecord ep = sequence_.Play(
        k, [&](const StepRecord&, const StepResult*) { return !channel.StopRequested(); });
    const StepRecord& last = ep.steps.back();
    channel.Done(k,
                 {{"index", k},
                  {"return", JsonDouble(ep.episode_return)},
                  {"length", static_cast<int>(ep.steps.size()) - 1},
                  {"is_success", last.is_success},
                  {"final_distance", GoalDistance(last.obs.achieved_goal, last.obs.desired_goal)}});
  }

 private:
  EpisodeSequence sequence_;
};

}  // namespace

RandomMetrics RunRandomEpisodesJob(const RandomEpisodesJob& job) {
  PolicyContext context;
  context.seed = job.seed;
  ScheduleOptions schedule;
  for (int k = 0; k < job.episodes; ++k) schedule.episodes.push_back(k);
  schedule.jobs = job.jobs;
  schedule.mode = job.mode;
  if (job.on_episode) schedule.on_done = [&](int, const nlohmann::json&) { job.on_episode(); };
  const ScheduleResult result = RunEpisodes(schedule, [&](int) {
    return std::make_unique<RandomEpisodeRunner>(*job.spec, job.assets, context);
  });
  if (!result.failures.empty()) {
    if (result.failures.front().usage) throw UsageError(result.failures.front().message);
    throw RunError(DescribeFailures(result));
  }
  RandomMetrics m;
  if (result.signal) {
    m.signal = result.signal;
    return m;
  }
  std::vector<double> returns;
  double successes = 0, total_length = 0;
  for (const auto& [k, row] : result.results) {  // in episode order, whichever worker ran it
    returns.push_back(row.at("return").get<double>());
    m.final_distances.push_back(row.at("final_distance").get<double>());
    successes += row.at("is_success").get<bool>();
    total_length += row.at("length").get<int>();
    m.rows.push_back(row);
  }
  const double n = job.episodes;
  double var = 0;
  for (double r : returns) m.mean_return += r / n;
  for (double r : returns) var += (r - m.mean_return) * (r - m.mean_return) / n;
  for (double f : m.final_distances) m.mean_final_distance += f / n;
  m.success_rate = successes / n;
  m.std_return = std::sqrt(var);
  m.mean_length = total_length / n;
  return m;
}

nlohmann::json RandomMetricsJson(const RandomEpisodesJob& job, const RandomMetrics& m,
                                 const AssetSource& loaded) {
  return {{"env_id", job.spec->id},
          {"seed", job.seed},
          {"policy", "random"},
          {"n_episodes", job.episodes},
          {"success_rate", m.success_rate},
          {"mean_return", m.mean_return},
          // the population standard deviation (numpy's np.std default, ddof=0)
          {"std_return", m.std_return},
          {"std_return_ddof", 0},
          {"mean_episode_length", m.mean_length},
          {"mean_final_distance", m.mean_final_distance},
          {"final_distances", m.final_distances},
          {"episodes", m.rows},
          {"assets", AssetsJson(loaded)},
          {"versions", VersionsJson()}};
}

}  // namespace fetchscope
