// Minari datasets in and out (dataset/): what MinariWriter writes is checked with Debian's
// python3-h5py against Minari 0.5's format (not with our reader); datasets written in exactly
// Minari's layout by h5py (as create_dataset_from_buffers and DataCollector leave them) are read
// by MinariReader; every bad input is one line naming the file. The Python side is
// tests/data/minari/minari_h5py.py.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <thread>

#include "base/errors.h"
#include "dataset/minari_reader.h"
#include "dataset/minari_replay.h"
#include "dataset/minari_trajectory.h"
#include "dataset/minari_writer.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/episode.h"
#include "src/fetch_env.h"
#include "src/policy.h"
#include "src/trajectory.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::PythonWithH5py;
using testing::ReadFile;
using testing::ReplaceMinariActions;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::SourceDir;
using testing::SpawnFetchscope;
using testing::TempDir;
using testing::WaitExit;
using testing::WriteEdited;

std::string Script() { return (SourceDir() / "tests/data/minari/minari_h5py.py").string(); }

void WriteText(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// a synthetic episode of `steps` steps with values that use every bit of a double
MinariEpisode MakeEpisode(int steps, int obs_dim, std::optional<uint64_t> seed, double base) {
  MinariEpisode e;
  e.seed = seed;
  e.obs_dim = obs_dim;
  const auto value = [&](int i) { return std::sin(base + 0.37 * i) * 1.2345678901234567; };
  for (int i = 0; i < (steps + 1) * obs_dim; ++i) e.observation.push_back(value(i));
  for (int i = 0; i < (steps + 1) * 3; ++i) e.achieved_goal.push_back(value(1000 + i));
  for (int i = 0; i < (steps + 1) * 3; ++i) e.desired_goal.push_back(value(2000 + i % 3));
  for (int i = 0; i < steps * 4; ++i) e.actions.push_back(static_cast<float>(value(3000 + i)));
  for (int i = 0; i < steps; ++i) e.rewards.push_back(i % 3 ? -1.0 : -0.0);
  e.terminations.assign(steps, 0);
  e.truncations.assign(steps, 0);
  e.truncations.back() = 1;
  for (int i = 0; i <= steps; ++i) e.is_success.push_back(i % 3 ? 0.0f : 1.0f);
  return e;
}

std::vector<MinariEpisode> SomeEpisodes(int obs_dim) {
  return {MakeEpisode(50, obs_dim, 0, 0.1), MakeEpisode(7, obs_dim, uint64_t{1} << 63, 0.2),
          MakeEpisode(50, obs_dim, std::nullopt, 0.3)};
}

MinariWriteOptions Options(const fs::path& root, const std::string& id, const EnvSpec& spec) {
  MinariWriteOptions o;
  o.dataset_id = id;
  o.root = root;
  o.spec = &spec;
  o.algorithm_name = "scripted";
  o.code_permalink = "fetchscope test";
  o.description = "minari_test";
  return o;
}

fs::path Write(const MinariWriteOptions& options, const std::vector<MinariEpisode>& episodes) {
  MinariWriter writer(options);
  for (const MinariEpisode& e : episodes) writer.Add(e);
  return writer.Commit();
}

// the episodes as minari_h5py.py's `check` expects them
json Expected(const std::string& env_id, const std::vector<MinariEpisode>& episodes) {
  json j = {{"env_id", env_id}, {"algorithm_name", "scripted"}, {"episodes", json::array()}};
  for (const MinariEpisode& e : episodes) {
    const auto rows = [](const std::vector<double>& v, int cols) {
      json out = json::array();
      for (size_t r = 0; r < v.size() / cols; ++r) {
        out.push_back(std::vector<double>(v.begin() + r * cols, v.begin() + (r + 1) * cols));
      }
      return out;
    };
    std::vector<double> actions(e.actions.begin(), e.actions.end());
    std::vector<bool> truncations(e.truncations.begin(), e.truncations.end());
    j["episodes"].push_back({{"seed", e.seed ? json(*e.seed) : json()},
                             {"observation", rows(e.observation, e.obs_dim)},
                             {"achieved_goal", rows(e.achieved_goal, 3)},
                             {"desired_goal", rows(e.desired_goal, 3)},
                             {"actions", rows(actions, 4)},
                             {"rewards", e.rewards},
                             {"truncations", truncations},
                             {"is_success", e.is_success}});
  }
  return j;
}

void ExpectSameEpisode(const MinariEpisode& a, const MinariEpisode& b) {
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.obs_dim, b.obs_dim);
  // bit for bit: memcmp-equal vectors (== on doubles would pass -0.0 for 0.0)
  const auto same = [](const auto& x, const auto& y) {
    return x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size() * sizeof(x[0])) == 0;
  };
  EXPECT_TRUE(same(a.observation, b.observation));
  EXPECT_TRUE(same(a.achieved_goal, b.achieved_goal));
  EXPECT_TRUE(same(a.desired_goal, b.desired_goal));
  EXPECT_TRUE(same(a.actions, b.actions));
  EXPECT_TRUE(same(a.rewards, b.rewards));
  EXPECT_EQ(a.terminations, b.terminations);
  EXPECT_EQ(a.truncations, b.truncations);
  EXPECT_TRUE(same(a.is_success, b.is_success));
}

TEST(MinariWriter, LayoutAndMetadataAreMinarisReadWithH5py) {
  const std::string py = PythonWithH5py();
  if (py.empty()) GTEST_SKIP() << "python3-h5py is not installed";
  for (const char* env_id : {"FetchPush-v4", "FetchReachDense-v4"}) {
    SCOPED_TRACE(env_id);
    TempDir tmp;
    const EnvSpec& spec = FindEnvSpec(env_id);
    const int width = spec.has_object ? 25 : 10;
    const std::string id = "fetchscope/Fetch/scripted-v0";
    const auto episodes = SomeEpisodes(width);
    EXPECT_EQ(Write(Options(tmp.path(), id, spec), episodes), tmp.path() / id);
    WriteText(tmp.path() / "expected.json", Expected(env_id, episodes).dump());
    const auto r = RunCommand(py + " " + Script() + " check " + tmp.path().string() + " " + id +
                              " " + (tmp.path() / "expected.json").string() + " 2>&1");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output, "ok\n");
  }
}

TEST(MinariWriter, SameEpisodesGiveTheSameBytes) {
  TempDir tmp;
  const EnvSpec& spec = FindEnvSpec("FetchPush-v4");
  const fs::path a = Write(Options(tmp.path() / "a", "xy/same-v1", spec), SomeEpisodes(25));
  const fs::path b = Write(Options(tmp.path() / "b", "xy/same-v1", spec), SomeEpisodes(25));
  for (const char* file : {"data/main_data.hdf5", "data/metadata.json"}) {
    const std::string bytes = ReadFile(a / file);
    EXPECT_GT(bytes.size(), 100u) << file;
    EXPECT_TRUE(bytes == ReadFile(b / file)) << file << " differs between two identical writes";
  }
}

TEST(MinariWriter, RefusesAnExistingIdUnlessOverwrite) {
  TempDir tmp;
  const EnvSpec& spec = FindEnvSpec("FetchSlide-v4");
  auto options = Options(tmp.path(), "ns/FetchSlide/test-v0", spec);
  Write(options, SomeEpisodes(25));
  try {
    MinariWriter again(options);
    FAIL() << "an existing id was not refused";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("already exists"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--overwrite"), std::string::npos) << e.what();
  }
  options.overwrite = true;
  Write(options, {MakeEpisode(3, 25, 9, 0.5)});
  const MinariDataset d = ReadMinariDataset("ns/FetchSlide/test-v0", tmp.path());
  ASSERT_EQ(d.episodes.size(), 1u);
  EXPECT_EQ(d.episodes[0].steps(), 3);
  // nothing but the dataset and the namespace metadata is left in the namespace folder
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(tmp.path() / "ns/FetchSlide")) {
    names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"namespace_metadata.json", "test-v0"}));
  // --overwrite replaces datasets only, never another folder
  fs::create_directories(tmp.path() / "plain-v0");
  options.dataset_id = "plain-v0";
  EXPECT_THROW(MinariWriter{options}, UsageError);
}

TEST(MinariWriter, AnUnfinishedDatasetLeavesNothing) {
  TempDir tmp;
  const EnvSpec& spec = FindEnvSpec("FetchPush-v4");
  {
    MinariWriter writer(Options(tmp.path() / "root", "deep/name/space/gone-v0", spec));
    writer.Add(MakeEpisode(5, 25, 1, 0.1));
  }  // no Commit: an error or an interrupt
  EXPECT_FALSE(fs::exists(tmp.path() / "root" / "deep"));
}

TEST(MinariWriter, RejectsIdsMinariCannotLoad) {
  TempDir tmp;
  const EnvSpec& spec = FindEnvSpec("FetchPush-v4");
  for (const char* id : {"noversion", "../up-v0", "a//b-v0", "/abs-v0", "sp ace-v0", "x-v"}) {
    SCOPED_TRACE(id);
    EXPECT_THROW(MinariWriter{Options(tmp.path(), id, spec)}, UsageError);
  }
  EXPECT_TRUE(fs::is_empty(tmp.path()));
}

TEST(MinariReader, ReadsWhatTheWriterWroteBitForBit) {
  TempDir tmp;
  const EnvSpec& spec = FindEnvSpec("FetchPickAndPlace-v4");
  const auto episodes = SomeEpisodes(25);
  const fs::path dir = Write(Options(tmp.path(), "fetchscope/rt-v2", spec), episodes);
  // by id, by dataset folder, by data folder and by file
  for (const std::string& what :
       {std::string("fetchscope/rt-v2"), dir.string(), (dir / "data").string(),
        (dir / "data/main_data.hdf5").string()}) {
    SCOPED_TRACE(what);
    const MinariDataset d = ReadMinariDataset(what, tmp.path());
    EXPECT_EQ(d.metadata.dataset_id, "fetchscope/rt-v2");
    EXPECT_EQ(d.metadata.env_id, "FetchPickAndPlace-v4");
    EXPECT_EQ(d.metadata.reward_type, "sparse");
    EXPECT_EQ(d.metadata.max_episode_steps, 50);
    EXPECT_EQ(d.metadata.algorithm_name, "scripted");
    EXPECT_EQ(d.metadata.total_steps, 107);
    ASSERT_EQ(d.episodes.size(), episodes.size());
    for (size_t i = 0; i < episodes.size(); ++i) ExpectSameEpisode(d.episodes[i], episodes[i]);
  }
  const MinariDataset some = ReadMinariDataset("fetchscope/rt-v2", tmp.path(), {2, 0});
  ASSERT_EQ(some.episodes.size(), 2u);
  EXPECT_EQ(some.episodes[0].id, 2);
  ExpectSameEpisode(some.episodes[0], episodes[2]);
  EXPECT_THROW(ReadMinariDataset("fetchscope/rt-v2", tmp.path(), {3}), UsageError);
  EXPECT_THROW(ReadMinariDataset("fetchscope/none-v0", tmp.path()), UsageError);
}

// datasets as Minari's own writers leave them, from the Python side
TEST(MinariReader, ReadsDatasetsInMinarisOwnLayout) {
  const std::string py = PythonWithH5py();
  if (py.empty()) GTEST_SKIP() << "python3-h5py is not installed";
  struct Case {
    const char* mode;
    const char* env_id;
    bool seeded;
  } cases[] = {{"buffers", "FetchPushDense-v4", true},
               {"collector", "FetchPush-v4", false},
               {"tiny", "FetchReach-v4", true}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.mode);
    TempDir tmp;
    const std::string id = std::string("minari/") + c.mode + "-v0";
    const fs::path out = tmp.path() / "values.json";
    const auto r = RunCommand(py + " " + Script() + " write " + tmp.path().string() + " " + id +
                              " " + c.env_id + " " + c.mode + " " + out.string() + " 2>&1");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const json want = json::parse(ReadFile(out));
    const MinariDataset d = ReadMinariDataset(id, tmp.path());
    EXPECT_EQ(d.metadata.env_id, c.env_id);
    EXPECT_EQ(d.metadata.minari_version, "0.5.3");
    ASSERT_EQ(d.episodes.size(), want["episodes"].size());
    for (size_t i = 0; i < d.episodes.size(); ++i) {
      const MinariEpisode& e = d.episodes[i];
      const json& w = want["episodes"][i];
      EXPECT_EQ(e.seed.has_value(), c.seeded);
      if (c.seeded) {
        EXPECT_EQ(*e.seed, w["seed"].get<uint64_t>());
      }
      std::vector<double> flat;
      for (const auto& row : w["observation"]) {
        for (double v : row) flat.push_back(v);
      }
      EXPECT_EQ(e.observation, flat);
      flat.clear();
      for (const auto& row : w["desired_goal"]) {
        for (double v : row) flat.push_back(v);
      }
      EXPECT_EQ(e.desired_goal, flat);
      std::vector<float> actions;
      for (const auto& row : w["actions"]) {
        for (double v : row) actions.push_back(static_cast<float>(v));
      }
      EXPECT_EQ(e.actions, actions);
      EXPECT_EQ(e.rewards, w["rewards"].get<std::vector<double>>());  // float32 or float64
      std::vector<uint8_t> truncations;
      for (bool b : w["truncations"]) truncations.push_back(b);
      EXPECT_EQ(e.truncations, truncations);
      EXPECT_TRUE(e.is_success.empty());  // Minari's writers store no is_success for Fetch
    }
  }
}

// Played episodes (random: float32 actions; scripted: float64, unclipped) go through the dataset
// and come back with every observation, reward and success bit, and the actions as the env
// applied them (clipped, float32).
TEST(MinariTrajectory, PlayedEpisodesComeBackBitForBit) {
  for (const char* policy_name : {"random", "scripted"}) {
    SCOPED_TRACE(policy_name);
    TempDir tmp;
    const EnvSpec& spec = FindEnvSpec("FetchPickAndPlace-v4");
    FetchEnv env(spec, ResolveAssets("bundled"));
    PolicyContext context;
    context.seed = 5;
    auto policy = MakePolicy(ParsePolicySpec(policy_name), spec, context);
    std::vector<EpisodeRecord> played;
    for (int k = 0; k < 3; ++k) {
      played.push_back(RunEpisode(
          env, *policy, k, k == 0 ? std::optional<uint64_t>(5) : std::nullopt, k == 2 ? 20 : 50));
    }
    MinariWriteOptions options = Options(tmp.path(), "played/episodes-v0", spec);
    {
      MinariWriter writer(options);
      for (const EpisodeRecord& e : played) {
        writer.Add(
            ToMinariEpisode(e, e.index == 0 ? std::optional<uint64_t>(5) : std::nullopt, 25));
      }
      writer.Commit();
    }
    const MinariDataset d = ReadMinariDataset("played/episodes-v0", tmp.path());
    ASSERT_EQ(d.episodes.size(), played.size());
    for (size_t k = 0; k < played.size(); ++k) {
      const MinariEpisode& m = d.episodes[k];
      const EpisodeRecord& e = played[k];
      ASSERT_EQ(m.steps() + 1, static_cast<int>(e.steps.size()));
      EXPECT_EQ(m.seed.has_value(), k == 0);
      EXPECT_EQ(m.truncations.back(), 1);
      for (size_t t = 0; t < e.steps.size(); ++t) {
        const StepRecord& s = e.steps[t];
        EXPECT_EQ(std::memcmp(&m.observation[t * 25], s.obs.observation.data(), 25 * 8), 0) << t;
        EXPECT_EQ(std::memcmp(&m.achieved_goal[t * 3], s.obs.achieved_goal.data(), 24), 0) << t;
        EXPECT_EQ(std::memcmp(&m.desired_goal[t * 3], s.obs.desired_goal.data(), 24), 0) << t;
        EXPECT_EQ(m.is_success[t], s.is_success ? 1.0f : 0.0f);
        if (t == 0) continue;
        EXPECT_EQ(std::memcmp(&m.rewards[t - 1], &*s.reward, 8), 0) << t;
        for (int i = 0; i < 4; ++i) {
          const double applied = std::clamp(s.action->value[i], -1.0, 1.0);
          EXPECT_EQ(m.actions[(t - 1) * 4 + i], static_cast<float>(applied));
          if (s.action->is_float32) {  // the float32 path loses nothing
            EXPECT_EQ(static_cast<double>(m.actions[(t - 1) * 4 + i]), applied);
          }
        }
      }
    }
  }
}

// Replaying a dataset: float32 episodes (random policy) replay bit for bit, the first from its
// seed and the others continuing the generator; float64 ones (scripted) were stored rounded to
// float32 and drift after the reset; an edited observation is found at its row and index.
TEST(MinariReplay, FindsTheFirstDivergence) {
  const EnvSpec& spec = FindEnvSpec("FetchPush-v4");
  for (const char* policy_name : {"random", "scripted"}) {
    SCOPED_TRACE(policy_name);
    FetchEnv env(spec, ResolveAssets("bundled"));
    PolicyContext context;
    context.seed = 8;
    auto policy = MakePolicy(ParsePolicySpec(policy_name), spec, context);
    std::vector<MinariEpisode> episodes;
    for (int k = 0; k < 3; ++k) {
      const std::optional<uint64_t> seed = k == 0 ? std::optional<uint64_t>(8) : std::nullopt;
      episodes.push_back(ToMinariEpisode(RunEpisode(env, *policy, k, seed, 30), seed, 25));
    }
    FetchEnv replay(spec, ResolveAssets("bundled"));
    for (size_t k = 0; k < episodes.size(); ++k) {
      const MinariDivergence d = ReplayMinariEpisode(replay, episodes[k], 0.0);
      EXPECT_EQ(d.reset, k == 0 ? "seed" : "continued");
      if (std::string(policy_name) == "random") {
        EXPECT_EQ(d.first_step, -1) << k << " " << d.where << " " << d.difference;
        EXPECT_EQ(d.max_difference, 0.0);
      } else {
        EXPECT_GE(d.first_step, 1) << k;  // the reset itself is exact
      }
    }
  }
  FetchEnv env(spec, ResolveAssets("bundled"));
  PolicyContext context;
  auto policy = MakePolicy(PolicySpec::Random(), spec, context);
  MinariEpisode e = ToMinariEpisode(RunEpisode(env, *policy, 0, 3, 20), 3, 25);
  e.observation[7 * 25 + 3] += 1e-3;
  const MinariDivergence d = ReplayMinariEpisode(env, e, 1e-6);
  EXPECT_EQ(d.first_step, 7);
  EXPECT_EQ(d.where, "observation[3]");
  EXPECT_NEAR(d.difference, -1e-3, 1e-12);
}

// Every bad input: one line, starting with the file it is about, saying what is wrong, and
// nothing printed by libhdf5 itself.
class MinariBadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ =
        Write(Options(tmp_.path(), "bad/input-v0", FindEnvSpec("FetchPush-v4")), SomeEpisodes(25));
    metadata_ = ReadFile(dir_ / "data/metadata.json");
  }
  fs::path Hdf5() const { return dir_ / "data/main_data.hdf5"; }
  fs::path Metadata() const { return dir_ / "data/metadata.json"; }
  void EditMetadata(const std::string& from, const std::string& to) {
    WriteEdited(Metadata(), metadata_, from, to);
  }
  void ReplaceActions(size_t rows) { ReplaceMinariActions(Hdf5(), "episode_1", rows); }
  void ExpectOneLine(const fs::path& file, const std::string& what) {
    ::testing::internal::CaptureStderr();
    std::string message;
    try {
      ReadMinariDataset(dir_.string(), tmp_.path());
    } catch (const RunError& e) {
      message = e.what();
    }
    const std::string printed = ::testing::internal::GetCapturedStderr();
    EXPECT_EQ(message.rfind(file.string() + ": ", 0), 0u) << message;
    EXPECT_NE(message.find(what), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_EQ(printed, "") << "libhdf5 printed on its own";
  }

  TempDir tmp_;
  fs::path dir_;
  std::string metadata_;
};

TEST_F(MinariBadInput, MissingMetadataKey) {
  EditMetadata("\"minari_version\": \"0.5.0\", ", "");
  ExpectOneLine(Metadata(), "missing key 'minari_version'");
}

TEST_F(MinariBadInput, MissingEpisodeKey) {
  ReplaceActions(0);
  ExpectOneLine(Hdf5(), "episode_1: missing key 'actions'");
}

TEST_F(MinariBadInput, EpisodeOfTheWrongLength) {
  ReplaceActions(6);
  ExpectOneLine(Hdf5(),
                "episode_1: episodes of the wrong length: 'actions' has 6 rows, "
                "expected 7");
}

TEST_F(MinariBadInput, NotAFetchSpace) {
  const std::string box =
      "{\\\"type\\\": \\\"Box\\\", \\\"dtype\\\": \\\"float64\\\", \\\"shape\\\": [17], "
      "\\\"low\\\": [-Infinity], \\\"high\\\": [Infinity]}";
  const size_t begin = metadata_.find("\"observation_space\": \"") + 22;
  const size_t end = metadata_.find("\", \"action_space\"");
  EditMetadata(metadata_.substr(begin, end - begin), box);
  ExpectOneLine(Metadata(), "observation_space is not a Fetch space");
}

TEST_F(MinariBadInput, NotAFetchEnvId) {
  EditMetadata("{\\\"id\\\": \\\"FetchPush-v4\\\"", "{\\\"id\\\": \\\"HalfCheetah-v5\\\"");
  ExpectOneLine(Metadata(), "env_spec id 'HalfCheetah-v5' is not a Fetch environment");
}

TEST_F(MinariBadInput, UnsupportedMinariVersion) {
  for (const char* version : {"0.3.1", "~=0.4", "0.6.0"}) {
    EditMetadata("\"minari_version\": \"0.5.0\"",
                 std::string("\"minari_version\": \"") + version + "\"");
    ExpectOneLine(Metadata(), std::string("unsupported minari_version '") + version + "'");
  }
}

TEST_F(MinariBadInput, TruncatedHdf5File) {
  fs::resize_file(Hdf5(), fs::file_size(Hdf5()) / 2);
  ExpectOneLine(Hdf5(), "truncated HDF5 file");
}

TEST_F(MinariBadInput, NotAnHdf5FileAtAll) {
  WriteText(Hdf5(), "{\"this is\": \"json\"}\n");
  ExpectOneLine(Hdf5(), "not a readable HDF5 file");
}

TEST_F(MinariBadInput, StepsThatDoNotAddUp) {
  EditMetadata("\"total_steps\": 107", "\"total_steps\": 100");
  ExpectOneLine(Metadata(), "total_steps is 100 but the episodes hold 107 steps");
}

// The commands: rollout --minari writes the episodes of its trajectory JSON, bit for bit (actions
// as applied: clipped, float32); --jobs 2 writes the same bytes; export of the trajectory JSON
// or of a run folder of episode files writes the same HDF5 bytes; an existing id is refused.
TEST(MinariCommands, RolloutAndExportRoundTrip) {
  TempDir tmp;
  const fs::path root = tmp.path() / "datasets";
  const std::string run =
      "rollout --env-id FetchPush-v4 --policy random --episodes 3 --steps 12 "
      "--seed 4 --minari-root " +
      root.string() + " ";
  auto r = RunFetchscope(run + "--minari rt/one-v0 --json-out " + (tmp.path() / "t.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("wrote Minari dataset rt/one-v0 at " + (root / "rt/one-v0").string()),
            std::string::npos)
      << r.output;
  const Trajectory t = ReadTrajectory((tmp.path() / "t.json").string());
  const MinariDataset d = ReadMinariDataset("rt/one-v0", root);
  EXPECT_EQ(d.metadata.env_id, "FetchPush-v4");
  EXPECT_EQ(d.metadata.algorithm_name, "random");
  ASSERT_EQ(d.episodes.size(), t.episodes.size());
  for (size_t k = 0; k < t.episodes.size(); ++k) {
    SCOPED_TRACE(k);
    ExpectSameEpisode(
        d.episodes[k],
        ToMinariEpisode(t.episodes[k], k == 0 ? std::optional<uint64_t>(4) : std::nullopt, 25));
  }
  // --jobs 2, worker processes: the same bytes
  r = RunFetchscope(run + "--jobs 2 --minari rt/two-v0");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(ReadFile(root / "rt/one-v0/data/main_data.hdf5") ==
              ReadFile(root / "rt/two-v0/data/main_data.hdf5"));
  std::string metadata = ReadFile(root / "rt/two-v0/data/metadata.json");  // but for the id
  metadata.replace(metadata.find("rt/two-v0"), 9, "rt/one-v0");
  EXPECT_EQ(ReadFile(root / "rt/one-v0/data/metadata.json"), metadata);
  // an existing id: refused before the run, replaced with --overwrite
  r = RunFetchscope(run + "--minari rt/one-v0");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("already exists"), std::string::npos) << r.output;
  r = RunFetchscope(run + "--minari rt/one-v0 --overwrite");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // export: the trajectory JSON, and a run folder of one file per episode
  r = RunFetchscope("export " + (tmp.path() / "t.json").string() +
                    " --minari rt/export-v0 --minari-root " + root.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fs::path folder = tmp.path() / "run";
  fs::create_directories(folder);
  for (const TrajectoryEpisode& e : t.episodes) {
    Trajectory one = t;
    one.episodes = {e};
    char name[32];
    std::snprintf(name, sizeof name, "episode_%03d.json", e.index);
    WriteText(folder / name, TrajectoryText(one));
  }
  r = RunCommand("MINARI_DATASETS_PATH=" + root.string() + " " FETCHSCOPE_BIN " export " +
                 folder.string() + " --minari rt/folder-v0 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string hdf5 = ReadFile(root / "rt/one-v0/data/main_data.hdf5");
  EXPECT_TRUE(hdf5 == ReadFile(root / "rt/export-v0/data/main_data.hdf5"));
  EXPECT_TRUE(hdf5 == ReadFile(root / "rt/folder-v0/data/main_data.hdf5"));
  r = RunFetchscope("export " + (tmp.path() / "nothing").string() + " --minari rt/x-v0");
  EXPECT_EQ(r.exit_code, 2) << r.output;
}

// record --minari: the run folder's episodes as a dataset, the bytes export makes of the same
// folder, and replaying it on the env: bit for bit (random policy: float32 actions). A shard
// writes its part, recording the shard.
TEST(MinariCommands, RecordMinariReplaysBitForBit) {
  unsetenv("DISPLAY");
  TempDir tmp;
  const fs::path root = tmp.path() / "datasets", out = tmp.path() / "run";
  const std::string record =
      "record --quiet --env-id FetchReach-v4 --width 32 --height 32 "
      "--steps 6 --episodes 2 --seed 3 --policy random --minari-root " +
      root.string() + " --out " + out.string() + " ";
  auto r = RunFetchscope(record + "--minari rec/run-v0");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("wrote Minari dataset rec/run-v0"), std::string::npos) << r.output;
  r = RunFetchscope("export " + out.string() + " --minari rec/export-v0 --minari-root " +
                    root.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(ReadFile(root / "rec/run-v0/data/main_data.hdf5") ==
              ReadFile(root / "rec/export-v0/data/main_data.hdf5"));
  const MinariDataset d = ReadMinariDataset("rec/run-v0", root);
  ASSERT_EQ(d.episodes.size(), 2u);
  EXPECT_EQ(d.episodes[0].seed, std::optional<uint64_t>(3));
  EXPECT_FALSE(d.episodes[1].seed.has_value());
  FetchEnv env(FindEnvSpec("FetchReach-v4"), ResolveAssets("bundled"));
  for (const MinariEpisode& e : d.episodes) {
    const MinariDivergence divergence = ReplayMinariEpisode(env, e, 0.0);
    EXPECT_EQ(divergence.first_step, -1) << divergence.where;
    EXPECT_EQ(divergence.max_difference, 0.0);
  }
  // a shard writes its own dataset, which records the shard (merge-datasets joins them)
  std::string shard_run = record;
  shard_run.replace(shard_run.find(out.string()), out.string().size(),
                    (tmp.path() / "shard").string());
  r = RunFetchscope(shard_run + "--shard 0/2 --minari rec/shard-v0");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json shard =
      json::parse(ReadFile(root / "rec/shard-v0/data/metadata.json")).at("selection");
  EXPECT_EQ(shard.at("shard"), json::array({0, 2}));
  EXPECT_EQ(shard.at("episodes"), json::array({0}));
}

// --- Writing datasets as Minari's own tools would, and leaving nothing behind

// The names in `folder` that start with '.': temporary folders of unfinished writes.
std::vector<std::string> HiddenEntries(const fs::path& folder) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name[0] == '.') names.push_back(name);
  }
  return names;
}

json DatasetMetadata(const fs::path& dataset) {
  return json::parse(ReadFile(dataset / "data/metadata.json"));
}

// The metadata keys and values that Minari 0.5.3's create_dataset_from_buffers writes:
// author_email where given, requirements, env_spec's max_episode_steps the TimeLimit the
// episodes ran under; sparse rewards float32 and dense float64 (checked with h5py).
TEST(MinariWriter, AuthorRequirementsTimeLimitAndRewardDtypes) {
  const std::string py = PythonWithH5py();
  if (py.empty()) GTEST_SKIP() << "python3-h5py is not installed";
  for (const char* env_id : {"FetchPush-v4", "FetchPushDense-v4"}) {
    SCOPED_TRACE(env_id);
    TempDir tmp;
    const EnvSpec& spec = FindEnvSpec(env_id);
    auto options = Options(tmp.path(), "meta/push-v0", spec);
    options.author = "Jane Doe";
    options.author_email = "jane@example.org";
    options.max_episode_steps = 80;
    const auto episodes = SomeEpisodes(25);
    Write(options, episodes);
    json expected = Expected(env_id, episodes);
    expected["author"] = "Jane Doe";
    expected["author_email"] = "jane@example.org";
    expected["max_episode_steps"] = 80;
    WriteText(tmp.path() / "expected.json", expected.dump());
    const auto r = RunCommand(py + " " + Script() + " check " + tmp.path().string() +
                              " meta/push-v0 " + (tmp.path() / "expected.json").string() + " 2>&1");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output, "ok\n");
    const auto dtype = RunCommand(py + " -c 'import h5py; print(h5py.File(\"" +
                                  (tmp.path() / "meta/push-v0/data/main_data.hdf5").string() +
                                  "\")[\"episode_0/rewards\"].dtype)'");
    EXPECT_EQ(dtype.output, spec.dense ? "float64\n" : "float32\n");
    // read back: the same rewards either way
    const MinariDataset d = ReadMinariDataset("meta/push-v0", tmp.path());
    ASSERT_EQ(d.episodes.size(), episodes.size());
    for (size_t k = 0; k < episodes.size(); ++k) ExpectSameEpisode(d.episodes[k], episodes[k]);
  }
}

// rollout --steps 80: env_spec says max_episode_steps 80 (gym.make(id, max_episode_steps=80));
// the code_permalink of rollout and record has one shape, without the binary's path or --jobs.
TEST(MinariCommands, TimeLimitAuthorAndPermalinkOfRolloutAndRecord) {
  unsetenv("DISPLAY");
  TempDir tmp;
  const fs::path root = tmp.path() / "datasets";
  auto r = RunFetchscope(
      "rollout --env-id FetchReach-v4 --episodes 2 --steps 80 --seed 5 --jobs 2 --minari-root " +
      root.string() +
      " --minari perm/rollout-v0 --minari-author 'Jane Doe' --minari-author-email j@x.org");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  json m = DatasetMetadata(root / "perm/rollout-v0");
  EXPECT_NE(m["env_spec"].get<std::string>().find("\"max_episode_steps\": 80,"), std::string::npos)
      << m["env_spec"];
  EXPECT_EQ(m["author"], json::array({"Jane Doe"}));
  EXPECT_EQ(m["author_email"], json::array({"j@x.org"}));
  EXPECT_EQ(m["code_permalink"], "fetchscope " FETCHSCOPE_VERSION
                                 " rollout --env-id FetchReach-v4 --policy random --seed 5 "
                                 "--episodes 2 --steps 80");
  r = RunFetchscope(
      "record --quiet --env-id FetchReach-v4 --width 32 --height 32 --steps 7 "
      "--episodes 2 --seed 5 --minari-root " +
      root.string() + " --out " + (tmp.path() / "run").string() + " --minari perm/record-v0");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  m = DatasetMetadata(root / "perm/record-v0");
  EXPECT_NE(m["env_spec"].get<std::string>().find("\"max_episode_steps\": 7,"), std::string::npos)
      << m["env_spec"];
  EXPECT_EQ(m["author"], json::array({"fetchscope"}));
  EXPECT_FALSE(m.contains("author_email"));
  EXPECT_EQ(m["code_permalink"], "fetchscope " FETCHSCOPE_VERSION
                                 " record --env-id FetchReach-v4 --policy random --seed 5 "
                                 "--episodes 2 --steps 7");
  // export of that run folder: the TimeLimit of its episodes
  r = RunFetchscope("export " + (tmp.path() / "run").string() +
                    " --minari perm/export-v0 --minari-root " + root.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(DatasetMetadata(root / "perm/export-v0")["env_spec"],
            DatasetMetadata(root / "perm/record-v0")["env_spec"]);
}

// MINARI_DATASETS_PATH= (set, empty) is an error, as in Minari, not a fallback to ~/.minari.
// MINARI_DATASETS_PATH set but empty counts as unset (the rule for every variable fetchscope
// reads, FETCHSCOPE_ASSETS too): the default root under HOME is used. Set to a file, it is
// refused naming the variable.
TEST(MinariCommands, AnEmptyDatasetsPathIsUnsetAndAFileIsRefusedNamingTheVariable) {
  TempDir tmp;
  auto r = RunCommand("HOME=" + tmp.path().string() +
                      " MINARI_DATASETS_PATH= " FETCHSCOPE_BIN
                      " rollout --env-id FetchReach-v4 --steps 3 --minari up/empty-v0 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(tmp.path() / ".minari" / "datasets" / "up" / "empty-v0" / "data" /
                         "main_data.hdf5"))
      << r.output;
  WriteText(tmp.path() / "file", "not a folder");
  r = RunCommand("MINARI_DATASETS_PATH=" + (tmp.path() / "file").string() +
                 " " FETCHSCOPE_BIN " datasets 2>&1");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("MINARI_DATASETS_PATH '" + (tmp.path() / "file").string() +
                          "' is a file, not a folder"),
            std::string::npos)
      << r.output;
}

// One rule for ids, read or written: an id names a folder under the datasets root, so
// "../outside/x-v0" is refused by record --from (as by rollout --minari), and the same dataset
// is read when given by its path.
TEST(MinariCommands, AnIdNeverLeavesTheDatasetsRootAndAPathIsGivenAsAPath) {
  TempDir tmp;
  const fs::path root = tmp.path() / "root", outside = tmp.path() / "outside";
  fs::create_directories(root);
  auto r = RunFetchscope("rollout --env-id FetchReach-v4 --steps 3 --minari x-v0 --minari-root " +
                         outside.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_TRUE(fs::is_directory(outside / "x-v0" / "data"));
  // from a folder where ../outside/x-v0 is no path: only the root could make it one
  const fs::path cwd = tmp.path() / "work" / "here";
  fs::create_directories(cwd);
  const std::string from_id = "cd " + cwd.string() + " && " FETCHSCOPE_BIN " ";
  r = RunCommand(from_id + "record --from ../outside/x-v0 --minari-root " + root.string() +
                 " --out " + (tmp.path() / "run").string() + " 2>&1");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(testing::LineCount(r.output), 1) << r.output;
  EXPECT_NE(r.output.find("no Minari dataset '../outside/x-v0': not a file or folder, and not a "
                          "dataset id"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(tmp.path() / "run"));
  r = RunCommand(from_id +
                 "rollout --env-id FetchReach-v4 --steps 3 --minari ../outside/y-v0 "
                 "--minari-root " +
                 root.string() + " 2>&1");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("is not a Minari dataset id"), std::string::npos) << r.output;
  // the same dataset by its path
  r = RunFetchscope("record --from " + (outside / "x-v0").string() + " --minari-root " +
                    root.string() + " --width 32 --height 32 --quiet --out " +
                    (tmp.path() / "run").string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

// datasets: a folder with data/ but no metadata.json is listed as unreadable, not left out; a
// root that cannot be listed is an error, not "no datasets"
TEST(MinariCommands, DatasetsListsABrokenDatasetAndRefusesAnUnlistableRoot) {
  TempDir tmp;
  const fs::path root = tmp.path() / "root";
  fs::create_directories(root / "ns" / "broken-v0" / "data");
  auto r = RunFetchscope("datasets --minari-root " + root.string() + " 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("ns/broken-v0"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("unreadable"), std::string::npos) << r.output;
  if (getuid() == 0) GTEST_SKIP() << "root can list a folder without permissions";
  fs::permissions(root, fs::perms::none);
  r = RunFetchscope("datasets --minari-root " + root.string() + " 2>&1");
  fs::permissions(root, fs::perms::owner_all);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("cannot list the datasets root"), std::string::npos) << r.output;
}

// export of a run cut off by an interrupt: the partial episode is refused, named; with
// --include-incomplete it is exported, its last step truncated, and that is said.
TEST(MinariCommands, ExportRefusesAnIncompleteEpisodeUnlessAsked) {
  TempDir tmp;
  const fs::path root = tmp.path() / "datasets", file = tmp.path() / "t.json";
  auto r = RunFetchscope(
      "rollout --env-id FetchPush-v4 --episodes 3 --steps 10 --seed 2 "
      "--json-out " +
      file.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  Trajectory t = ReadTrajectory(file.string());
  t.episodes[2].steps.resize(4);  // cut off after 3 steps
  t.episodes[2].complete = false;
  WriteText(file, TrajectoryText(t));
  const std::string run =
      "export " + file.string() + " --minari-root " + root.string() + " --minari cut/run-v0";
  r = RunFetchscope(run);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("episode 2 (3 steps) is incomplete"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--include-incomplete"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(root / "cut"));
  r = RunFetchscope(run + " --include-incomplete");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("not by the TimeLimit"), std::string::npos) << r.output;
  const MinariDataset d = ReadMinariDataset("cut/run-v0", root);
  ASSERT_EQ(d.episodes.size(), 3u);
  EXPECT_EQ(d.episodes[2].steps(), 3);
  EXPECT_EQ(d.episodes[2].truncations.back(), 1);
  // the TimeLimit is that of the complete episodes
  EXPECT_NE(DatasetMetadata(root / "cut/run-v0")["env_spec"].get<std::string>().find(
                "\"max_episode_steps\": 10,"),
            std::string::npos);
}

// export interrupted at random points (SIGINT, SIGTERM): it exits 128 + the signal and leaves
// nothing: no temporary folder, the old dataset byte for byte; or it finished, and the dataset
// is the new one whole.
TEST(MinariCommands, ExportInterruptedAtRandomPointsLeavesNothing) {
  TempDir tmp;
  const fs::path root = tmp.path() / "datasets", oldf = tmp.path() / "old.json",
                 newf = tmp.path() / "new.json";
  const std::string rollout = "rollout --env-id FetchPush-v4 --episodes 150 --steps 50 --jobs 2 ";
  ASSERT_EQ(RunFetchscope(rollout + "--seed 1 --json-out " + oldf.string()).exit_code, 0);
  ASSERT_EQ(RunFetchscope(rollout + "--seed 2 --json-out " + newf.string()).exit_code, 0);
  const std::string export_to = " --minari-root " + root.string() + " --minari int/push-v0 ";
  ASSERT_EQ(RunFetchscope("export " + oldf.string() + export_to).exit_code, 0);
  const fs::path hdf5 = root / "int/push-v0/data/main_data.hdf5";
  const std::string old_bytes = ReadFile(hdf5);
  const std::string old_meta = ReadFile(root / "int/push-v0/data/metadata.json");
  // how long a whole export takes, to spread the interrupts over it
  const auto start = std::chrono::steady_clock::now();
  ASSERT_EQ(RunFetchscope("export " + newf.string() + export_to + "--overwrite").exit_code, 0);
  const double whole_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  const std::string new_bytes = ReadFile(hdf5);
  ASSERT_NE(old_bytes, new_bytes);
  ASSERT_EQ(RunFetchscope("export " + oldf.string() + export_to + "--overwrite").exit_code, 0);
  std::mt19937 rng(26);
  int interrupted = 0;
  for (int i = 0; i < 8; ++i) {
    const int sig = i % 2 ? SIGTERM : SIGINT;
    const int delay_ms =
        static_cast<int>(std::uniform_real_distribution<>(0.1, 0.9)(rng) * whole_ms);
    SCOPED_TRACE("signal " + std::to_string(sig) + " after " + std::to_string(delay_ms) + " ms");
    const fs::path log = tmp.path() / "export.log";
    const pid_t pid = SpawnFetchscope("export " + newf.string() + export_to + "--overwrite", log);
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
    kill(pid, sig);
    const int status = WaitExit(pid);
    EXPECT_TRUE(HiddenEntries(root / "int").empty()) << ReadFile(log);
    if (status == 0) {  // it finished first: the new dataset, whole
      EXPECT_TRUE(ReadFile(hdf5) == new_bytes);
      ASSERT_EQ(RunFetchscope("export " + oldf.string() + export_to + "--overwrite").exit_code, 0);
      continue;
    }
    ++interrupted;
    EXPECT_EQ(status, 128 + sig) << ReadFile(log);
    EXPECT_TRUE(ReadFile(hdf5) == old_bytes);
    EXPECT_EQ(ReadFile(root / "int/push-v0/data/metadata.json"), old_meta);
    const std::string said = ReadFile(log);
    // before main installed the handler the signal ends it silently, which leaves nothing too
    if (!said.empty()) {
      EXPECT_NE(said.find("interrupted (" + std::string(sig == SIGINT ? "SIGINT" : "SIGTERM")),
                std::string::npos)
          << said;
      EXPECT_NE(said.find("nothing written"), std::string::npos) << said;
    }
  }
  EXPECT_GT(interrupted, 0);
}

// A temporary folder left by a killed write (SIGKILL, power loss) is removed by the next write
// of a dataset beside it; one of a process still running, or written to lately, is not.
TEST(MinariWriter, RemovesStaleTemporaryFoldersOfOurs) {
  TempDir tmp;
  const EnvSpec& spec = FindEnvSpec("FetchPush-v4");
  const fs::path ns = tmp.path() / "st";
  const pid_t dead = fork();
  if (dead == 0) _exit(0);
  waitpid(dead, nullptr, 0);
  const auto make = [&](const std::string& name, bool old) {
    fs::create_directories(ns / name / "data");
    WriteText(ns / name / "data/main_data.hdf5", "partial");
    if (old) {
      const auto when = fs::file_time_type::clock::now() - std::chrono::hours(1);
      fs::last_write_time(ns / name / "data/main_data.hdf5", when);
      fs::last_write_time(ns / name / "data", when);
      fs::last_write_time(ns / name, when);
    }
  };
  const std::string stale = ".gone-v0.tmp-" + std::to_string(dead) + "-0";
  // a live process's (this one's, with a number its own writes do not reach here: the writer
  // names its folder .ID.tmp-PID-N with N counting this process's writes from 0)
  const std::string alive = ".gone-v0.tmp-" + std::to_string(getpid()) + "-999";
  const std::string recent = ".gone-v0.tmp-" + std::to_string(dead) + "-1";
  const std::string other = ".other-v0.tmp-" + std::to_string(dead) + "-0";
  make(stale, true);
  make(alive, true);
  make(recent, false);
  make(other, true);
  Write(Options(tmp.path(), "st/gone-v0", spec), SomeEpisodes(25));
  EXPECT_FALSE(fs::exists(ns / stale));
  EXPECT_TRUE(fs::exists(ns / alive));
  EXPECT_TRUE(fs::exists(ns / recent));
  EXPECT_TRUE(fs::exists(ns / other));  // another dataset's: its own next write cleans it
}

// record --minari checks the datasets folder before rendering anything; an existing id is
// refused before the run, and --overwrite replaces it after the run.
TEST(MinariCommands, RecordChecksTheDatasetUpFrontAndOverwriteReplacesIt) {
  unsetenv("DISPLAY");
  TempDir tmp;
  const fs::path out = tmp.path() / "run";
  WriteText(tmp.path() / "file", "not a folder");
  const std::string record =
      "record --quiet --env-id FetchReach-v4 --width 32 --height 32 --steps 4 --episodes 1 "
      "--out " +
      out.string() + " ";
  auto r = RunFetchscope(record + "--minari-root " + (tmp.path() / "file").string() +
                         " --minari up/front-v0");
  EXPECT_EQ(r.exit_code, 2) << r.output;  // a bad path on the command line: a usage error
  EXPECT_NE(r.output.find("--minari-root '" + (tmp.path() / "file").string() +
                          "' is a file, not a folder"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(out / "episode_000.mp4")) << "rendered before checking the dataset";
  const fs::path root = tmp.path() / "datasets";
  r = RunFetchscope(record + "--seed 1 --minari-root " + root.string() + " --minari up/front-v0");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string first = ReadFile(root / "up/front-v0/data/main_data.hdf5");
  r = RunFetchscope(record + "--seed 2 --overwrite --minari-root " + root.string() +
                    " --minari up/front-v0");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(ReadFile(root / "up/front-v0/data/main_data.hdf5"), first);
  r = RunFetchscope(
      "record --quiet --env-id FetchReach-v4 --width 32 --height 32 --steps 4 "
      "--episodes 1 --out " +
      (tmp.path() / "run4").string() + " --minari-root " + root.string() + " --minari up/front-v0");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("pass --overwrite to replace it"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp.path() / "run4" / "episode_000.json"));
}

// record --minari whose dataset write fails at the end (the datasets folder, fine when the run
// began, replaced by a file while it renders): the message says how to write the dataset from
// the kept run, the run folder keeps its episodes, nothing is left under the dataset's name, and
// the export it names then writes the dataset.
TEST(MinariCommands, RecordWhoseDatasetWriteFailsAtTheEndKeepsTheRunAndSaysHowToExport) {
  unsetenv("DISPLAY");
  TempDir tmp;
  const fs::path out = tmp.path() / "run", root = tmp.path() / "datasets",
                 aside = tmp.path() / "datasets.aside", resume = tmp.path() / "resume",
                 log = tmp.path() / "record.log";
  fs::create_directories(root);
  // pause at the first kill point (episode 0's video flush: after the up-front check)
  setenv("FETCHSCOPE_TEST_KILL_AT", "1", 1);
  setenv("FETCHSCOPE_TEST_KILL_HOW", "pause", 1);
  setenv("FETCHSCOPE_TEST_KILL_RESUME", resume.c_str(), 1);
  const pid_t pid = SpawnFetchscope(
      "record --quiet --env-id FetchReach-v4 --width 32 --height 32 --steps 4 --episodes 2 "
      "--out " +
          out.string() + " --minari-root " + root.string() + " --minari late/fail-v0",
      log);
  unsetenv("FETCHSCOPE_TEST_KILL_AT");
  unsetenv("FETCHSCOPE_TEST_KILL_HOW");
  unsetenv("FETCHSCOPE_TEST_KILL_RESUME");
  for (int i = 0; i < 1200 && ReadFile(log).find("paused at kill point") == std::string::npos;
       ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_NE(ReadFile(log).find("paused at kill point 1"), std::string::npos) << ReadFile(log);
  fs::rename(root, aside);
  WriteText(root, "not a folder any more");
  WriteText(resume, "");
  const int status = WaitExit(pid);
  const std::string said = ReadFile(log);
  EXPECT_EQ(status, 1) << said;
  EXPECT_NE(said.find("record --minari: "), std::string::npos) << said;
  // the command names the run and the dataset, and the datasets root it was given
  const std::string named = "`fetchscope export " + out.string() + " --minari late/fail-v0";
  const size_t at = said.find(named);
  ASSERT_NE(at, std::string::npos) << said;
  const size_t end = said.find('`', at + 1);
  ASSERT_NE(end, std::string::npos) << said;
  const std::string command = said.substr(at + 1 + 11, end - at - 1 - 11);  // after "fetchscope "
  EXPECT_EQ(command,
            "export " + out.string() + " --minari late/fail-v0 --minari-root " + root.string());
  EXPECT_EQ(said.find("wrote Minari dataset"), std::string::npos) << said;
  // the run is kept: both episodes' files and the manifest
  for (const char* file : {"episode_000.json", "episode_000.mp4", "episode_001.json",
                           "episode_001.mp4", "manifest.json"}) {
    EXPECT_TRUE(fs::is_regular_file(out / file)) << file;
  }
  // nothing under the dataset's name, in the folder the check saw or the file now in its place
  EXPECT_EQ(ReadFile(root), "not a folder any more");
  EXPECT_FALSE(fs::exists(aside / "late/fail-v0"));
  EXPECT_TRUE(HiddenEntries(aside / "late").empty());
  EXPECT_TRUE(HiddenEntries(aside).empty());
  // and the command it names writes the dataset from the kept run
  fs::remove(root);
  fs::rename(aside, root);
  const auto r = RunFetchscope(command);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::is_regular_file(root / "late/fail-v0/data/main_data.hdf5")) << r.output;
}

// rollout --minari stopped by SIGINT or SIGTERM while it adds episodes: 128 + the signal, the
// usual line, and no dataset, temporary folder or namespace folder left (any --jobs).
TEST(MinariCommands, RolloutInterruptedLeavesNoDataset) {
  TempDir tmp;
  const fs::path root = tmp.path() / "datasets";
  int i = 0;
  for (const int sig : {SIGINT, SIGTERM}) {
    SCOPED_TRACE(sig);
    const fs::path log = tmp.path() / ("rollout" + std::to_string(i) + ".log");
    const pid_t pid = SpawnFetchscope("rollout --env-id FetchPush-v4 --episodes 2000 --jobs " +
                                          std::to_string(++i) + " --minari-root " + root.string() +
                                          " --minari ri/push-v0",
                                      log);
    // once the rollout handles the signal (its episodes started; before that the default
    // action ends it, with nothing to say), and a moment into its episodes: a fixed wait alone
    // came before that under the sanitizers
    ASSERT_TRUE(testing::WaitForSignalHandler(pid, sig)) << ReadFile(log);
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    kill(pid, sig);
    EXPECT_EQ(WaitExit(pid), 128 + sig) << ReadFile(log);
    EXPECT_NE(ReadFile(log).find("nothing written"), std::string::npos) << ReadFile(log);
    EXPECT_FALSE(fs::exists(root / "ri")) << "a dataset or its folder was left";
  }
}

}  // namespace
}  // namespace fetchscope
