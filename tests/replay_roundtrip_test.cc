// Replaying fetchscope's own output: `--policy replay:episode_NNN.json` plays the trajectory
// JSON's episodes, each under its own index (its own reset) and in its recorded precision, so
// that record -> replay gives the same trajectories bit for bit: float32 (random policy) and
// float64 (scripted policy). --replay-dtype float32 does the same for a CSV export.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::ReadFile;
using testing::RunFetchscope;
using testing::TempDir;
namespace fs = std::filesystem;

nlohmann::json ReadJson(const fs::path& path) { return nlohmann::json::parse(ReadFile(path)); }

class ReplayRoundTrip : public ::testing::Test {
 protected:
  void SetUp() override { unsetenv("DISPLAY"); }
};

// record -> replay each episode's trajectory JSON -> the same trajectory and the same video.
void ExpectRecordReplayRoundTrip(const std::string& env, const std::string& policy,
                                 const std::string& dtype) {
  TempDir tmp;
  const std::string common =
      "record --quiet --env-id " + env + " --width 32 --height 32 --steps 12 --seed 3 ";
  const fs::path first = tmp.path() / "first";
  auto r = RunFetchscope(common + "--episodes 3 --policy " + policy + " --out " + first.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (int k : {2, 0}) {  // episode 2 first: it must play as episode 2, with its own reset
    SCOPED_TRACE("episode " + std::to_string(k));
    const std::string name = "episode_00" + std::to_string(k);
    const nlohmann::json recorded = ReadJson(first / (name + ".json"));
    ASSERT_EQ(recorded["episodes"][0]["action_dtype"], dtype);
    const fs::path again = tmp.path() / ("again" + std::to_string(k));
    r = RunFetchscope(common + "--policy replay:" + (first / (name + ".json")).string() +
                      " --out " + again.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(testing::EpisodeFiles(again).size(), 3u);  // only that episode
    const nlohmann::json replayed = ReadJson(again / (name + ".json"));
    EXPECT_EQ(replayed["episodes"], recorded["episodes"]);
    // the same encoded video stream, packet for packet (the container's tags name the policy,
    // which differs: replay:FILE here)
    auto packets = [](const fs::path& mp4) {
      return testing::RunCommand("ffmpeg -v error -i " + mp4.string() +
                                 " -map 0:v:0 -c copy -f framemd5 -")
          .output;
    };
    const std::string a = packets(again / (name + ".mp4")), b = packets(first / (name + ".mp4"));
    EXPECT_NE(a.find(", "), std::string::npos) << a;  // packets were listed
    EXPECT_EQ(a, b);
  }
}

TEST_F(ReplayRoundTrip, Float32RandomRunReplaysBitForBit) {
  ExpectRecordReplayRoundTrip("FetchPickAndPlace-v4", "random", "float32");
}

TEST_F(ReplayRoundTrip, Float64ScriptedRunReplaysBitForBit) {
  ExpectRecordReplayRoundTrip("FetchPush-v4", "scripted", "float64");
}

// rollout's trajectory JSON with several episodes replays whole through rollout too.
TEST_F(ReplayRoundTrip, RolloutTrajectoryReplaysAllItsEpisodes) {
  TempDir tmp;
  const std::string common = "rollout --env-id FetchSlide-v4 --steps 8 --seed 11 --episodes 3 ";
  auto r = RunFetchscope(common + "--policy random --json-out " + (tmp.path() / "a.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunFetchscope(common + "--policy replay:" + (tmp.path() / "a.json").string() +
                    " --json-out " + (tmp.path() / "b.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(ReadJson(tmp.path() / "b.json")["episodes"],
            ReadJson(tmp.path() / "a.json")["episodes"]);
}

// record's per-episode trajectory (episode_002.json holds episode 2 alone) replays through
// rollout and render as that episode, from its own reset: rollout gives its trajectory back,
// render the frame record drew at that step. A --episodes that disagrees with the file is a
// usage error that says what to do.
TEST_F(ReplayRoundTrip, RolloutAndRenderReplayOneEpisodeOfARecordRun) {
  TempDir tmp;
  const fs::path run = tmp.path() / "run";
  auto r = RunFetchscope(
      "record --quiet --no-report --env-id FetchPush-v4 --policy random "
      "--seed 9 --episodes 3 --steps 6 --width 48 --height 48 --sheet-every 1 "
      "--overlay none --out " +
      run.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string file = (run / "episode_002.json").string();
  const std::string common = "--env-id FetchPush-v4 --seed 9 --policy replay:" + file;
  r = RunFetchscope("rollout --steps 6 " + common + " --json-out " +
                    (tmp.path() / "b.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json replayed = ReadJson(tmp.path() / "b.json")["episodes"];
  ASSERT_EQ(replayed.size(), 1u);
  EXPECT_EQ(replayed[0]["index"], 2);
  EXPECT_EQ(replayed[0]["steps"], ReadJson(file)["episodes"][0]["steps"]);

  r = RunFetchscope("rollout --steps 6 --episodes 2 " + common + " --json-out " +
                    (tmp.path() / "c.json").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--episodes 2 disagrees with"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("drop --episodes"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp.path() / "c.json"));

  // render after the episode's 4 steps sees the state record drew for step 4 of episode 2
  r = RunFetchscope("render --steps 4 --width 48 --height 48 --overlay none " + common + " -o " +
                    (tmp.path() / "frame.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunFetchscope(
      "render --steps 4 --width 48 --height 48 --overlay none --env-id FetchPush-v4 "
      "--seed 9 --policy random -o " +
      (tmp.path() / "episode0.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(ReadFile(tmp.path() / "frame.png"), ReadFile(tmp.path() / "episode0.png"))
      << "render played episode 0, not the file's episode 2";
}

// A CSV export of float32 actions: --replay-dtype float32 reproduces the run; read as float64
// (the default) it takes Gymnasium's double path and drifts.
TEST_F(ReplayRoundTrip, CsvWithReplayDtypeFloat32ReproducesARandomRun) {
  TempDir tmp;
  const std::string common = "rollout --env-id FetchPush-v4 --steps 20 --seed 4 --episodes 2 ";
  auto r = RunFetchscope(common + "--policy random --json-out " + (tmp.path() / "a.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json a = ReadJson(tmp.path() / "a.json");
  std::string csv = "dx,dy,dz,gripper\n", jsonl;
  for (const auto& e : a["episodes"]) {
    for (size_t t = 1; t < e["steps"].size(); ++t) {
      const auto& act = e["steps"][t]["action"];
      for (size_t c = 0; c < 4; ++c) csv += act[c].dump() + (c < 3 ? "," : "\n");
      jsonl += act.dump() + "\n";
    }
  }
  std::ofstream(tmp.path() / "a.csv") << csv;
  std::ofstream(tmp.path() / "a.jsonl") << jsonl;
  for (const char* file : {"a.csv", "a.jsonl"}) {
    SCOPED_TRACE(file);
    r = RunFetchscope(common +
                      "--replay-dtype float32 --policy replay:" + (tmp.path() / file).string() +
                      " --json-out " + (tmp.path() / "b.json").string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json b = ReadJson(tmp.path() / "b.json");
    EXPECT_EQ(b["episodes"], a["episodes"]);
    r = RunFetchscope(common +
                      "--replay-dtype float64 --policy replay:" + (tmp.path() / file).string() +
                      " --json-out " + (tmp.path() / "c.json").string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json c = ReadJson(tmp.path() / "c.json");
    EXPECT_EQ(c["episodes"][0]["action_dtype"], "float64");
    EXPECT_NE(c["episodes"][0]["steps"], a["episodes"][0]["steps"]);
  }
}

// An incomplete (interrupted) episode is not replayed as if it were whole.
TEST_F(ReplayRoundTrip, AnIncompleteEpisodeIsRefused) {
  TempDir tmp;
  const std::string common = "rollout --env-id FetchReach-v4 --steps 6 --seed 1 --episodes 1 ";
  auto r = RunFetchscope(common + "--policy random --json-out " + (tmp.path() / "a.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  nlohmann::json a = ReadJson(tmp.path() / "a.json");
  EXPECT_EQ(a["episodes"][0]["complete"], true);
  auto& steps = a["episodes"][0]["steps"];
  steps.erase(steps.begin() + 4, steps.end());
  a["episodes"][0]["complete"] = false;
  a["episodes"][0]["length"] = 3;
  std::ofstream(tmp.path() / "cut.json") << a.dump();
  r = RunFetchscope(common + "--policy replay:" + (tmp.path() / "cut.json").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("incomplete"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--steps 3"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace fetchscope
