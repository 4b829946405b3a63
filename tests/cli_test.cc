// Black-box tests of the anatomy subcommands against the built binary.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>

#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::ReadFile;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::TempDir;
namespace fs = std::filesystem;

const char* kIds[] = {"FetchReach-v4",     "FetchReachDense-v4",   "FetchPush-v4",
                      "FetchPushDense-v4", "FetchPickAndPlace-v4", "FetchPickAndPlaceDense-v4",
                      "FetchSlide-v4",     "FetchSlideDense-v4"};

TEST(Cli, ListEnvsJsonHasTheEightIds) {
  auto r = RunFetchscope("list-envs --json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto j = nlohmann::json::parse(r.output);
  ASSERT_EQ(j.size(), 8u);
  for (int i = 0; i < 8; ++i) EXPECT_EQ(j[i]["id"], kIds[i]);
}

TEST(Cli, DescribeEveryId) {
  TempDir tmp;
  for (const char* id : kIds) {
    const std::string prefix = (tmp.path() / id).string();
    auto r = RunFetchscope(std::string("describe --env-id ") + id + " --json-out " + prefix);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    auto j = nlohmann::json::parse(ReadFile(prefix + "_describe.json"));
    const bool reach = std::string(id).find("Reach") != std::string::npos;
    const bool pick = std::string(id).find("PickAndPlace") != std::string::npos;
    EXPECT_EQ(j["action_space"]["shape"][0], 4);
    EXPECT_EQ(j["action_space"]["dtype"], "float32");
    // the chapter's D1 layout: one bound per element, the Boxes directly under
    // observation_space, infinities as strict-JSON strings
    EXPECT_EQ(j["action_space"]["low"], nlohmann::json::parse("[-1.0, -1.0, -1.0, -1.0]"));
    EXPECT_EQ(j["action_space"]["high"], nlohmann::json::parse("[1.0, 1.0, 1.0, 1.0]"));
    const auto& spaces = j["observation_space"];
    EXPECT_EQ(spaces.size(), 3u) << spaces.dump();
    const int n = reach ? 10 : 25;
    EXPECT_EQ(spaces["observation"]["shape"], nlohmann::json::array({n}));
    EXPECT_EQ(spaces["observation"]["labels"].size(), static_cast<size_t>(n));
    for (const char* key : {"achieved_goal", "desired_goal"}) {
      EXPECT_EQ(spaces[key]["type"], "Box");
      EXPECT_EQ(spaces[key]["dtype"], "float64");
      EXPECT_EQ(spaces[key]["shape"], nlohmann::json::array({3}));
      EXPECT_EQ(spaces[key]["low"], nlohmann::json::array({"-inf", "-inf", "-inf"}));
    }
    EXPECT_EQ(spaces["observation"]["high"], std::vector<std::string>(n, "inf"));
    EXPECT_EQ(spaces["observation"]["low"], std::vector<std::string>(n, "-inf"));
    EXPECT_EQ(j["action_space"]["labels"].size(), 4u);
    const std::string grip = j["action_space"]["labels"][3]["meaning"];
    if (pick) {
      EXPECT_NE(grip.find("> 0 OPENS"), std::string::npos) << grip;
    } else {
      EXPECT_NE(grip.find("ignored"), std::string::npos) << grip;
    }
    EXPECT_EQ(j["distance_threshold"], 0.05);
    EXPECT_EQ(j["max_episode_steps"], 50);
    EXPECT_EQ(j["n_substeps"], 20);
    EXPECT_EQ(j["assets"]["sha256"].get<std::string>().size(), 64u);
  }
  auto r = RunFetchscope("describe --env-id auto");
  ASSERT_EQ(r.exit_code, 0);
  EXPECT_EQ(nlohmann::json::parse(r.output)["env_id"], "FetchReachDense-v4");
}

TEST(Cli, RewardCheckPassesForEveryTaskBundledAndGenuine) {
  std::vector<std::string> assets = {"bundled"};
  if (!testing::GenuineAssetsDir().empty()) assets.push_back(testing::GenuineAssetsDir().string());
  for (const std::string& a : assets) {
    for (const char* id :
         {"FetchReach-v4", "FetchPushDense-v4", "FetchPickAndPlace-v4", "FetchSlide-v4"}) {
      auto r = RunFetchscope(std::string("reward-check --n-steps 500 --env-id ") + id +
                             " --assets " + a);
      EXPECT_EQ(r.exit_code, 0) << id << " " << a << "\n" << r.output;
      EXPECT_NE(r.output.find("PASS"), std::string::npos);
      EXPECT_NE(r.output.find("Dense-v4"), std::string::npos);  // both variants checked
    }
  }
}

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

struct BadInput {
  std::string args;
  int exit_code;
  std::string message;  // substring of the one-line error
};

// gtest prints the command line instead of the bytes of the struct
void PrintTo(const BadInput& c, std::ostream* os) { *os << c.args; }

class BadInputTest : public ::testing::TestWithParam<BadInput> {};

TEST_P(BadInputTest, OneClearLineAndNoOutputFile) {
  TempDir tmp;
  const fs::path bad = tmp.path() / "bad";
  fs::create_directories(bad / "fetch");
  std::ofstream(bad / "fetch" / "reach.xml") << "<mujoco><worldbody><body name='x'></mujoco>";
  std::ofstream(bad / "fetch" / "push.xml") << "<mujoco/>";
  std::ofstream(tmp.path() / "nan.csv") << "0,0,0,0\nnan,0,0,0\n";
  std::ofstream(tmp.path() / "three.csv") << "0,0,0\n";
  std::ofstream(tmp.path() / "empty.csv") << "";
  std::ofstream(tmp.path() / "text.csv") << "hello,world\nfoo,bar\n";
  std::string args = GetParam().args;
  for (auto [key, value] : {std::pair<std::string, std::string>{"TMP", tmp.path().string()}}) {
    size_t pos;
    while ((pos = args.find(key)) != std::string::npos) args.replace(pos, key.size(), value);
  }
  const std::string out = (tmp.path() / "out.json").string();
  auto r = RunFetchscope(args + " --json-out " + out);
  EXPECT_EQ(r.exit_code, GetParam().exit_code) << r.output;
  EXPECT_NE(r.output.find(GetParam().message), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("fetchscope: error: "), std::string::npos) << r.output;
  EXPECT_LE(std::count(r.output.begin(), r.output.end(), '\n'), 2) << r.output;
  EXPECT_EQ(r.output.find("terminate"), std::string::npos);
  EXPECT_EQ(r.output.find("Abort"), std::string::npos);
  EXPECT_FALSE(fs::exists(out));
  for (const auto& entry : fs::directory_iterator(tmp.path())) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Anatomy, BadInputTest,
    ::testing::Values(
        BadInput{"describe --env-id FetchReach-v9", 2,
                 "unknown env id 'FetchReach-v9' (did you mean 'FetchReach-v4'?): use one of "
                 "FetchReach-v4"},
        BadInput{"describe --assets TMP/missing", 2, "missing' does not exist: use bundled, auto"},
        BadInput{"describe --assets TMP", 2, "has no fetch/reach.xml"},
        BadInput{"describe --env-id FetchReach-v4 --assets TMP/bad", 1,
                 "bad/fetch/reach.xml': XML parse error"},
        BadInput{"random-episodes --seed -3", 2, "--seed '-3' is not valid"},
        BadInput{"random-episodes --seed 99999999999999999999999", 2, "is too large"},
        BadInput{"random-episodes --n-episodes 0", 2, "--n-episodes"},
        BadInput{"rollout --policy greedy", 2, "unknown policy 'greedy'"},
        BadInput{"rollout --steps 5 --policy replay:TMP/nan.csv", 1, "not a finite number"},
        BadInput{"rollout --steps 1 --policy replay:TMP/three.csv", 1, "three.csv"},
        BadInput{"rollout --steps 1 --policy replay:TMP/empty.csv", 1, "empty"},
        BadInput{"rollout --steps 1 --policy replay:TMP/text.csv", 1, "text.csv"},
        BadInput{"rollout --steps 5 --policy replay:TMP/missing.csv", 1, "missing.csv"},
        BadInput{"rollout --steps 50 --policy replay:TMP/nan.csv", 1, "nan.csv"},
        BadInput{"rollout --steps 3 --policy 'exec:exit 3'", 1, "exited with status 3"},
        BadInput{"rollout --steps 3 --policy 'exec:echo hello; cat >/dev/null'", 1,
                 "answer 'hello'"},
        BadInput{"rollout --steps 3 --exec-timeout 0.5 --policy 'exec:sleep 5'", 1,
                 "no answer for step 0 within 0.5 s"},
        BadInput{"rollout --steps 10001", 2, "--steps"}));

TEST(Cli, UnwritableOutputIsARunError) {
  auto r = RunFetchscope("describe --json-out /proc/nope/x.json");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("/proc/nope"), std::string::npos) << r.output;
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

}  // namespace
}  // namespace fetchscope
