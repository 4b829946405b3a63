// The one resolver of the options that env-driven commands share: --env-id, --seed, --assets,
// --policy with its context, and the list of episodes a run plays. Each command parses
// `--policy` once (ParsePolicySpec, a replay file read with it) before resolving; the layers
// below get the PolicySpec, never the text.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "cli/common.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/policy_spec.h"

namespace fetchscope::cli {

/// --policy, --exec-timeout and --replay-dtype as given (record and rollout take all three).
struct PolicyOptions {
  std::string policy = "random";  ///< --policy
  double exec_timeout = 10.0;     ///< --exec-timeout, seconds per answer of an exec: policy
  std::string replay_dtype;       ///< --replay-dtype: "", float32, float64
  std::string exec_fields;        ///< --exec-fields: "" (all), or a comma-separated list
};

/// Adds --policy, --exec-timeout, --exec-fields and --replay-dtype to `sub`.
void AddPolicyOptions(CLI::App* sub, PolicyOptions* options);

/// `options` parsed once into the typed spec (ParsePolicySpec; a replay file is read here).
/// --exec-fields for a policy other than exec: is refused (UsageError); its names are checked
/// against the env by WithExecFields.
PolicySpec ParsePolicyOptions(const PolicyOptions& options);

/// `policy` with --exec-fields parsed for `spec`'s observation (ParseExecFields: an unknown
/// name, or an object slice on Reach, is a UsageError naming it). Other policies as they are.
PolicySpec WithExecFields(PolicySpec policy, const PolicyOptions& options, const EnvSpec& spec);

/// For `--policy replay:FILE.json` holding fetchscope's trajectory JSON: the env and seed the file
/// was recorded with replace --env-id and --seed where the command line does not name them, so
/// the replay reproduces the recording. Where it names others, ReplayedEpisodes refuses the run
/// naming both. Any other policy leaves `env` as it is.
void ApplyReplayedEnv(const PolicySpec& policy, EnvOptions* env);

/// Says once on stderr (unless `quiet`) that `steps` run past `spec`'s TimeLimit and that those
/// steps are marked `where` (e.g. "in the trajectory JSON"); nothing when steps <=
/// max_episode_steps.
void NotePastTimeLimit(const EnvSpec& spec, int steps, bool quiet, const std::string& where);

/// --env-id, --seed and --assets, resolved (bad values are UsageError/RunError naming them).
struct ResolvedEnv {
  const EnvSpec* spec = nullptr;  ///< the v4 id (auto: FetchReachDense-v4)
  uint64_t seed = 0;              ///< the first reset's seed
  AssetSource assets;             ///< the model files
};

/// Resolves the env options; `with_seed` false leaves seed 0 and does not parse --seed.
ResolvedEnv ResolveEnv(const EnvOptions& env, bool with_seed = true);

/// What a run of episodes under a policy was asked for.
struct EpisodeRequest {
  PolicySpec policy = PolicySpec::Random();  ///< --policy, parsed (ParsePolicySpec)
  int episodes = 1;                          ///< --episodes (or 1 for a one-frame command)
  bool episodes_given = false;               ///< --episodes was on the command line
  int steps = 50;                            ///< steps per episode
  bool quiet = false;                        ///< no warnings on stderr
  /// where this command marks steps past the TimeLimit (NotePastTimeLimit)
  std::string past_limit_marks = "in the trajectory JSON";
};

/// A run of episodes, resolved: the env, the episode indices played (a replay:FILE.json
/// trajectory plays its own, each from its own reset; else 0 .. episodes-1) and the policy's
/// context (stop requests from SIGINT/SIGTERM through StopSignal()).
struct ResolvedRun {
  ResolvedEnv env;
  std::vector<int> episodes;
  PolicyContext policy_context;
};

/// Resolves a run; the policy is not built (MakePolicy(request.policy, *env.spec,
/// policy_context) builds one per worker, from the spec: no file is read again).
ResolvedRun ResolveRun(const EnvOptions& env, const EpisodeRequest& request);

}  // namespace fetchscope::cli
