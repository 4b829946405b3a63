// fetchscope random-episodes: baseline metrics of the seeded random policy. --jobs runs the
// episodes on the episode scheduler's worker processes; the JSON is byte-identical to --jobs 1.
#include <signal.h>

#include <cstdio>

#include "base/errors.h"
#include "base/json_util.h"
#include "cli/chapter.h"
#include "cli/command.h"
#include "cli/common.h"
#include "cli/jobs_options.h"
#include "cli/resolve.h"
#include "run/episode_scheduler.h"
#include "run/progress.h"
#include "run/random_episodes_run.h"
#include "src/fetch_env.h"

namespace fetchscope::cli {
namespace {

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

// parse (AddRandomEpisodes) -> resolve -> run (RunRandomEpisodesJob) -> print.
int RunRandomEpisodes(const RandomEpisodesOptions& o) {
  const ResolvedEnv env = ResolveEnv(o.env);
  const EnvSpec& spec = *env.spec;
  const uint64_t seed = env.seed;
  const WorkerMode mode = ParseWorkerMode(o.worker_mode);
  const std::string path = JsonOutPath(o.json_out, "random_metrics");
  CheckJsonOutReplaces(path, {{"env_id", spec.id}, {"seed", seed}}, o.overwrite);
  FetchEnv fetch(spec, env.assets);  // bad assets fail here, before any worker starts
  RandomEpisodesJob job;
  job.spec = &spec;
  job.assets = env.assets;
  job.seed = seed;
  job.episodes = o.n_episodes;
  job.jobs = ResolveJobs(o.jobs, o.n_episodes);
  job.mode = mode;
  ProgressReporter progress = ProgressReporter::ForLongRuns("random-episodes", o.n_episodes,
                                                            spec.max_episode_steps, "steps");
  job.on_episode = [&] { progress.EpisodeDone(spec.max_episode_steps); };
  const RandomMetrics m = RunRandomEpisodesJob(job);
  progress.Clear();
  if (m.signal) {
    std::fprintf(stderr, "random-episodes: interrupted (%s); nothing written\n",
                 m.signal == SIGINT ? "SIGINT" : "SIGTERM");
    return 128 + m.signal;
  }
  nlohmann::json j = RandomMetricsJson(job, m, fetch.assets());
  const std::string chapter = MeanReturnVersusChapter(spec, m.mean_return, o.n_episodes, seed);
  if (!chapter.empty()) j["chapter_differences"] = {chapter};
  if (o.json_out.empty()) {
    std::printf("%s\n", DumpJson(j).c_str());
    return 0;
  }
  WriteJson(path, j);
  std::printf(
      "%s, %d random episodes (seed %s): success rate %.3f, mean return %.3f (std %.3f), "
      "mean length %.1f, mean final distance %.4f m\nwrote %s\n",
      spec.id.c_str(), o.n_episodes, o.env.seed.c_str(), m.success_rate, m.mean_return,
      m.std_return, m.mean_length, m.mean_final_distance, path.c_str());
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
