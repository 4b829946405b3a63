// bench --what sim: env steps/s per task beside the raw mj_step bound, and this process's peak
// resident set.
#include <sys/resource.h>

#include <chrono>
#include <cstdio>

#include "bench/bench.h"
#include "src/episode.h"
#include "src/fetch_env.h"

namespace fetchscope::bench {
namespace {

using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// Raw physics bound: the same episodes (reset, gripper held in place) as bare mj_step calls,
// without the env's action, observation and callback work around them.
double RawSubstepsPerSecond(FetchEnv& env, double budget_s) {
  mjModel* m = env.model();
  mjData* d = env.data();
  const int substeps = env.spec().max_episode_steps * env.spec().n_substeps;
  long n = 0;
  double busy = 0;
  while (busy < budget_s) {
    env.Reset(n);
    env.Step(Action{});  // anchors the mocap on the gripper, as every episode's first step does
    const auto start = Clock::now();
    for (int i = 0; i < substeps; ++i) mj_step(m, d);
    busy += Seconds(start, Clock::now());
    n += substeps;
  }
  return n / busy;
}

// Env steps with the zero policy (no policy cost), resets every 50 steps included.
double EnvStepsPerSecond(FetchEnv& env, double budget_s) {
  Action zero;
  long n = 0;
  const auto start = Clock::now();
  while (Seconds(start, Clock::now()) < budget_s) {
    env.Reset(n);
    for (int t = 0; t < env.spec().max_episode_steps; ++t) env.Step(zero);
    n += env.spec().max_episode_steps;
  }
  return n / Seconds(start, Clock::now());
}

}  // namespace

double PeakRssMiB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;
}

nlohmann::json BenchSim(const AssetSource& assets, double budget_s) {
  nlohmann::json rows = nlohmann::json::array();
  std::printf("%-22s %14s %16s %12s %8s\n", "sim", "mj_step/s", "bound steps/s", "env steps/s",
              "ratio");
  for (const EnvSpec& spec : AllEnvSpecs()) {
    if (spec.dense) continue;  // dense and sparse differ only in the reward formula
    FetchEnv env(spec, assets);
    // interleave the two measurements and keep the best of three of each
    double raw = 0, stepped = 0;
    for (int rep = 0; rep < 3; ++rep) {
      raw = std::max(raw, RawSubstepsPerSecond(env, budget_s / 6));
      stepped = std::max(stepped, EnvStepsPerSecond(env, budget_s / 6));
    }
    const double bound = raw / spec.n_substeps;
    std::printf("%-22s %14.0f %16.1f %12.1f %7.1f%%\n", spec.id.c_str(), raw, bound, stepped,
                100 * stepped / bound);
    rows.push_back({{"env_id", spec.id},
                    {"mj_step_per_s", raw},
                    {"bound_env_steps_per_s", bound},
                    {"env_steps_per_s", stepped},
                    {"ratio_to_bound", stepped / bound}});
  }
  return rows;
}

}  // namespace fetchscope::bench
