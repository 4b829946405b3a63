#include "cli/resolve.h"

#include <cstdio>

#include "base/stop_signal.h"
#include "src/episode_source.h"
#include "src/exec_wire.h"

namespace fetchscope::cli {

void AddPolicyOptions(CLI::App* sub, PolicyOptions* options) {
  sub->add_option("--policy", options->policy, kPolicyHelp)->capture_default_str();
  sub->add_option("--exec-timeout", options->exec_timeout,
                  "Seconds an exec: policy may take per answer")
      ->capture_default_str()
      ->check(CLI::Range(0.001, 86400.0));
  sub->add_option("--exec-fields", options->exec_fields, kExecFieldsHelp);
  sub->add_option("--replay-dtype", options->replay_dtype, kReplayDtypeHelp);
}

PolicySpec ParsePolicyOptions(const PolicyOptions& options) {
  PolicySpec spec =
      ParsePolicySpec(options.policy, {options.exec_timeout, options.replay_dtype, ""});
  if (!options.exec_fields.empty() && !spec.is_exec()) {
    throw UsageError("--exec-fields '" + options.exec_fields +
                     "' chooses what an exec: policy's lines carry; --policy " + spec.text +
                     " reads no lines (give --policy exec:CMD)");
  }
  return spec;
}

PolicySpec WithExecFields(PolicySpec policy, const PolicyOptions& options, const EnvSpec& spec) {
  if (auto* exec = std::get_if<policy_spec::Exec>(&policy.value)) {
    exec->fields = ParseExecFields(options.exec_fields, spec.has_object);
  }
  return policy;
}

void ApplyReplayedEnv(const PolicySpec& policy, EnvOptions* env) {
  const Trajectory* file = policy.replay_trajectory();
  if (!file) return;  // a CSV, .npy or JSON-lines action file: no env of its own
  for (const TrajectoryEpisode& e : file->episodes) {
    if (!e.placed) continue;
    throw UsageError("--policy " + policy.text + ": episode " + std::to_string(e.index) +
                     " starts from a reset placed by hand (serve), which replay: cannot make (it "
                     "plays the actions from this run's own reset); accepted: record --from " +
                     policy.text.substr(std::string("replay:").size()) + ", which resets there");
  }
  if (!env->env_id_option || env->env_id_option->count() == 0) env->env_id = file->env_id;
  if (!env->seed_option || env->seed_option->count() == 0) env->seed = std::to_string(file->seed);
}

void NotePastTimeLimit(const EnvSpec& spec, int steps, bool quiet, const std::string& where) {
  const int limit = spec.max_episode_steps;
  if (quiet || steps <= limit) return;
  std::fprintf(stderr,
               "fetchscope: note: episodes of %d steps run past %s's TimeLimit of %d steps "
               "(gym.make's env is truncated there); steps %d..%d are marked past_time_limit %s\n",
               steps, spec.id.c_str(), limit, limit + 1, steps, where.c_str());
}

ResolvedEnv ResolveEnv(const EnvOptions& env, bool with_seed) {
  ResolvedEnv resolved;
  resolved.spec = &FindEnvSpec(env.env_id);
  if (with_seed) resolved.seed = ParseSeed(env.seed);
  resolved.assets = ResolveAssets(env.assets);
  return resolved;
}

ResolvedRun ResolveRun(const EnvOptions& options, const EpisodeRequest& request) {
  EnvOptions env = options;
  ApplyReplayedEnv(request.policy, &env);
  ResolvedRun run;
  run.env = ResolveEnv(env);
  if (auto replayed =
          ReplayedEpisodes(request.policy, request.episodes_given ? request.episodes : 0,
                           run.env.spec->id, run.env.seed)) {
    run.episodes = *replayed;
  } else {
    for (int k = 0; k < request.episodes; ++k) run.episodes.push_back(k);
  }
  NotePastTimeLimit(*run.env.spec, request.steps, request.quiet, request.past_limit_marks);
  PolicyContext& context = run.policy_context;
  context.seed = run.env.seed;
  context.steps_per_episode = request.steps;
  context.episodes = run.episodes.empty() ? 0 : run.episodes.back() + 1;
  context.episode_indices = run.episodes;
  context.stop_requested = [] { return StopSignal() != 0; };
  return run;
}

}  // namespace fetchscope::cli
