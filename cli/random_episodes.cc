// fetchscope random-episodes: baseline metrics of the seeded random policy. --jobs runs the
// episodes on the episode scheduler's worker processes; the JSON is byte-identical to --jobs 1.
#include <signal.h>

#include <cmath>
#include <cstdio>

#include "base/errors.h"
#include "base/json_util.h"
#include "cli/chapter.h"
#include "cli/command.h"
#include "cli/common.h"
#include "cli/jobs_options.h"
#include "cli/resolve.h"
#include "run/episode_scheduler.h"
#include "src/episode.h"
#include "src/fetch_env.h"

namespace fetchscope::cli {
namespace {

// Plays random episodes and reports each one's row of the metrics.
class RandomEpisodeRunner : public EpisodeRunner {
 public:
  RandomEpisodeRunner(const EnvSpec& spec, const AssetSource& assets, const PolicyContext& context)
      : sequence_(std::make_unique<FetchEnv>(spec, assets), MakePolicy("random", spec, context),
                  context.seed, spec.max_episode_steps) {}
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

// The chapter's D3 expects a dense mean return of -15 to -25 on FetchReachDense-v4; a line
// saying what this run measured when it lies outside that ("" inside it, or for another env).
std::string MeanReturnVersusChapter(const EnvSpec& spec, double mean, int episodes, uint64_t seed) {
  if (spec.id != "FetchReachDense-v4") return "";
  if (mean >= kChapterDenseReturnLow && mean <= kChapterDenseReturnHigh) return "";
  char line[256];
  std::snprintf(line, sizeof(line),
                "mean return %.1f (the chapter expects %.0f to %.0f): measured over these %d "
                "random episodes, seed %llu",
                mean, kChapterDenseReturnHigh, kChapterDenseReturnLow, episodes,
                static_cast<unsigned long long>(seed));
  return line;
}

}  // namespace

int RunRandomEpisodes(const RandomEpisodesOptions& o) {
  const ResolvedEnv env = ResolveEnv(o.env);
  const EnvSpec& spec = *env.spec;
  const uint64_t seed = env.seed;
  const AssetSource& assets = env.assets;
  const WorkerMode mode = ParseWorkerMode(o.worker_mode);
  const std::string path = JsonOutPath(o.json_out, "random_metrics");
  CheckJsonOutReplaces(path, {{"env_id", spec.id}, {"seed", seed}}, o.overwrite);
  FetchEnv fetch(spec, assets);  // bad assets fail here, before any worker starts
  PolicyContext context;
  context.seed = seed;
  ScheduleOptions schedule;
  for (int k = 0; k < o.n_episodes; ++k) schedule.episodes.push_back(k);
  schedule.jobs = ResolveJobs(o.jobs, o.n_episodes);
  schedule.mode = mode;
  const ScheduleResult result = RunEpisodes(
      schedule, [&](int) { return std::make_unique<RandomEpisodeRunner>(spec, assets, context); });
  if (!result.failures.empty()) {
    if (result.failures.front().usage) throw UsageError(result.failures.front().message);
    throw RunError(DescribeFailures(result));
  }
  if (result.signal) {
    std::fprintf(stderr, "random-episodes: interrupted (%s); nothing written\n",
                 result.signal == SIGINT ? "SIGINT" : "SIGTERM");
    return 128 + result.signal;
  }
  nlohmann::json rows = nlohmann::json::array();
  std::vector<double> returns, finals;
  double successes = 0, total_length = 0;
  for (const auto& [k, row] : result.results) {  // in episode order, whichever worker ran it
    returns.push_back(row.at("return").get<double>());
    finals.push_back(row.at("final_distance").get<double>());
    successes += row.at("is_success").get<bool>();
    total_length += row.at("length").get<int>();
    rows.push_back(row);
  }
  const double n = o.n_episodes;
  double mean = 0, var = 0, mean_final = 0;
  for (double r : returns) mean += r / n;
  for (double r : returns) var += (r - mean) * (r - mean) / n;
  for (double f : finals) mean_final += f / n;
  nlohmann::json j = {{"env_id", spec.id},
                      {"seed", seed},
                      {"policy", "random"},
                      {"n_episodes", o.n_episodes},
                      {"success_rate", successes / n},
                      {"mean_return", mean},
                      // the population standard deviation (numpy's np.std default, ddof=0)
                      {"std_return", std::sqrt(var)},
                      {"std_return_ddof", 0},
                      {"mean_episode_length", total_length / n},
                      {"mean_final_distance", mean_final},
                      {"final_distances", finals},
                      {"episodes", rows},
                      {"assets", AssetsJson(fetch.assets())},
                      {"versions", VersionsJson()}};
  const std::string chapter = MeanReturnVersusChapter(spec, mean, o.n_episodes, seed);
  if (!chapter.empty()) j["chapter_differences"] = {chapter};
  if (o.json_out.empty()) {
    std::printf("%s\n", DumpJson(j).c_str());
    return 0;
  }
  WriteJson(path, j);
  std::printf(
      "%s, %d random episodes (seed %s): success rate %.3f, mean return %.3f (std %.3f), "
      "mean length %.1f, mean final distance %.4f m\nwrote %s\n",
      spec.id.c_str(), o.n_episodes, o.env.seed.c_str(), successes / n, mean, std::sqrt(var),
      total_length / n, mean_final, path.c_str());
  if (!chapter.empty()) std::printf("differs from the chapter: %s\n", chapter.c_str());
  return 0;
}

Command AddRandomEpisodes(CLI::App& app) {
  auto o = std::make_shared<RandomEpisodesOptions>();
  CLI::App* sub = app.add_subcommand(
      "random-episodes",
      "Random-policy baseline: success rate, mean and std of returns (std over episodes with "
      "ddof=0, numpy's np.std default), lengths, final distances");
  AddEnvOptions(sub, &o->env);
  sub->add_option("--n-episodes", o->n_episodes, "Episodes to run")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  sub->add_option("--json-out", o->json_out,
                  "Write P (.json), P/random_metrics.json if P ends in /, or "
                  "P_random_metrics.json; without it JSON goes to stdout. A mean return outside "
                  "the course chapter's expected range gets a line saying so");
  sub->add_flag("--overwrite", o->overwrite, kJsonOverwriteHelp);
  AddJobsOptions(sub, &o->jobs, &o->worker_mode);
  return {sub, [o] { return RunRandomEpisodes(*o); }};
}

}  // namespace fetchscope::cli
