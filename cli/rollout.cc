// fetchscope rollout: episodes without rendering, written as trajectory JSON.
#include <cstdio>

#include "cli/common.h"
#include "src/episode.h"
#include "src/fetch_env.h"
#include "src/json_util.h"

namespace fetchscope::cli {

void RegisterRollout(CLI::App& app) {
  auto env = std::make_shared<EnvOptions>();
  auto episodes = std::make_shared<int>(1);
  auto steps = std::make_shared<int>(50);
  auto policy_spec = std::make_shared<std::string>("random");
  auto json_out = std::make_shared<std::string>();
  auto exec_timeout = std::make_shared<double>(10.0);
  CLI::App* sub = app.add_subcommand(
      "rollout", "Run episodes without rendering and write the trajectory JSON");
  AddEnvOptions(sub, env.get());
  sub->add_option("--episodes", *episodes, "Number of episodes")->capture_default_str()->check(CLI::Range(1, 1000000));
  sub->add_option("--steps", *steps, "Steps per episode (TimeLimit is 50)")->capture_default_str()->check(CLI::Range(1, 50));
  sub->add_option("--policy", *policy_spec, kPolicyHelp)->capture_default_str();
  sub->add_option("--exec-timeout", *exec_timeout, "Seconds an exec: policy may take per answer")
      ->capture_default_str()->check(CLI::Range(0.001, 86400.0));
  sub->add_option("--json-out", *json_out, "Write F (.json) or F_rollout.json; without it JSON goes to stdout");
  sub->callback([=]() {
    const EnvSpec& spec = FindEnvSpec(env->env_id);
    const uint64_t seed = ParseSeed(env->seed);
    const AssetSource assets = ResolveAssets(env->assets);
    PolicyContext context;
    context.seed = seed;
    context.steps_per_episode = *steps;
    context.episodes = *episodes;
    context.exec_timeout_s = *exec_timeout;
    auto policy = MakePolicy(*policy_spec, spec, context);
    FetchEnv fetch(spec, assets);
    std::vector<EpisodeRecord> records;
    int successes = 0;
    for (int e = 0; e < *episodes; ++e) {
      records.push_back(RunEpisode(fetch, *policy, e, e == 0 ? std::optional<uint64_t>(seed) : std::nullopt, *steps));
      successes += records.back().steps.back().is_success;
    }
    std::vector<const EpisodeRecord*> ptrs;
    for (const auto& r : records) ptrs.push_back(&r);
    nlohmann::json j = TrajectoryJson(fetch, seed, *policy_spec, ptrs);
    if (json_out->empty()) {
      std::printf("%s\n", DumpJson(j).c_str());
      return;
    }
    const std::string path = JsonOutPath(*json_out, "rollout");
    WriteJson(path, j);
    std::printf("%s: %d episode(s) of %d steps, policy %s, seed %s: success %d/%d (%.0f%%)\nwrote %s\n",
                spec.id.c_str(), *episodes, *steps, policy_spec->c_str(), env->seed.c_str(), successes,
                *episodes, 100.0 * successes / *episodes, path.c_str());
  });
}

}  // namespace fetchscope::cli
