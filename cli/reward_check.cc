// fetchscope reward-check: every step's reward equals compute_reward(achieved, desired), for
// the sparse and the dense variant, and relabelled rewards equal the formulas.
#include <cmath>
#include <cstdio>

#include "base/json_util.h"
#include "cli/chapter.h"
#include "cli/command.h"
#include "cli/common.h"
#include "cli/resolve.h"
#include "src/episode.h"
#include "src/fetch_env.h"
#include "src/policy.h"
#include "src/rng.h"

namespace fetchscope::cli {
namespace {

// The formulas written out independently of FetchEnv, as Gymnasium-Robotics states them.
double FormulaReward(bool dense, double threshold, const std::array<double, 3>& a,
                     const std::array<double, 3>& b) {
  double sum = 0;
  for (int i = 0; i < 3; ++i) sum += (a[i] - b[i]) * (a[i] - b[i]);
  const double d = std::sqrt(sum);
  if (dense) return -d;
  return -static_cast<double>(static_cast<float>(d > threshold));
}

bool SameBits(double a, double b) { return a == b && std::signbit(a) == std::signbit(b); }

struct Mismatch {
  std::string env_id, kind;
  int episode, t;
  double got, expected;
};

// Checks one step's reward against the formula and compute_reward, and its success flag.
void CheckStep(const EnvSpec& spec, FetchEnv& fetch, const StepRecord& s, const StepResult& r,
               int episode, std::vector<Mismatch>* mismatches) {
  const double expected =
      FormulaReward(spec.dense, spec.distance_threshold, s.obs.achieved_goal, s.obs.desired_goal);
  if (!SameBits(r.reward, expected)) {
    mismatches->push_back({spec.id, "step reward", episode, s.t, r.reward, expected});
  }
  const double via_env = fetch.ComputeReward(s.obs.achieved_goal, s.obs.desired_goal);
  if (!SameBits(via_env, r.reward)) {
    mismatches->push_back({spec.id, "compute_reward", episode, s.t, via_env, r.reward});
  }
  double d2 = 0;
  for (int i = 0; i < 3; ++i) {
    d2 += (s.obs.achieved_goal[i] - s.obs.desired_goal[i]) *
          (s.obs.achieved_goal[i] - s.obs.desired_goal[i]);
  }
  if (r.is_success != (std::sqrt(d2) < spec.distance_threshold)) {
    mismatches->push_back(
        {spec.id, "is_success", episode, s.t, double(r.is_success), double(!r.is_success)});
  }
}

// Relabel: pairs each achieved goal with a future achieved goal and with a random goal; the
// number of rewards checked.
long CheckRelabelled(const EnvSpec& spec, FetchEnv& fetch,
                     const std::vector<std::array<double, 3>>& achieved, int episode,
                     NumpyGenerator& relabel_rng, std::vector<Mismatch>* mismatches) {
  long checks = 0;
  for (size_t t = 0; t < achieved.size(); ++t) {
    const size_t future = t + static_cast<size_t>(relabel_rng.NextDouble() * (achieved.size() - t));
    std::array<double, 3> random_goal;
    for (int i = 0; i < 3; ++i) {
      random_goal[i] = fetch.initial_gripper_xpos()[i] + relabel_rng.Uniform(-0.3, 0.3);
    }
    for (const auto& goal : {achieved[std::min(future, achieved.size() - 1)], random_goal}) {
      const double got = fetch.ComputeReward(achieved[t], goal);
      const double expected = FormulaReward(spec.dense, spec.distance_threshold, achieved[t], goal);
      ++checks;
      if (!SameBits(got, expected)) {
        mismatches->push_back({spec.id, "relabelled reward", episode, int(t), got, expected});
      }
    }
  }
  return checks;
}

// Random-policy episodes of one variant, `n_steps` in all, every reward checked: its line on
// stdout and its entry in the JSON.
nlohmann::json CheckVariant(const EnvSpec& spec, const AssetSource& assets, uint64_t seed,
                            int n_steps, std::vector<Mismatch>* mismatches) {
  FetchEnv fetch(spec, assets);
  PolicyContext context;
  context.seed = seed;
  auto policy = MakePolicy(PolicySpec::Random(), spec, context);
  NumpyGenerator relabel_rng(seed + 1);
  long step_checks = 0, relabel_checks = 0, success_checks = 0;
  int done = 0, episode = 0;
  while (done < n_steps) {
    const int steps = std::min(spec.max_episode_steps, n_steps - done);
    std::vector<std::array<double, 3>> achieved;
    auto check = [&](const StepRecord& s, const StepResult* r) {
      achieved.push_back(s.obs.achieved_goal);
      if (!r) return true;
      ++step_checks;
      ++success_checks;
      CheckStep(spec, fetch, s, *r, episode, mismatches);
      return true;
    };
    RunEpisode(fetch, *policy, episode, episode == 0 ? std::optional<uint64_t>(seed) : std::nullopt,
               steps, check);
    relabel_checks += CheckRelabelled(spec, fetch, achieved, episode, relabel_rng, mismatches);
    done += steps;
    ++episode;
  }
  std::printf("%-28s %ld step rewards, %ld success flags, %ld relabelled rewards: %s\n",
              spec.id.c_str(), step_checks, success_checks, relabel_checks,
              mismatches->empty() ? "all equal" : "MISMATCH");
  return {{"env_id", spec.id},
          {"step_rewards_checked", step_checks},
          {"success_flags_checked", success_checks},
          {"relabelled_rewards_checked", relabel_checks},
          {"episodes", episode}};
}

// The first 20 mismatches, printed and as JSON.
nlohmann::json FirstMismatches(const std::vector<Mismatch>& mismatches) {
  nlohmann::json first = nlohmann::json::array();
  for (size_t i = 0; i < mismatches.size() && i < 20; ++i) {
    const Mismatch& mm = mismatches[i];
    first.push_back({{"env_id", mm.env_id},
                     {"kind", mm.kind},
                     {"episode", mm.episode},
                     {"t", mm.t},
                     {"got", JsonDouble(mm.got)},
                     {"expected", JsonDouble(mm.expected)}});
    std::printf("  mismatch: %s %s episode %d t %d: got %.17g expected %.17g\n", mm.env_id.c_str(),
                mm.kind.c_str(), mm.episode, mm.t, mm.got, mm.expected);
  }
  return first;
}

}  // namespace

bool RunRewardCheck(const RewardCheckOptions& options) {
  const ResolvedEnv env = ResolveEnv(options.env);
  const EnvSpec& chosen = *env.spec;
  const uint64_t seed = env.seed;
  const AssetSource& assets = env.assets;
  const std::string path = JsonOutPath(options.json_out, "reward_check");
  CheckJsonOutReplaces(path, {{"task", TaskName(chosen.task)}, {"seed", seed}}, options.overwrite);
  std::vector<Mismatch> mismatches;
  nlohmann::json variants = nlohmann::json::array();
  for (const EnvSpec& spec : AllEnvSpecs()) {
    if (spec.task != chosen.task) continue;
    variants.push_back(CheckVariant(spec, assets, seed, options.n_steps, &mismatches));
  }
  const nlohmann::json first = FirstMismatches(mismatches);
  const bool pass = mismatches.empty();
  std::printf("reward-check %s: %s (n-steps %d, seed %s, assets %s)\n",
              TaskName(chosen.task).c_str(), pass ? "PASS" : "FAIL", options.n_steps,
              options.env.seed.c_str(), assets.kind.c_str());
  if (!options.json_out.empty()) {
    nlohmann::json j = {{"task", TaskName(chosen.task)},       {"pass", pass},
                        {"n_steps", options.n_steps},          {"seed", seed},
                        {"assets", AssetsJson(assets)},        {"variants", variants},
                        {"mismatch_count", mismatches.size()}, {"first_mismatches", first},
                        {"versions", VersionsJson()}};
    WriteJson(path, j);
    std::printf("wrote %s\n", path.c_str());
  }
  return pass;
}

Command AddRewardCheck(CLI::App& app) {
  auto o = std::make_shared<RewardCheckOptions>();
  CLI::App* sub = app.add_subcommand(
      "reward-check",
      "Check every step's reward against compute_reward, sparse and dense, plus relabelled goals");
  AddEnvOptions(sub, &o->env);
  sub->add_option("--n-steps", o->n_steps, "Random-policy steps per variant")
      ->capture_default_str()
      ->check(CLI::Range(1, 10000000));
  sub->add_option("--json-out", o->json_out,
                  "Write P (.json), P/reward_check.json if P ends in /, or P_reward_check.json; "
                  "without it only the table is printed");
  sub->add_flag("--overwrite", o->overwrite, kJsonOverwriteHelp);
  return {sub, [o] { return RunRewardCheck(*o) ? 0 : 1; }};
}

}  // namespace fetchscope::cli
