// `random-episodes`, black box: the Reach baseline, where the mean return differs from the
// course chapter, and --json-out refusing to replace another env's or seed's results.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::CommandResult;
using testing::LinesWith;
using testing::ReadFile;
using testing::RunFetchscope;
using testing::TempDir;
namespace fs = std::filesystem;

TEST(Cli, RandomEpisodesReachBaseline) {
  TempDir tmp;
  const std::string prefix = (tmp.path() / "m").string();
  auto r = RunFetchscope("random-episodes --env-id FetchReachDense-v4 --n-episodes 20 --json-out " +
                         prefix);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto j = nlohmann::json::parse(ReadFile(prefix + "_random_metrics.json"));
  EXPECT_EQ(j["mean_episode_length"], 50.0);
  EXPECT_EQ(j["episodes"].size(), 20u);
  // a random walk of 0.05 m steps wanders ~0.2 m from a goal within 0.15 m: clearly negative
  EXPECT_LT(j["mean_return"].get<double>(), -5.0);
  EXPECT_GT(j["mean_return"].get<double>(), -25.0);
  auto s = RunFetchscope("random-episodes --env-id FetchReach-v4 --n-episodes 20");
  ASSERT_EQ(s.exit_code, 0) << s.output;
  auto js = nlohmann::json::parse(s.output);
  EXPECT_LE(js["mean_return"].get<double>(), -45.0);  // sparse: nearly -1 every step
}

TEST(RoughEdges, RandomEpisodesSaysTheMeanReturnDiffersFromTheChapter) {
  TempDir tmp;
  CommandResult r =
      RunFetchscope("random-episodes --n-episodes 4 --json-out " + (tmp.path() / "d3").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(ReadFile(tmp.path() / "d3_random_metrics.json"));
  const std::vector<std::string> lines = LinesWith(r.output, "the chapter expects");
  ASSERT_EQ(lines.size(), 1u) << r.output;
  char mean[32];
  std::snprintf(mean, sizeof(mean), "%.1f", j["mean_return"].get<double>());
  EXPECT_NE(lines[0].find(std::string("mean return ") + mean), std::string::npos) << lines[0];
  EXPECT_NE(lines[0].find("-15 to -25"), std::string::npos) << lines[0];
  ASSERT_EQ(j["chapter_differences"].size(), 1u);
  // sparse Reach: the chapter's dense range does not apply, so nothing is said
  r = RunFetchscope("random-episodes --n-episodes 2 --env-id FetchReach-v4 --json-out " +
                    (tmp.path() / "sparse").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("chapter"), std::string::npos) << r.output;
}

TEST(RoughEdges, JsonOutRefusesToReplaceAnotherEnvsOrSeedsResults) {
  TempDir tmp;
  const std::string prefix = (tmp.path() / "results" / "ch01").string();
  const fs::path file = tmp.path() / "results" / "ch01_random_metrics.json";
  CommandResult r = RunFetchscope("random-episodes --n-episodes 2 --json-out " + prefix);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string first = ReadFile(file);
  // the chapter's second D3 run: another env, same file
  r = RunFetchscope("random-episodes --n-episodes 2 --env-id FetchReach-v4 --json-out " + prefix);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  for (const std::string& needle :
       {file.string(), std::string("FetchReachDense-v4 seed 0"),
        std::string("FetchReach-v4 seed 0"), std::string("--overwrite")}) {
    EXPECT_NE(r.output.find(needle), std::string::npos) << needle << " in " << r.output;
  }
  EXPECT_EQ(ReadFile(file), first);
  // another seed: refused too
  r = RunFetchscope("random-episodes --n-episodes 2 --seed 5 --json-out " + prefix);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("seed 5"), std::string::npos) << r.output;
  EXPECT_EQ(ReadFile(file), first);
  // same env and seed: replaced silently, as before
  r = RunFetchscope("random-episodes --n-episodes 3 --json-out " + prefix);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(nlohmann::json::parse(ReadFile(file))["n_episodes"], 3);
  // --overwrite replaces
  r = RunFetchscope(
      "random-episodes --n-episodes 2 --env-id FetchReach-v4 --overwrite --json-out " + prefix);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(nlohmann::json::parse(ReadFile(file))["env_id"], "FetchReach-v4");

  // the other json writers: describe (env), reward-check (task, seed), rollout (env, seed)
  const std::vector<std::pair<std::string, std::string>> writers = {
      {"describe", "describe"},
      {"reward-check --n-steps 20", "reward_check"},
      {"rollout --episodes 1 --steps 2", "rollout"}};
  for (const auto& [command, suffix] : writers) {
    SCOPED_TRACE(command);
    const std::string p = (tmp.path() / "w").string();
    r = RunFetchscope(command + " --json-out " + p);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    r = RunFetchscope(command + " --env-id FetchPush-v4 --json-out " + p);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("w_" + suffix + ".json"), std::string::npos) << r.output;
    r = RunFetchscope(command + " --env-id FetchPush-v4 --overwrite --json-out " + p);
    EXPECT_EQ(r.exit_code, 0) << r.output;
  }
}

}  // namespace
}  // namespace fetchscope
