// The typed --policy (src/policy.h): ParsePolicySpec turns the text into one case of PolicySpec,
// reading a replay file once, and MakePolicy builds a policy from the spec without touching the
// filesystem; bad text is refused with one line naming it and the accepted values.
#include "src/policy.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "base/errors.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/episode.h"
#include "src/fetch_env.h"
#include "src/replay_file.h"
#include "src/trajectory.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using testing::SourceDir;
using testing::TempDir;

fs::path ReplayData(const std::string& name) { return SourceDir() / "tests/data/replay" / name; }

// The message of the UsageError that parsing `text` with `options` throws ("" when it parses).
std::string UsageMessage(const std::string& text, const PolicyOptions& options = {}) {
  try {
    ParsePolicySpec(text, options);
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}

// Plays `steps` steps of episode `k` of `policy` on `env` and returns the actions taken.
std::vector<Action> Actions(FetchEnv& env, Policy& policy, int k, int steps) {
  const EpisodeRecord episode = RunEpisode(env, policy, k, 7, steps);
  std::vector<Action> actions;
  for (size_t t = 1; t < episode.steps.size(); ++t) actions.push_back(*episode.steps[t].action);
  return actions;
}

void ExpectSameActions(const std::vector<Action>& a, const std::vector<Action>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t t = 0; t < a.size(); ++t) {
    for (int i = 0; i < 4; ++i) EXPECT_EQ(a[t].value[i], b[t].value[i]) << "row " << t;
    EXPECT_EQ(a[t].is_float32, b[t].is_float32) << "row " << t;
  }
}

TEST(PolicySpec, EachNameParsesToItsCaseKeepingTheText) {
  EXPECT_TRUE(std::holds_alternative<policy_spec::Random>(ParsePolicySpec("random").value));
  EXPECT_TRUE(std::holds_alternative<policy_spec::Zero>(ParsePolicySpec("zero").value));
  EXPECT_TRUE(std::holds_alternative<policy_spec::Scripted>(ParsePolicySpec("scripted").value));
  EXPECT_EQ(ParsePolicySpec("scripted").text, "scripted");

  const PolicySpec exec = ParsePolicySpec("exec:python3 my policy.py:x", {2.5, "", ""});
  const auto* e = std::get_if<policy_spec::Exec>(&exec.value);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->command, "python3 my policy.py:x");  // everything after the first ':'
  EXPECT_EQ(e->timeout_s, 2.5);
  EXPECT_EQ(exec.text, "exec:python3 my policy.py:x");
  EXPECT_TRUE(exec.is_exec());
  EXPECT_EQ(exec.replay(), nullptr);

  const std::string csv = ReplayData("replay.csv").string();
  const PolicySpec replay = ParsePolicySpec("replay:" + csv, {10, "float32", ""});
  ASSERT_NE(replay.replay(), nullptr);
  EXPECT_EQ(replay.text, "replay:" + csv);
  EXPECT_EQ(replay.replay()->path, csv);
  EXPECT_EQ(replay.replay_dtype(), "float32");
  EXPECT_EQ(replay.replay_trajectory(), nullptr);
  ASSERT_NE(replay.replay()->rows, nullptr);
  EXPECT_EQ(replay.replay()->rows->size(), 6u);
  // float32: each value rounded to float32 at parse time, once for every worker
  for (const Action& a : *replay.replay()->rows) {
    EXPECT_TRUE(a.is_float32);
    for (double v : a.value) EXPECT_EQ(v, static_cast<double>(static_cast<float>(v)));
  }
}

TEST(PolicySpec, EveryReplayFormatIsReadIntoTheSpec) {
  for (const char* name : {"replay.csv", "replay.jsonl", "replay_f32.npy", "replay_f64.npy"}) {
    SCOPED_TRACE(name);
    const std::string path = ReplayData(name).string();
    const PolicySpec spec = ParsePolicySpec("replay:" + path);
    ASSERT_NE(spec.replay(), nullptr);
    ASSERT_NE(spec.replay()->rows, nullptr);
    ExpectSameActions(*spec.replay()->rows, ReadReplayFile(path));
  }
  // a relative file is read from base_dir (the golden manifest's folder), its text kept
  const PolicySpec golden = ParsePolicySpec("replay:replay.csv", {10, "", ReplayData("").string()});
  ASSERT_NE(golden.replay(), nullptr);
  EXPECT_EQ(golden.text, "replay:replay.csv");
  EXPECT_EQ(golden.replay()->rows->size(), 6u);
}

TEST(PolicySpec, BadTextIsRefusedWithOneLineNamingIt) {
  const std::string accepted = std::string(": use ") + kPolicyHelp;
  EXPECT_EQ(UsageMessage("scriptd"),
            "unknown policy 'scriptd' (did you mean 'scripted'?)" + accepted);
  EXPECT_EQ(UsageMessage("replya:a.csv"),
            "unknown policy 'replya:a.csv' (did you mean 'replay:'?)" + accepted);
  const std::string random_colon = UsageMessage("random:");  // no such case: an unknown name
  EXPECT_EQ(random_colon.rfind("unknown policy 'random:'", 0), 0u) << random_colon;
  EXPECT_EQ(UsageMessage("replay:"), "--policy replay: needs a file, e.g. replay:actions.csv");
  EXPECT_EQ(UsageMessage("exec:"),
            "--policy exec: needs a command, e.g. exec:'python3 my_policy.py'");
  EXPECT_EQ(UsageMessage("random", {10, "float16", ""}),
            "--replay-dtype 'float16' is not known; accepted: float32, float64");
  EXPECT_EQ(UsageMessage("random", {10, "float32", ""}),
            "--replay-dtype applies to --policy replay:FILE only, not to 'random'");
  const std::string npy = ReplayData("replay_f64.npy").string();
  EXPECT_EQ(UsageMessage("replay:" + npy, {10, "float32", ""}),
            "--replay-dtype float32: replay file " + npy +
                " holds float64 (its .npy dtype); drop --replay-dtype, a .npy carries its own "
                "precision");
  // a file that does not exist is a UsageError naming it, at parse time
  EXPECT_THROW(ParsePolicySpec("replay:/nonexistent/none.csv"), UsageError);
}

// The spec holds the file's contents: once parsed, the file can go, and every worker's
// MakePolicy still builds the same replay.
TEST(PolicySpec, AReplayFileIsReadOnceAndMakePolicyTouchesNoFile) {
  TempDir tmp;
  const fs::path csv = tmp.path() / "actions.csv";
  fs::copy_file(ReplayData("replay.csv"), csv);
  const std::vector<Action> rows = ReadReplayFile(csv.string());
  const PolicySpec spec = ParsePolicySpec("replay:" + csv.string());
  fs::remove(csv);

  const EnvSpec& env_spec = FindEnvSpec("FetchReach-v4");
  FetchEnv env(env_spec, ResolveAssets("bundled"));
  PolicyContext context;
  context.steps_per_episode = 3;
  context.episodes = 2;
  for (int worker = 0; worker < 2; ++worker) {
    auto policy = MakePolicy(spec, env_spec, context);
    EXPECT_EQ(policy->name(), "replay:" + csv.string());
    // episode 1 plays rows 3..5
    ExpectSameActions(Actions(env, *policy, 1, 3), {rows.begin() + 3, rows.end()});
  }
  // too few rows for the run: refused from the spec, naming the file
  context.episodes = 3;
  try {
    MakePolicy(spec, env_spec, context);
    FAIL() << "accepted";
  } catch (const RunError& e) {
    EXPECT_EQ(std::string(e.what()),
              "replay file '" + csv.string() +
                  "' has 6 action rows but 3 episode(s) of 3 steps need 9: add rows, or pass "
                  "--steps 2");
  }
}

TEST(PolicySpec, ATrajectoryJsonIsReadOnceAndReplaysEachEpisodeByIndex) {
  const EnvSpec& env_spec = FindEnvSpec("FetchReach-v4");
  FetchEnv env(env_spec, ResolveAssets("bundled"));
  PolicyContext random_context;
  random_context.seed = 7;
  auto random = MakePolicy(PolicySpec::Random(), env_spec, random_context);
  Trajectory recorded;
  recorded.env_id = env_spec.id;
  recorded.seed = 7;
  recorded.policy = "random";
  recorded.assets = env.assets();
  recorded.episodes.push_back(RunEpisode(env, *random, 0, 7, 4));
  recorded.episodes.push_back(RunEpisode(env, *random, 1, std::nullopt, 4));
  TempDir tmp;
  const fs::path json = tmp.path() / "episodes.json";
  std::ofstream(json) << TrajectoryText(recorded);

  const PolicySpec spec = ParsePolicySpec("replay:" + json.string());
  fs::remove(json);
  ASSERT_NE(spec.replay_trajectory(), nullptr);
  EXPECT_EQ(spec.replay()->rows, nullptr);
  EXPECT_EQ(spec.replay_trajectory()->episodes.size(), 2u);

  PolicyContext context;
  context.steps_per_episode = 4;
  context.episode_indices = {0, 1};
  context.episodes = 2;
  auto policy = MakePolicy(spec, env_spec, context);
  std::vector<Action> want;
  for (size_t t = 1; t < recorded.episodes[1].steps.size(); ++t) {
    want.push_back(*recorded.episodes[1].steps[t].action);
  }
  ExpectSameActions(Actions(env, *policy, 1, 4), want);

  // a trajectory carries its precision: another --replay-dtype is refused at parse time
  std::ofstream(json) << TrajectoryText(recorded);
  const std::string message = UsageMessage("replay:" + json.string(), {10, "float64", ""});
  EXPECT_EQ(message, "--replay-dtype float64: replay file " + json.string() +
                         " records episode 0 in float32 (its action_dtype); drop --replay-dtype, "
                         "a trajectory JSON carries its own precision");
  // an episode the run plays that the file lacks: refused from the spec
  context.episode_indices = {0, 5};
  context.episodes = 6;
  EXPECT_THROW(MakePolicy(spec, env_spec, context), RunError);
}

TEST(PolicySpec, NamedSpecsBuildTheirPolicies) {
  const EnvSpec& env_spec = FindEnvSpec("FetchReach-v4");
  FetchEnv env(env_spec, ResolveAssets("bundled"));
  PolicyContext context;
  context.seed = 3;
  // record --from: zero actions under the recording's policy name
  const PolicySpec from = PolicySpec::Zero("exec:python3 x.py");
  EXPECT_EQ(from.text, "exec:python3 x.py");
  EXPECT_FALSE(from.is_exec());
  auto zero = MakePolicy(from, env_spec, context);
  for (const Action& a : Actions(env, *zero, 0, 3)) {
    for (double v : a.value) EXPECT_EQ(v, 0.0);
  }
  // random: the same draws as the parsed "random"
  auto a = MakePolicy(PolicySpec::Random(), env_spec, context);
  auto b = MakePolicy(ParsePolicySpec("random"), env_spec, context);
  ExpectSameActions(Actions(env, *a, 0, 5), Actions(env, *b, 0, 5));
}

}  // namespace
}  // namespace fetchscope
