// A trajectory JSON replayed with --policy replay:FILE.json brings its own env and seed (issue
// 19's wrong result): without --env-id/--seed the replay reproduces the recording, and a command
// line naming another env or seed is refused with one line naming both, --quiet or not.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "test_util.h"

namespace fetchscope {
namespace {

using testing::ReadFile;
using testing::RunFetchscope;
using testing::TempDir;
namespace fs = std::filesystem;

// The steps of the single episode in a record run's episode_NNN.json.
nlohmann::json Steps(const fs::path& file) {
  return nlohmann::json::parse(ReadFile(file)).at("episodes").at(0).at("steps");
}

class ReplayEnvTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // recorded on a non-default env and seed: FetchReach-v4 (sparse), seed 3
    const auto r = RunFetchscope(
        "record --env-id FetchReach-v4 --seed 3 --episodes 2 --width 64 "
        "--height 48 --overlay goal --quiet --no-report --out '" +
        recorded().string() + "'");
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  fs::path recorded() const { return tmp_.path() / "a"; }
  fs::path episode() const { return recorded() / "episode_001.json"; }
  TempDir tmp_;
};

TEST_F(ReplayEnvTest, RecordTakesTheFilesEnvAndSeedEvenWhenQuiet) {
  const fs::path out = tmp_.path() / "b";
  const auto r = RunFetchscope("record --policy replay:'" + episode().string() +
                               "' --quiet --width 64 --height 48 --overlay goal --no-report "
                               "--out '" +
                               out.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json replayed = nlohmann::json::parse(ReadFile(out / "episode_001.json"));
  EXPECT_EQ(replayed.at("env_id"), "FetchReach-v4");
  EXPECT_EQ(replayed.at("seed"), 3);
  // the same episode, step for step: observations, actions, rewards, success
  EXPECT_EQ(replayed.at("episodes").at(0).at("steps"), Steps(episode()));
  const nlohmann::json manifest = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  EXPECT_EQ(manifest.at("env_id"), "FetchReach-v4");
  EXPECT_EQ(manifest.at("seed"), 3);
}

TEST_F(ReplayEnvTest, RolloutAndRenderTakeTheFilesEnvAndSeed) {
  const auto r = RunFetchscope("rollout --policy replay:'" + episode().string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j.at("env_id"), "FetchReach-v4");
  EXPECT_EQ(j.at("episodes").at(0).at("steps"), Steps(episode()));
  const auto frame = RunFetchscope("render --policy replay:'" + episode().string() +
                                   "' --steps 5 --width 64 --height 48 -o '" +
                                   (tmp_.path() / "f.png").string() + "'");
  EXPECT_EQ(frame.exit_code, 0) << frame.output;
}

TEST_F(ReplayEnvTest, ACommandLineNamingAnotherEnvOrSeedIsRefusedNamingBoth) {
  for (const std::string& other : {std::string("--env-id FetchPush-v4"), std::string("--seed 4"),
                                   std::string("--env-id FetchReachDense-v4 --quiet")}) {
    const fs::path out = tmp_.path() / "refused";
    const auto r = RunFetchscope("record " + other + " --policy replay:'" + episode().string() +
                                 "' --width 64 --height 48 --out '" + out.string() + "'");
    EXPECT_EQ(r.exit_code, 2) << other << ": " << r.output;
    EXPECT_NE(r.output.find("FetchReach-v4 with --seed 3"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("drop --env-id and --seed"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out / "manifest.json")) << other;
    const auto rollout =
        RunFetchscope("rollout " + other + " --policy replay:'" + episode().string() + "'");
    EXPECT_EQ(rollout.exit_code, 2) << other << ": " << rollout.output;
  }
}

TEST_F(ReplayEnvTest, NamingTheFilesOwnEnvAndSeedIsAccepted) {
  const auto r = RunFetchscope("rollout --env-id FetchReach-v4 --seed 3 --policy replay:'" +
                               episode().string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(nlohmann::json::parse(r.output).at("episodes").at(0).at("steps"), Steps(episode()));
}

}  // namespace
}  // namespace fetchscope
