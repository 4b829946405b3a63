// `rollout`, black box: byte-identical JSON for the same seed, replayed and exec actions, the
// scripted policy's success rates, and --steps past the env's TimeLimit marked.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <string>

#include "src/trajectory.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::CommandResult;
using testing::Count;
using testing::ReadFile;
using testing::RunFetchscope;
using testing::TempDir;
namespace fs = std::filesystem;
using nlohmann::json;

TEST(Cli, SameSeedSameCommandGivesByteIdenticalJson) {
  TempDir tmp;
  const std::string a = (tmp.path() / "a.json").string(), b = (tmp.path() / "b.json").string();
  const std::string cmd =
      "rollout --env-id FetchPickAndPlace-v4 --episodes 2 --seed 5 --policy random --json-out ";
  ASSERT_EQ(RunFetchscope(cmd + a).exit_code, 0);
  ASSERT_EQ(RunFetchscope(cmd + b).exit_code, 0);
  EXPECT_EQ(ReadFile(a), ReadFile(b));
  EXPECT_FALSE(ReadFile(a).empty());
  auto j = nlohmann::json::parse(ReadFile(a));
  ASSERT_EQ(j["episodes"].size(), 2u);
  EXPECT_EQ(j["episodes"][0]["steps"].size(), 51u);
  EXPECT_TRUE(j["episodes"][0]["steps"][0]["action"].is_null());
  EXPECT_TRUE(j["episodes"][0]["steps"][0]["reward"].is_null());
  EXPECT_EQ(j["episodes"][0]["steps"][1]["observation"].size(), 25u);
  EXPECT_EQ(j["episodes"][0]["action_dtype"], "float32");
  EXPECT_NE(j["episodes"][0]["steps"][0]["desired_goal"],
            j["episodes"][1]["steps"][0]["desired_goal"]);
}

TEST(Cli, ReplayReproducesFileActionsExactly) {
  TempDir tmp;
  const fs::path csv = tmp.path() / "a.csv";
  {
    std::ofstream out(csv);
    out << std::setprecision(17);
    for (int t = 0; t < 10; ++t) out << 0.1 * t << "," << -0.123456789012345 << ",0.7,-1\n";
  }
  const std::string out = (tmp.path() / "t.json").string();
  auto r = RunFetchscope("rollout --env-id FetchPickAndPlace-v4 --steps 10 --policy replay:" +
                         csv.string() + " --json-out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto j = nlohmann::json::parse(ReadFile(out));
  const auto& steps = j["episodes"][0]["steps"];
  ASSERT_EQ(steps.size(), 11u);
  for (int t = 0; t < 10; ++t) {
    EXPECT_EQ(steps[t + 1]["action"][0].get<double>(), 0.1 * t);
    EXPECT_EQ(steps[t + 1]["action"][1].get<double>(), -0.123456789012345);
  }
  EXPECT_EQ(j["episodes"][0]["action_dtype"], "float64");
  // the same actions through exec: give the same trajectory
  const fs::path script = tmp.path() / "p.py";
  {
    std::ofstream py(script);
    py << "import sys, json\nfor t, line in enumerate(sys.stdin):\n"
          "    json.loads(line)\n"
          "    print(repr(0.1 * t), -0.123456789012345, 0.7, -1, flush=True)\n";
  }
  const std::string out2 = (tmp.path() / "e.json").string();
  r = RunFetchscope("rollout --env-id FetchPickAndPlace-v4 --steps 10 --policy 'exec:python3 " +
                    script.string() + "' --json-out " + out2);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto e = nlohmann::json::parse(ReadFile(out2));
  EXPECT_EQ(e["episodes"][0]["steps"], j["episodes"][0]["steps"]);
}

TEST(Cli, ScriptedPolicySolvesTheTasks) {
  struct Case {
    const char* id;
    int min_successes;  // of 20 (PRODUCT: Reach 95%, Push 80%, PickAndPlace 70%)
  };
  for (Case c :
       {Case{"FetchReach-v4", 19}, Case{"FetchPush-v4", 16}, Case{"FetchPickAndPlace-v4", 14}}) {
    auto r = RunFetchscope(std::string("rollout --episodes 20 --policy scripted --env-id ") + c.id);
    ASSERT_EQ(r.exit_code, 0);
    auto j = nlohmann::json::parse(r.output);
    int successes = 0;
    for (const auto& e : j["episodes"]) successes += e["is_success"].get<bool>();
    EXPECT_GE(successes, c.min_successes) << c.id;
  }
}

TEST(PastTimeLimit, RolloutMarksEveryStepAfterTheLimit) {
  TempDir tmp;
  const fs::path t = tmp.path() / "t.json";
  const CommandResult r = RunFetchscope(
      "rollout --env-id FetchReach-v4 --steps 53 --episodes 2 --json-out " + t.string() + " 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(Count(r.output, "TimeLimit"), 1) << r.output;  // said once
  EXPECT_NE(r.output.find("steps 51..53"), std::string::npos) << r.output;
  const json j = json::parse(ReadFile(t));
  ASSERT_TRUE(j.contains("note"));
  EXPECT_NE(j["note"].get<std::string>().find("TimeLimit"), std::string::npos);
  for (const json& e : j["episodes"]) {
    ASSERT_EQ(e["steps"].size(), 54u);
    for (const json& s : e["steps"]) {
      const int step = s["t"].get<int>();
      EXPECT_EQ(s.contains("past_time_limit"), step > 50) << step;
      if (step > 50) {
        EXPECT_EQ(s["past_time_limit"], true);
      }
    }
    EXPECT_EQ(e["past_time_limit"],
              (json{{"max_episode_steps", 50}, {"first_step", 51}, {"steps", 3}}));
  }
  // the file reads back and writes the same bytes
  EXPECT_EQ(TrajectoryText(ParseTrajectory(ReadFile(t), t.string())), ReadFile(t));
  // within the limit nothing is marked or said
  const CommandResult within = RunFetchscope("rollout --env-id FetchReach-v4 --steps 50 2>&1");
  ASSERT_EQ(within.exit_code, 0) << within.output;
  EXPECT_EQ(within.output.find("past_time_limit"), std::string::npos);
  EXPECT_EQ(within.output.find("TimeLimit"), std::string::npos);
  EXPECT_EQ(within.output.find("\"note\""), std::string::npos);
}

}  // namespace
}  // namespace fetchscope
