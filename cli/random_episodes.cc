// fetchscope random-episodes: baseline metrics of the seeded random policy.
#include <cmath>
#include <cstdio>

#include "cli/common.h"
#include "src/episode.h"
#include "src/fetch_env.h"
#include "src/json_util.h"

namespace fetchscope::cli {

void RegisterRandomEpisodes(CLI::App& app) {
  auto env = std::make_shared<EnvOptions>();
  auto n_episodes = std::make_shared<int>(10);
  auto json_out = std::make_shared<std::string>();
  CLI::App* sub = app.add_subcommand(
      "random-episodes", "Random-policy baseline: success rate, returns, lengths, final distances");
  AddEnvOptions(sub, env.get());
  sub->add_option("--n-episodes", *n_episodes, "Episodes to run")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  sub->add_option("--json-out", *json_out,
                  "Write P (.json) or P_random_metrics.json; without it JSON goes to stdout");
  sub->callback([env, n_episodes, json_out]() {
    const EnvSpec& spec = FindEnvSpec(env->env_id);
    const uint64_t seed = ParseSeed(env->seed);
    FetchEnv fetch(spec, ResolveAssets(env->assets));
    PolicyContext context;
    context.seed = seed;
    auto policy = MakePolicy("random", spec, context);
    nlohmann::json rows = nlohmann::json::array();
    std::vector<double> returns, finals;
    double successes = 0, total_length = 0;
    for (int e = 0; e < *n_episodes; ++e) {
      const EpisodeRecord ep = RunEpisode(fetch, *policy, e, e == 0 ? std::optional<uint64_t>(seed) : std::nullopt,
                                          spec.max_episode_steps);
      const StepRecord& last = ep.steps.back();
      const double final_distance = GoalDistance(last.obs.achieved_goal, last.obs.desired_goal);
      returns.push_back(ep.episode_return);
      finals.push_back(final_distance);
      successes += last.is_success;
      total_length += ep.steps.size() - 1;
      rows.push_back({{"index", e}, {"return", JsonDouble(ep.episode_return)},
                      {"length", static_cast<int>(ep.steps.size()) - 1},
                      {"is_success", last.is_success}, {"final_distance", final_distance}});
    }
    const double n = *n_episodes;
    double mean = 0, var = 0, mean_final = 0;
    for (double r : returns) mean += r / n;
    for (double r : returns) var += (r - mean) * (r - mean) / n;
    for (double f : finals) mean_final += f / n;
    nlohmann::json j = {{"env_id", spec.id},
                        {"seed", seed},
                        {"policy", "random"},
                        {"n_episodes", *n_episodes},
                        {"success_rate", successes / n},
                        {"mean_return", mean},
                        {"std_return", std::sqrt(var)},
                        {"mean_episode_length", total_length / n},
                        {"mean_final_distance", mean_final},
                        {"final_distances", finals},
                        {"episodes", rows},
                        {"assets", AssetsJson(fetch.assets())},
                        {"versions", VersionsJson()}};
    if (json_out->empty()) {
      std::printf("%s\n", DumpJson(j).c_str());
      return;
    }
    const std::string path = JsonOutPath(*json_out, "random_metrics");
    WriteJson(path, j);
    std::printf("%s, %d random episodes (seed %s): success rate %.3f, mean return %.3f (std %.3f), "
                "mean length %.1f, mean final distance %.4f m\nwrote %s\n",
                spec.id.c_str(), *n_episodes, env->seed.c_str(), successes / n, mean, std::sqrt(var),
                total_length / n, mean_final, path.c_str());
  });
}

}  // namespace fetchscope::cli
