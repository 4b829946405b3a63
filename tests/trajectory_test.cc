// The trajectory type, its one writer and its one reader (src/trajectory.h), and the episode
// sources built on them (src/episode_source.h): write -> read -> write gives the same bytes,
// read gives the same values bit for bit, and a malformed file is refused naming the file and
// the key.
#include "src/trajectory.h"

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "base/errors.h"
#include "base/json_util.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/episode.h"
#include "src/episode_source.h"
#include "src/fetch_env.h"
#include "src/policy.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

uint64_t Bits(double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof(bits));
  return bits;
}

// Equal bit for bit (so -0.0 differs from 0.0 and NaN equals NaN).
void ExpectSameBits(double a, double b, const std::string& what) {
  EXPECT_EQ(Bits(a), Bits(b)) << what << ": " << a << " vs " << b;
}

TrajectoryStep Step(int t, std::vector<double> observation, std::array<double, 3> achieved,
                    std::array<double, 3> desired, std::optional<Action> action,
                    std::optional<double> reward, bool success) {
  TrajectoryStep s;
  s.t = t;
  s.obs.observation = std::move(observation);
  s.obs.achieved_goal = achieved;
  s.obs.desired_goal = desired;
  s.action = action;
  s.reward = reward;
  s.is_success = success;
  return s;
}

Action MakeAction(std::array<double, 4> value, bool float32) {
  Action a;
  a.value = value;
  a.is_float32 = float32;
  return a;
}

// Values that a careless writer or reader would change: -0.0, the shortest round-trip digits,
// subnormals, the extremes, non-finite observations and rewards.
Trajectory HardTrajectory() {
  Trajectory t;
  t.env_id = "FetchPush-v4";
  t.seed = 18446744073709551615ull;  // 2^64 - 1
  t.policy = "replay:run/episode_003.json";
  t.assets.kind = "dir";
  t.assets.root = "/opt/assets \"quoted\" ü";
  t.assets.sha256 = "ab12";
  t.assets.origin = "--assets auto: $FETCHSCOPE_ASSETS";
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();

  TrajectoryEpisode a;  // float32 actions, complete
  a.index = 0;
  a.steps.push_back(
      Step(0, {-0.0, 0.1 + 0.2, 5e-324, DBL_MAX, -DBL_MIN, 1e16, 1e-5, 123456789.0, -1.0, 0.0},
           {1.3, 0.75, 0.42}, {-0.0, 1e-300, 2.0 / 3.0}, std::nullopt, std::nullopt, false));
  a.steps.push_back(Step(1, {inf, -inf, nan, 0, 1, 2, 3, 4, 5, 6}, {1, 2, 3}, {4, 5, 6},
                         MakeAction({0.1f, -1.0f, 0.333333343f, -0.0f}, true), -1.0, false));
  a.steps.push_back(Step(2, std::vector<double>(10, 0.5), {1, 2, 3}, {4, 5, 6},
                         MakeAction({1e-45f, 3.4028234663852886e38, 0, 1}, true), -0.0, true));
  a.episode_return = -1.0;
  a.complete = true;

  TrajectoryEpisode b;  // float64 actions, cut short by SIGINT
  b.index = 7;
  b.steps.push_back(Step(0, std::vector<double>(25, 0.25), {0, 0, 0}, {0, 0, 0}, std::nullopt,
                         std::nullopt, false));
  b.steps.push_back(Step(1, std::vector<double>(25, -0.125), {0, 0, 0}, {0, 0, 0},
                         MakeAction({0.1, 0.2, 0.30000000000000004, -0.7}, false),
                         -0.06283185307179587, false));
  b.episode_return = -0.06283185307179587;
  b.complete = false;

  TrajectoryEpisode c;  // the reset alone
  c.index = 3;
  c.steps.push_back(Step(0, std::vector<double>(10, 1.0), {1, 1, 1}, {2, 2, 2}, std::nullopt,
                         std::nullopt, true));
  c.episode_return = inf;

  t.episodes = {a, b, c};
  return t;
}

void ExpectSameTrajectory(const Trajectory& read, const Trajectory& written) {
  EXPECT_EQ(read.env_id, written.env_id);
  EXPECT_EQ(read.seed, written.seed);
  EXPECT_EQ(read.policy, written.policy);
  EXPECT_EQ(read.assets.kind, written.assets.kind);
  EXPECT_EQ(read.assets.root, written.assets.root);
  EXPECT_EQ(read.assets.sha256, written.assets.sha256);
  EXPECT_EQ(read.assets.origin, written.assets.origin);
  ASSERT_EQ(read.episodes.size(), written.episodes.size());
  for (size_t e = 0; e < read.episodes.size(); ++e) {
    const TrajectoryEpisode& r = read.episodes[e];
    const TrajectoryEpisode& w = written.episodes[e];
    const std::string where = "episode " + std::to_string(w.index);
    EXPECT_EQ(r.index, w.index);
    EXPECT_EQ(r.complete, w.complete) << where;
    ExpectSameBits(r.episode_return, w.episode_return, where + " return");
    ASSERT_EQ(r.steps.size(), w.steps.size()) << where;
    for (size_t t = 0; t < r.steps.size(); ++t) {
      const TrajectoryStep& rs = r.steps[t];
      const TrajectoryStep& ws = w.steps[t];
      const std::string at = where + " step " + std::to_string(t);
      EXPECT_EQ(rs.t, ws.t) << at;
      ASSERT_EQ(rs.obs.observation.size(), ws.obs.observation.size()) << at;
      for (size_t i = 0; i < rs.obs.observation.size(); ++i) {
        ExpectSameBits(rs.obs.observation[i], ws.obs.observation[i],
                       at + " observation[" + std::to_string(i) + "]");
      }
      for (int i = 0; i < 3; ++i) {
        ExpectSameBits(rs.obs.achieved_goal[i], ws.obs.achieved_goal[i], at + " achieved_goal");
        ExpectSameBits(rs.obs.desired_goal[i], ws.obs.desired_goal[i], at + " desired_goal");
      }
      ASSERT_EQ(rs.action.has_value(), ws.action.has_value()) << at;
      if (rs.action) {
        EXPECT_EQ(rs.action->is_float32, ws.action->is_float32) << at;
        for (int i = 0; i < 4; ++i) {
          ExpectSameBits(rs.action->value[i], ws.action->value[i], at + " action");
        }
      }
      ASSERT_EQ(rs.reward.has_value(), ws.reward.has_value()) << at;
      if (rs.reward) ExpectSameBits(*rs.reward, *ws.reward, at + " reward");
      EXPECT_EQ(rs.is_success, ws.is_success) << at;
    }
  }
}

TEST(Trajectory, WriteReadWriteGivesTheSameBytesAndValues) {
  const Trajectory written = HardTrajectory();
  const std::string text = TrajectoryText(written);
  const Trajectory read = ParseTrajectory(text, "hard.json");
  ExpectSameTrajectory(read, written);
  EXPECT_EQ(TrajectoryText(read), text);
  // Python's json.dumps spelling of the hard doubles
  EXPECT_NE(text.find("-0.0,"), std::string::npos);
  EXPECT_NE(text.find("0.30000000000000004"), std::string::npos);
  EXPECT_NE(text.find("5e-324"), std::string::npos);
  EXPECT_NE(text.find("\"nan\""), std::string::npos);
  EXPECT_NE(text.find("18446744073709551615"), std::string::npos);
  EXPECT_EQ(text.back(), '\n');
  // what the file says of each episode, derived from its steps
  const nlohmann::json j = nlohmann::json::parse(text);
  EXPECT_EQ(j["episodes"][0]["action_dtype"], "float32");
  EXPECT_EQ(j["episodes"][1]["action_dtype"], "float64");
  EXPECT_EQ(j["episodes"][2]["action_dtype"], "none");
  EXPECT_EQ(j["episodes"][0]["length"], 2);
  EXPECT_EQ(j["episodes"][0]["is_success"], true);
  EXPECT_EQ(j["episodes"][1]["complete"], false);
  EXPECT_EQ(j["episodes"][2]["return"], "inf");
}

TEST(Trajectory, IncompleteEpisodesStayIncompleteAndOlderFilesReadAsBefore) {
  const Trajectory read = ParseTrajectory(TrajectoryText(HardTrajectory()), "hard.json");
  EXPECT_TRUE(read.episodes[0].complete);
  EXPECT_FALSE(read.episodes[1].complete);
  // only the file's episode 0 was reset with the file's seed
  ASSERT_TRUE(read.episodes[0].seed.has_value());
  EXPECT_EQ(*read.episodes[0].seed, 18446744073709551615ull);
  EXPECT_FALSE(read.episodes[1].seed.has_value());
  EXPECT_EQ(read.episodes[1].file, "hard.json");

  // files from before "complete", "action_dtype" and "return": complete, float64, summed
  nlohmann::json j = nlohmann::json::parse(TrajectoryText(HardTrajectory()));
  for (auto& e : j["episodes"]) {
    e.erase("complete");
    e.erase("action_dtype");
    e.erase("return");
  }
  const Trajectory old = ParseTrajectory(j.dump(), "old.json");
  EXPECT_TRUE(old.episodes[1].complete);
  EXPECT_FALSE(old.episodes[1].steps[1].action->is_float32);
  EXPECT_EQ(old.episodes[1].episode_return, -0.06283185307179587);
}

// The schema version, as the manifest's: written, absent = version 0 (read as before), newer =
// refused in one line naming the file and both versions.
TEST(Trajectory, SchemaVersionIsWrittenAndANewerOneIsRefused) {
  static_assert(kTrajectorySchemaVersion == 1, "the messages below name version 1");
  nlohmann::json j = nlohmann::json::parse(TrajectoryText(HardTrajectory()));
  EXPECT_EQ(j["schema_version"], kTrajectorySchemaVersion);
  EXPECT_EQ(ParseTrajectory(j.dump(), "v1.json").schema_version, 1);

  // a file from before versions: read as version 0, the same values, written back versioned
  j.erase("schema_version");
  const Trajectory old = ParseTrajectory(j.dump(), "old.json");
  EXPECT_EQ(old.schema_version, 0);
  ExpectSameTrajectory(old, HardTrajectory());
  EXPECT_EQ(TrajectoryText(old), TrajectoryText(HardTrajectory()));

  TempDir tmp;
  const fs::path newer = tmp.path() / "newer.json";
  j["schema_version"] = 2;
  std::ofstream(newer) << j.dump();
  const std::string refusal = newer.string() +
                              ": has trajectory schema version 2; this fetchscope reads versions "
                              "0 to 1: use a newer fetchscope";
  try {
    ReadTrajectory(newer.string());
    FAIL() << "accepted";
  } catch (const RunError& e) {
    EXPECT_EQ(std::string(e.what()), refusal);
  }
  // as a replay file too, even where the newer layout has moved the episodes
  j.erase("episodes");
  std::ofstream(newer) << j.dump();
  try {
    ReadReplayTrajectory(newer.string());
    FAIL() << "accepted";
  } catch (const RunError& e) {
    EXPECT_EQ(std::string(e.what()), "replay file " + refusal);
  }
}

// A real episode: what RunEpisode played is what the file gives back.
TEST(Trajectory, ARecordedEpisodeReadsBackExactly) {
  const EnvSpec& spec = FindEnvSpec("FetchPush-v4");
  FetchEnv env(spec, ResolveAssets("bundled"));
  PolicyContext context;
  context.seed = 5;
  auto policy = MakePolicy(PolicySpec::Random(), spec, context);
  Trajectory written;
  written.env_id = spec.id;
  written.seed = 5;
  written.policy = "random";
  written.assets = env.assets();
  written.episodes.push_back(RunEpisode(env, *policy, 0, 5, 6));
  written.episodes.push_back(RunEpisode(env, *policy, 1, std::nullopt, 6));
  const std::string text = TrajectoryText(written);
  const nlohmann::json episodes =
      nlohmann::json::array({EpisodeJson(written.episodes[0]), EpisodeJson(written.episodes[1])});
  EXPECT_EQ(text, DumpJson(TrajectoryJson(spec, env.assets(), 5, "random", episodes)) + "\n");
  const Trajectory read = ParseTrajectory(text, "push.json");
  ExpectSameTrajectory(read, written);
  EXPECT_EQ(TrajectoryText(read), text);
}

struct BadCase {
  const char* name;
  // edits a valid trajectory document
  std::function<void(nlohmann::json&)> edit;
  const char* message;  // the whole message after "t.json: "
};

class BadTrajectoryTest : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadTrajectoryTest, NamesTheFileAndTheKey) {
  nlohmann::json j = nlohmann::json::parse(TrajectoryText(HardTrajectory()));
  GetParam().edit(j);
  try {
    ParseTrajectory(j.dump(), "t.json");
    FAIL() << "accepted";
  } catch (const RunError& e) {
    EXPECT_EQ(std::string(e.what()), std::string("t.json: ") + GetParam().message);
  }
}

using nlohmann::json;

INSTANTIATE_TEST_SUITE_P(
    Reader, BadTrajectoryTest,
    ::testing::Values(
        BadCase{"NotATrajectory",
                [](json& j) {
                  j = {{"a", 1}};
                },
                "not a fetchscope trajectory (an object with env_id, seed and episodes)"},
        BadCase{"NoEnvId", [](json& j) { j.erase("env_id"); }, "env_id: expected a string"},
        BadCase{"VersionNotAnInteger", [](json& j) { j["schema_version"] = "1"; },
                "schema_version: expected an integer of at least 0, found \"1\""},
        BadCase{"NegativeVersion", [](json& j) { j["schema_version"] = -1; },
                "schema_version: expected an integer of at least 0, found -1"},
        BadCase{"NegativeSeed", [](json& j) { j["seed"] = -1; },
                "seed: expected a non-negative integer below 2^64"},
        BadCase{"EpisodesNotAList", [](json& j) { j["episodes"] = 3; },
                "episodes: expected a list"},
        BadCase{"NoIndex", [](json& j) { j["episodes"][1].erase("index"); },
                "episodes[1].index: expected an integer from 0 to 100000000"},
        BadCase{"RepeatedIndex", [](json& j) { j["episodes"][2]["index"] = 0; },
                "episodes[2].index: episode 0 appears twice"},
        BadCase{"ShortAction", [](json& j) { j["episodes"][1]["steps"][1]["action"].erase(0); },
                "episodes[1].steps[1].action: expected 4 numbers"},
        BadCase{"TextInAction", [](json& j) { j["episodes"][1]["steps"][1]["action"][2] = "0.3"; },
                "episodes[1].steps[1].action[2]: expected a number, found \"0.3\""},
        BadCase{"InfiniteAction",
                [](json& j) { j["episodes"][1]["steps"][1]["action"][0] = "inf"; },
                "episodes[1].steps[1].action[0]: expected a number, found \"inf\""},
        BadCase{"NotFloat32", [](json& j) { j["episodes"][0]["steps"][2]["action"][3] = 0.1; },
                "episodes[0].steps[2].action[3]: 0.1 is not a float32 number although "
                "action_dtype is float32"},
        BadCase{"UnknownDtype", [](json& j) { j["episodes"][0]["action_dtype"] = "float16"; },
                "episodes[0].action_dtype: 'float16' is not float32, float64 or none"},
        BadCase{"NoSteps", [](json& j) { j["episodes"][2]["steps"] = json::array(); },
                "episodes[2].steps: expected a list starting with the reset (t = 0)"},
        BadCase{"StepNotAnObject", [](json& j) { j["episodes"][0]["steps"][1] = 1; },
                "episodes[0].steps[1]: expected an object"},
        BadCase{"WrongT", [](json& j) { j["episodes"][0]["steps"][2]["t"] = 5; },
                "episodes[0].steps[2].t: expected 2, found 5"},
        BadCase{"TextInObservation",
                [](json& j) { j["episodes"][0]["steps"][0]["observation"][4] = "abc"; },
                "episodes[0].steps[0].observation[4]: expected a number, found \"abc\""},
        BadCase{"EmptyObservation",
                [](json& j) { j["episodes"][0]["steps"][0]["observation"] = json::array(); },
                "episodes[0].steps[0].observation: expected a list of numbers"},
        BadCase{"ShortGoal",
                [](json& j) {
                  j["episodes"][1]["steps"][0]["desired_goal"] = {1, 2};
                },
                "episodes[1].steps[0].desired_goal: expected 3 numbers"},
        BadCase{"ActionAtReset",
                [](json& j) {
                  j["episodes"][0]["steps"][0]["action"] = {0, 0, 0, 0};
                },
                "episodes[0].steps[0].action: expected null at the reset (t = 0)"},
        BadCase{"NoReward", [](json& j) { j["episodes"][0]["steps"][1].erase("reward"); },
                "episodes[0].steps[1].reward: expected a number"},
        BadCase{"NullReward", [](json& j) { j["episodes"][0]["steps"][1]["reward"] = nullptr; },
                "episodes[0].steps[1].reward: expected a number, found null"},
        BadCase{"NoSuccess", [](json& j) { j["episodes"][1]["steps"][1].erase("is_success"); },
                "episodes[1].steps[1].is_success: expected true or false"},
        BadCase{"CompleteNotABool", [](json& j) { j["episodes"][1]["complete"] = "no"; },
                "episodes[1].complete: expected true or false"},
        BadCase{"ResetNotPlaced",
                [](json& j) {
                  j["episodes"][0]["reset"] = {{"rule", "seed"}, {"goal", {1, 2, 3}}};
                },
                "episodes[0].reset.rule: expected \"placed\""},
        BadCase{"ResetUnknownMember",
                [](json& j) {
                  j["episodes"][0]["reset"] = {{"rule", "placed"}, {"goal", {1, 2, 3}}, {"g", 1}};
                },
                "episodes[0].reset.g: unknown member; accepted: rule, goal, object_position, "
                "object_euler"},
        BadCase{"ResetGoalInfinite",
                [](json& j) {
                  j["episodes"][0]["reset"] = {{"rule", "placed"}, {"goal", {1, "inf", 3}}};
                },
                "episodes[0].reset.goal: expected 3 finite numbers"},
        BadCase{"ResetObjectHalf",
                [](json& j) {
                  j["episodes"][0]["reset"] = {
                      {"rule", "placed"}, {"goal", {1, 2, 3}}, {"object_position", {1, 2, 3}}};
                },
                "episodes[0].reset: expected object_position and object_euler together, or "
                "neither"}),
    [](const ::testing::TestParamInfo<BadCase>& info) { return std::string(info.param.name); });

TEST(Trajectory, TextThatIsNotJsonNamesTheFile) {
  try {
    ParseTrajectory("{\"episodes\": [", "cut.json");
    FAIL() << "accepted";
  } catch (const RunError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("cut.json: not JSON: ", 0), 0u) << e.what();
  }
  EXPECT_THROW(ReadTrajectory("/nonexistent/t.json"), RunError);
}

TEST(Trajectory, ReplayFilesAreTrajectoriesOnlyWhenTheyHoldOne) {
  TempDir tmp;
  const fs::path rows = tmp.path() / "rows.json", run = tmp.path() / "run.json",
                 bad = tmp.path() / "bad.json", csv = tmp.path() / "run.csv";
  std::ofstream(rows) << "[[0, 0, 0, 1]]";
  std::ofstream(run) << TrajectoryText(HardTrajectory());
  nlohmann::json j = nlohmann::json::parse(TrajectoryText(HardTrajectory()));
  j["episodes"][0]["steps"][1]["action"] = {1, 2};
  std::ofstream(bad) << j.dump();
  std::ofstream(csv) << TrajectoryText(HardTrajectory());
  EXPECT_FALSE(ReadReplayTrajectory(rows.string()).has_value());
  EXPECT_FALSE(ReadReplayTrajectory(csv.string()).has_value());
  EXPECT_FALSE(ReadReplayTrajectory((tmp.path() / "missing.json").string()).has_value());
  const std::optional<Trajectory> read = ReadReplayTrajectory(run.string());
  ASSERT_TRUE(read.has_value());
  EXPECT_EQ(read->episodes.size(), 3u);
  try {
    ReadReplayTrajectory(bad.string());
    FAIL() << "accepted";
  } catch (const RunError& e) {
    EXPECT_EQ(std::string(e.what()),
              "replay file " + bad.string() + ": episodes[0].steps[1].action: expected 4 numbers");
  }
}

// The sources: episodes played by EpisodeSequence, written, loaded as record --from loads them
// and replayed by EpisodeReplayer come out the same; an edited reward is caught at its step.
TEST(EpisodeSource, ARecordingReplaysExactlyAndAnEditIsCaught) {
  TempDir tmp;
  const EnvSpec& spec = FindEnvSpec("FetchReach-v4");
  PolicyContext context;
  context.seed = 11;
  EpisodeSequence sequence(std::make_unique<FetchEnv>(spec, ResolveAssets("bundled")),
                           MakePolicy(PolicySpec::Random(), spec, context), 11, 5);
  Trajectory written;
  written.env_id = spec.id;
  written.seed = 11;
  written.policy = "random";
  written.assets = sequence.env().assets();
  written.episodes.push_back(sequence.Play(0));
  written.episodes.push_back(sequence.Play(2));  // episode 1's reset is replayed in between
  const fs::path file = tmp.path() / "run.json";
  std::ofstream(file) << TrajectoryText(written);

  const TrajectorySource source = LoadTrajectorySource(file.string());
  EXPECT_EQ(source.env_id, "FetchReach-v4");
  EXPECT_EQ(source.seed, 11u);
  EXPECT_EQ(source.max_steps, 5);
  ASSERT_EQ(source.episodes.size(), 2u);
  EXPECT_EQ(source.episodes.at(2).file, file.string());
  EXPECT_EQ(SourceAssets(source), "bundled");
  FetchEnv env(spec, ResolveAssets("bundled"));
  EXPECT_NO_THROW(VerifyRecording(env, source));
  EpisodeReplayer replayer(env, 11);
  const EpisodeRecord replayed = replayer.Replay(2, source.episodes.at(2).steps, true, "", nullptr);
  Trajectory again = written;
  again.episodes = {written.episodes[0], replayed};
  EXPECT_EQ(TrajectoryText(again), TrajectoryText(written));

  nlohmann::json j = nlohmann::json::parse(TrajectoryText(written));
  j["episodes"][1]["steps"][4]["reward"] = 0.5;
  std::ofstream(file) << j.dump();
  try {
    FetchEnv fresh(spec, ResolveAssets("bundled"));
    VerifyRecording(fresh, LoadTrajectorySource(file.string()));
    FAIL() << "the edit was not caught";
  } catch (const ReplayMismatch& e) {
    EXPECT_NE(std::string(e.what()).find(file.string() + ": episode 2 step 4: reward recorded 0.5"),
              std::string::npos)
        << e.what();
  }
  // two files of different runs are refused
  const fs::path folder = tmp.path() / "mixed";
  fs::create_directories(folder);
  std::ofstream(folder / "episode_000.json") << TrajectoryText(written);
  written.seed = 12;
  std::ofstream(folder / "episode_001.json") << TrajectoryText(written);
  try {
    LoadTrajectorySource(folder.string());
    FAIL() << "mixed runs accepted";
  } catch (const RunError& e) {
    EXPECT_NE(std::string(e.what()).find("one run at a time"), std::string::npos) << e.what();
  }
}

// An episode whose reset was placed by hand (serve's form): written with its "reset", replayed
// from there and checked step by step; an edited placement is caught at the reset.
TEST(EpisodeSource, APlacedResetReplaysExactlyAndAnEditedPlacementIsCaught) {
  TempDir tmp;
  const EnvSpec& spec = FindEnvSpec("FetchPush-v4");
  FetchEnv env(spec, ResolveAssets("bundled"));
  const Observation drawn = env.Reset(4);
  PlacedReset placed;
  placed.goal = {1.4, 0.6, 0.42};
  placed.object = ObjectPose{{1.2, 0.9, drawn.observation[5]},
                             {drawn.observation[11], drawn.observation[12], drawn.observation[13]}};
  TrajectoryEpisode episode;
  episode.placed = placed;
  TrajectoryStep row;
  row.obs = env.ResetTo(placed.goal, placed.object);
  row.is_success = env.IsSuccess(row.obs.achieved_goal, row.obs.desired_goal);
  episode.steps.push_back(row);
  for (int t = 1; t <= 4; ++t) {
    Action a;
    a.value = {0.3 * t, -0.5, 0.1, 1};
    const StepResult r = env.Step(a);
    TrajectoryStep step;
    step.t = t;
    step.obs = r.obs;
    step.action = a;
    step.reward = r.reward;
    step.is_success = r.is_success;
    episode.steps.push_back(step);
    episode.episode_return += r.reward;
  }
  Trajectory written;
  written.env_id = spec.id;
  written.seed = 4;
  written.policy = "keys";
  written.assets = env.assets();
  written.episodes = {episode};
  const fs::path file = tmp.path() / "placed.json";
  std::ofstream(file) << TrajectoryText(written);

  const TrajectorySource source = LoadTrajectorySource(file.string());
  ASSERT_EQ(source.starts.count(0), 1u);
  EXPECT_STREQ(source.starts.at(0).Rule(), "placed");
  FetchEnv fresh(spec, ResolveAssets("bundled"));
  EXPECT_NO_THROW(VerifyRecording(fresh, source));
  EpisodeReplayer replayer(fresh, 4);
  Trajectory again = written;
  again.episodes = {replayer.ReplaySource(source, 0, nullptr)};
  EXPECT_EQ(TrajectoryText(again), TrajectoryText(written));  // "reset" written again

  nlohmann::json j = nlohmann::json::parse(TrajectoryText(written));
  j["episodes"][0]["reset"]["object_position"][0] = 1.21;
  std::ofstream(file) << j.dump();
  try {
    FetchEnv other(spec, ResolveAssets("bundled"));
    VerifyRecording(other, LoadTrajectorySource(file.string()));
    FAIL() << "the edited placement was not caught";
  } catch (const ReplayMismatch& e) {
    EXPECT_NE(std::string(e.what()).find("episode 0 step 0: observation[3] recorded 1.2"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace fetchscope
