// --shard I/N and its environment variables, and merge-manifests: the shards of a run together
// equal the unsharded run, file for file.
#include "run/shard.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>

#include "base/errors.h"
#include "cli/shard_options.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::EpisodeFiles;
using testing::ReadFile;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::TempDir;
namespace fs = std::filesystem;
using Env = std::map<std::string, std::string>;

// The machine running the tests may itself be a Slurm task or a Kubernetes pod.
void ClearShardEnvironment() {
  for (const char* name :
       {"SLURM_ARRAY_TASK_ID", "SLURM_ARRAY_TASK_COUNT", "SLURM_ARRAY_TASK_MIN",
        "SLURM_ARRAY_TASK_STEP", "SLURM_ARRAY_TASK_MAX", "JOB_COMPLETION_INDEX", "DISPLAY"}) {
    unsetenv(name);
  }
}

struct ShardCase {
  std::string flag;  // --shard
  int shard_count;   // --shard-count (0: not given)
  Env env;           // the environment
  int index, count;  // expected shard, when `error` is empty
  std::string source;
  std::string error;  // expected in the UsageError's message
};

void PrintTo(const ShardCase& c, std::ostream* os) {
  *os << "--shard '" << c.flag << "' --shard-count " << c.shard_count;
  for (const auto& [k, v] : c.env) *os << " " << k << "=" << v;
}

class ResolveShardTest : public ::testing::TestWithParam<ShardCase> {};

TEST_P(ResolveShardTest, ResolvesOrNamesTheBadValue) {
  const ShardCase& c = GetParam();
  auto lookup = [&](const char* name) -> const char* {
    auto it = c.env.find(name);
    return it == c.env.end() ? nullptr : it->second.c_str();
  };
  if (!c.error.empty()) {
    try {
      cli::ResolveShard(c.flag, c.shard_count, lookup);
      FAIL() << "accepted";
    } catch (const UsageError& e) {
      EXPECT_NE(std::string(e.what()).find(c.error), std::string::npos) << e.what();
    }
    return;
  }
  const Shard s = cli::ResolveShard(c.flag, c.shard_count, lookup);
  EXPECT_EQ(s.index, c.index);
  EXPECT_EQ(s.count, c.count);
  EXPECT_EQ(s.source, c.source);
}

const Env kSlurm = {{"SLURM_ARRAY_TASK_ID", "5"}, {"SLURM_ARRAY_TASK_COUNT", "16"}};

INSTANTIATE_TEST_SUITE_P(
    Cases, ResolveShardTest,
    ::testing::Values(
        ShardCase{"", 0, {}, 0, 1, "", ""}, ShardCase{"0/1", 0, {}, 0, 1, "--shard", ""},
        ShardCase{"2/3", 0, {}, 2, 3, "--shard", ""},
        ShardCase{"15/16", 16, {}, 15, 16, "--shard", ""},
        ShardCase{"3/3", 0, {}, 0, 0, "", "I must be below N"},
        ShardCase{"1/0", 0, {}, 0, 0, "", "N must be at least 1"},
        ShardCase{"1", 0, {}, 0, 0, "", "'1' is not of the form I/N"},
        ShardCase{"-1/3", 0, {}, 0, 0, "", "'-1/3' is not of the form I/N"},
        ShardCase{"a/b", 0, {}, 0, 0, "", "'a/b'"}, ShardCase{"1/3/5", 0, {}, 0, 0, "", "'1/3/5'"},
        ShardCase{"1/3", 4, {}, 0, 0, "", "--shard-count 4 disagrees"},
        // the flag wins over the environment
        ShardCase{"1/2", 0, kSlurm, 1, 2, "--shard", ""},
        ShardCase{"", 0, kSlurm, 5, 16, "SLURM_ARRAY_TASK_ID", ""},
        ShardCase{"",
                  0,
                  {{"SLURM_ARRAY_TASK_ID", "3"},
                   {"SLURM_ARRAY_TASK_COUNT", "4"},
                   {"SLURM_ARRAY_TASK_MIN", "1"}},
                  2,
                  4,
                  "SLURM_ARRAY_TASK_ID",
                  ""},
        ShardCase{"",
                  0,
                  {{"SLURM_ARRAY_TASK_ID", "6"},
                   {"SLURM_ARRAY_TASK_COUNT", "4"},
                   {"SLURM_ARRAY_TASK_MIN", "0"},
                   {"SLURM_ARRAY_TASK_STEP", "2"}},
                  3,
                  4,
                  "SLURM_ARRAY_TASK_ID",
                  ""},
        ShardCase{"",
                  0,
                  {{"SLURM_ARRAY_TASK_ID", "16"}, {"SLURM_ARRAY_TASK_COUNT", "16"}},
                  0,
                  0,
                  "",
                  "SLURM_ARRAY_TASK_ID=16 does not fit"},
        ShardCase{"",
                  0,
                  {{"SLURM_ARRAY_TASK_ID", "x1"}, {"SLURM_ARRAY_TASK_COUNT", "16"}},
                  0,
                  0,
                  "",
                  "SLURM_ARRAY_TASK_ID='x1' is not a non-negative whole number"},
        ShardCase{"",
                  0,
                  {{"SLURM_ARRAY_TASK_ID", "1"}, {"SLURM_ARRAY_TASK_COUNT", ""}},
                  0,
                  0,
                  "",
                  "SLURM_ARRAY_TASK_COUNT=''"},
        ShardCase{"", 0, {{"SLURM_ARRAY_TASK_ID", "1"}}, 0, 0, "", "SLURM_ARRAY_TASK_COUNT is not"},
        ShardCase{"",
                  0,
                  {{"SLURM_ARRAY_TASK_ID", "0"}, {"SLURM_ARRAY_TASK_COUNT", "0"}},
                  0,
                  0,
                  "",
                  "SLURM_ARRAY_TASK_COUNT=0 must be at least 1"},
        ShardCase{"", 8, {{"JOB_COMPLETION_INDEX", "7"}}, 7, 8, "JOB_COMPLETION_INDEX", ""},
        // Kubernetes wins over Slurm: --shard-count says which the user meant
        ShardCase{"",
                  8,
                  {{"JOB_COMPLETION_INDEX", "7"}, {"SLURM_ARRAY_TASK_ID", "5"}},
                  7,
                  8,
                  "JOB_COMPLETION_INDEX",
                  ""},
        ShardCase{
            "", 0, {{"JOB_COMPLETION_INDEX", "3"}}, 0, 0, "", "JOB_COMPLETION_INDEX=3 is set but"},
        ShardCase{"",
                  8,
                  {{"JOB_COMPLETION_INDEX", "8"}},
                  0,
                  0,
                  "",
                  "JOB_COMPLETION_INDEX=8 must be below --shard-count 8"},
        ShardCase{"", 8, {{"JOB_COMPLETION_INDEX", " 2"}}, 0, 0, "", "JOB_COMPLETION_INDEX=' 2'"},
        ShardCase{"", 8, {}, 0, 0, "", "--shard-count 8 needs JOB_COMPLETION_INDEX"},
        ShardCase{"", -2, {}, 0, 0, "", "--shard-count -2"}));

// Slurm arrays: a range maps its tasks to shards; an array that is no range (--array=2,5,7) is
// refused in every task; with a run of N shards already in --out, an array that is not the whole
// run (resubmitted indices) records shard ID of N.
TEST(ShardTest, SlurmArraysAgainstTheRunInOut) {
  auto resolve = [](const Env& env, int run_shards) {
    return cli::ResolveShard(
        "", 0,
        [&](const char* name) -> const char* {
          auto it = env.find(name);
          return it == env.end() ? nullptr : it->second.c_str();
        },
        run_shards);
  };
  auto array = [](const char* id, const char* count, const char* min, const char* max,
                  const char* step = "1") {
    return Env{{"SLURM_ARRAY_TASK_ID", id},
               {"SLURM_ARRAY_TASK_COUNT", count},
               {"SLURM_ARRAY_TASK_MIN", min},
               {"SLURM_ARRAY_TASK_MAX", max},
               {"SLURM_ARRAY_TASK_STEP", step}};
  };
  // --array=0-6:2 is a range of 4 tasks; --array=1-4 too
  EXPECT_EQ(resolve(array("4", "4", "0", "6", "2"), 0).index, 2);
  EXPECT_EQ(resolve(array("4", "4", "1", "4"), 0).index, 3);
  // --array=2,5,7: every task refuses, the first included, naming the variables
  for (const char* id : {"2", "5", "7"}) {
    try {
      resolve(array(id, "3", "2", "7"), 0);
      ADD_FAILURE() << "task " << id << " accepted --array=2,5,7";
    } catch (const UsageError& e) {
      EXPECT_NE(std::string(e.what()).find("SLURM_ARRAY_TASK_MAX=7 with SLURM_ARRAY_TASK_MIN=2"),
                std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find("not a range"), std::string::npos) << e.what();
    }
  }
  // a run of 4 shards in --out: --array=1 records shard 1/4, --array=1,3 shards 1/4 and 3/4
  Shard s = resolve(array("1", "1", "1", "1"), 4);
  EXPECT_EQ(s.index, 1);
  EXPECT_EQ(s.count, 4);
  s = resolve(array("3", "2", "1", "3"), 4);
  EXPECT_EQ(s.index, 3);
  EXPECT_EQ(s.count, 4);
  // the whole run resubmitted maps as the first submission did (--array=1-4 again)
  s = resolve(array("4", "4", "1", "4"), 4);
  EXPECT_EQ(s.index, 3);
  EXPECT_EQ(s.count, 4);
  // an index the run does not have
  try {
    resolve(array("4", "1", "4", "4"), 4);
    ADD_FAILURE() << "accepted task 4 of a 4-shard run";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("SLURM_ARRAY_TASK_ID=4 is not a shard of the run in "
                                         "--out, which has 4 shards (0..3)"),
              std::string::npos)
        << e.what();
  }
}

// The Kubernetes manifest the cluster guide links: one pod per shard, --shard-count = completions,
// and --resume so that a retried pod keeps what a killed attempt finished.
TEST(ShardTest, KubernetesManifestPassesItsCompletionsAsShardCount) {
  const std::string job = ReadFile(testing::SourceDir() / "examples/k8s/record-job.yaml");
  std::smatch completions, count;
  ASSERT_TRUE(std::regex_search(job, completions, std::regex("\\n  completions: (\\d+)"))) << job;
  ASSERT_TRUE(std::regex_search(job, count, std::regex("\"--shard-count\", \"(\\d+)\""))) << job;
  EXPECT_EQ(completions[1], count[1]);
  EXPECT_NE(job.find("completionMode: Indexed"), std::string::npos);
  EXPECT_NE(job.find("\"--resume\""), std::string::npos);
}

TEST(ShardTest, EpisodesAndManifestNames) {
  EXPECT_EQ(ShardEpisodes({1, 3, ""}, 8), (std::vector<int>{1, 4, 7}));
  EXPECT_EQ(ShardEpisodes({0, 1, ""}, 3), (std::vector<int>{0, 1, 2}));
  EXPECT_TRUE(ShardEpisodes({5, 6, ""}, 5).empty());
  // a replayed trajectory's own indices, not 0 .. N-1
  EXPECT_EQ(ShardEpisodes({1, 2, ""}, std::vector<int>{0, 3, 5, 8}), (std::vector<int>{3, 5}));
  EXPECT_TRUE(ShardEpisodes({1, 3, ""}, std::vector<int>{0, 3, 6}).empty());
  EXPECT_EQ(ShardManifestName({0, 1, ""}), "manifest.json");
  EXPECT_EQ(ShardManifestName({2, 16, ""}), "manifest_shard_0002_of_0016.json");
}

// -- black box: the real binary ------------------------------------------------------------

// A small record run; the random policy's generator runs across episodes, and Push draws for
// the object and the goal at every reset, so a shard must replay both for the episodes it skips.
std::string Record(int episodes = 7, int seed = 11) {
  return "record --quiet --env-id FetchPush-v4 --policy random --steps 4 --width 64 --height 48 "
         "--backend osmesa --episodes " +
         std::to_string(episodes) + " --seed " + std::to_string(seed);
}
const std::string kRun = Record();

class ShardRunTest : public ::testing::Test {
 protected:
  void SetUp() override { ClearShardEnvironment(); }
};

TEST_F(ShardRunTest, ShardsTogetherEqualTheUnshardedRunAndMerge) {
  TempDir tmp;
  const fs::path whole = tmp.path() / "whole", shared = tmp.path() / "shards";
  auto r = RunFetchscope(kRun + " --out " + whole.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (int i = 0; i < 3; ++i) {
    r = RunFetchscope(kRun + " --shard " + std::to_string(i) + "/3 --out " + shared.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  // the same files, byte for byte: trajectories, sheets and videos
  const auto expected = EpisodeFiles(whole), actual = EpisodeFiles(shared);
  ASSERT_EQ(expected.size(), 21u);
  ASSERT_EQ(actual.size(), expected.size());
  for (const auto& [name, bytes] : expected) {
    ASSERT_TRUE(actual.count(name)) << name;
    EXPECT_TRUE(actual.at(name) == bytes) << name << " differs";
  }
  auto shard1 = nlohmann::json::parse(ReadFile(shared / "manifest_shard_0001_of_0003.json"));
  EXPECT_EQ(shard1["shard"]["index"], 1);
  EXPECT_EQ(shard1["shard"]["count"], 3);
  EXPECT_EQ(shard1["shard"]["episodes"], nlohmann::json({1, 4}));
  EXPECT_EQ(shard1["episodes"].size(), 2u);
  EXPECT_FALSE(fs::exists(shared / "manifest.json"));

  r = RunFetchscope("merge-manifests " + shared.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto merged = nlohmann::json::parse(ReadFile(shared / "manifest.json"));
  auto single = nlohmann::json::parse(ReadFile(whole / "manifest.json"));
  EXPECT_EQ(merged["episodes"], single["episodes"]);  // all seven, in order, same returns
  EXPECT_EQ(merged["shards"].size(), 3u);
  EXPECT_EQ(merged["merged"], true);
  EXPECT_EQ(merged["interrupted"], false);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(merged["shards"][i]["index"], i);
    EXPECT_TRUE(merged["shards"][i]["timings_s"].contains("wall"));
  }
  // merging again reads the shard manifests, not the merged one
  EXPECT_EQ(RunFetchscope("merge-manifests --quiet " + shared.string()).exit_code, 0);
}

// The Slurm environment through the real binary: an irregular array refuses in its first task
// too, before anything is written; one index resubmitted into a folder holding shards of a 4-shard
// run records that run's shard (and a different run there is still refused).
TEST_F(ShardRunTest, SlurmResubmissionAndIrregularArrays) {
  TempDir tmp;
  const fs::path out = tmp.path() / "run";
  auto slurm = [](const char* id, const char* count, const char* min, const char* max) {
    return std::string("env SLURM_ARRAY_TASK_ID=") + id + " SLURM_ARRAY_TASK_COUNT=" + count +
           " SLURM_ARRAY_TASK_MIN=" + min + " SLURM_ARRAY_TASK_MAX=" + max +
           " SLURM_ARRAY_TASK_STEP=1 " + FETCHSCOPE_BIN + " ";
  };
  // --array=2,5,7: task 2 (the first) refuses like the others, naming the variables
  auto r = RunCommand(slurm("2", "3", "2", "7") + kRun + " --out " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("the array is not a range"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
  // shards 0, 2, 3 of 4 recorded; shard 1 resubmitted alone (--array=1)
  for (int i : {0, 2, 3}) {
    ASSERT_EQ(RunFetchscope(kRun + " --shard " + std::to_string(i) + "/4 --out " + out.string())
                  .exit_code,
              0);
  }
  // another run (seed 12) resubmitted there: refused, naming the difference
  r = RunCommand(slurm("1", "1", "1", "1") + Record(7, 12) + " --resume --out " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--seed is 11 there and 12 here"), std::string::npos) << r.output;
  r = RunCommand(slurm("1", "1", "1", "1") + kRun + " --resume --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(out / "manifest_shard_0001_of_0004.json")) << r.output;
  EXPECT_EQ(RunFetchscope("merge-manifests --quiet " + out.string()).exit_code, 0);
}

TEST_F(ShardRunTest, MergeAcrossFoldersWritesRelativePaths) {
  TempDir tmp;
  for (int i = 0; i < 2; ++i) {
    auto r = RunFetchscope(Record(3) + " --shard " + std::to_string(i) + "/2 --out " +
                           (tmp.path() / ("m" + std::to_string(i))).string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  const fs::path out = tmp.path() / "merged.json";
  auto r = RunFetchscope("merge-manifests " + (tmp.path() / "m0").string() + " " +
                         (tmp.path() / "m1").string() + " --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto merged = nlohmann::json::parse(ReadFile(out));
  ASSERT_EQ(merged["episodes"].size(), 3u);
  EXPECT_EQ(merged["episodes"][0]["video"], "m0/episode_000.mp4");
  EXPECT_EQ(merged["episodes"][1]["trajectory"], "m1/episode_001.json");
  EXPECT_EQ(merged["episodes"][2]["sheet"], "m0/episode_002_sheet.png");
}

TEST_F(ShardRunTest, MergeNamesMissingInterruptedAndForeignShards) {
  TempDir tmp;
  const fs::path dir = tmp.path() / "run";
  for (int i : {0, 1}) {
    auto r = RunFetchscope(kRun + " --shard " + std::to_string(i) + "/3 --out " + dir.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  auto r = RunFetchscope("merge-manifests " + dir.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("shard 2/3 has no manifest (episodes 2, 5)"), std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(dir / "manifest.json"));

  // shard 2 ran but was cut short: its manifest says so and lacks episode 5
  ASSERT_EQ(RunFetchscope(kRun + " --shard 2/3 --out " + dir.string()).exit_code, 0);
  const fs::path m2 = dir / "manifest_shard_0002_of_0003.json";
  auto manifest = nlohmann::json::parse(ReadFile(m2));
  manifest["interrupted"] = true;
  manifest["signal"] = "SIGTERM";
  manifest["episodes"].erase(1);
  std::ofstream(m2) << manifest.dump(2);
  r = RunFetchscope("merge-manifests " + dir.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("shard 2/3 was interrupted by SIGTERM (episodes 5 missing"),
            std::string::npos)
      << r.output;

  // a deleted video is named (shard 2 recorded again: --overwrite replaces its earlier files)
  ASSERT_EQ(RunFetchscope(kRun + " --shard 2/3 --overwrite --out " + dir.string()).exit_code, 0);
  fs::remove(dir / "episode_004.mp4");
  r = RunFetchscope("merge-manifests " + dir.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("episode 4: video"), std::string::npos) << r.output;

  // a shard of another run (another seed) is refused
  const fs::path other = tmp.path() / "other";
  ASSERT_EQ(RunFetchscope(Record(7, 12) + " --shard 0/3 --out " + other.string()).exit_code, 0);
  r = RunFetchscope("merge-manifests " + dir.string() + " " + other.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("manifest_shard_0000_of_0003.json' (shard 0/3) belongs to another run: "
                          "--seed is 12 there but 11 in '"),
            std::string::npos)
      << r.output;

  r = RunFetchscope("merge-manifests " + (tmp.path() / "nowhere").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("nowhere' is not a folder"), std::string::npos) << r.output;
}

// Shards recorded with different options are not one run: merge-manifests refuses them, naming
// the first option that differs and both values, and writes nothing (before, shard 0 with
// --layers rgb,depth and shard 1 with --msaa 4 merged into a manifest claiming depth for both).
TEST_F(ShardRunTest, MergeRefusesShardsRecordedWithOtherOptions) {
  TempDir tmp;
  const std::string run = Record(2);
  struct Case {
    std::string shard0, shard1;  // the options each shard adds
    std::string message;
  };
  const std::vector<Case> cases = {
      {"--layers rgb,depth", "--msaa 4", "--msaa is 4 there but auto in '"},
      {"--layers rgb,depth", "", "--layers is rgb there but rgb,depth in '"},
      {"", "--format mp4,webm", "--format is mp4,webm there but mp4 in '"}};
  for (size_t i = 0; i < cases.size(); ++i) {
    const Case& c = cases[i];
    // each shard in its own folder, as on two machines
    const fs::path m0 = tmp.path() / ("m0_" + std::to_string(i));
    const fs::path m1 = tmp.path() / ("m1_" + std::to_string(i));
    auto r = RunFetchscope(run + " --shard 0/2 " + c.shard0 + " --out " + m0.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    r = RunFetchscope(run + " --shard 1/2 " + c.shard1 + " --out " + m1.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    r = RunFetchscope("merge-manifests " + m0.string() + " " + m1.string());
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(
        r.output.find("fetchscope: error: '" + (m1 / "manifest_shard_0001_of_0002.json").string() +
                      "' (shard 1/2) belongs to another run: " + c.message +
                      (m0 / "manifest_shard_0000_of_0002.json").string() +
                      "' (shard 0/2); record every shard of a run with the same options"),
        std::string::npos)
        << r.output;
    EXPECT_FALSE(fs::exists(m0 / "manifest.json"));
    EXPECT_FALSE(fs::exists(m0 / "index.html"));
  }
  // in one folder, record itself refuses the second shard, by the same definition
  const fs::path m0 = tmp.path() / "m0_0";
  auto r = RunFetchscope(run + " --shard 1/2 --msaa 4 --out " + m0.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("holds another record run (manifest_shard_0000_of_0002.json: --msaa "
                          "is auto there and 4 here)"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(m0 / "manifest_shard_0001_of_0002.json"));
}

// A shard manifest of a newer schema version, or one from before "parameters", cannot be told to
// be of the same run: merge-manifests refuses it, naming the file (and the versions).
TEST_F(ShardRunTest, MergeRefusesNewerAndUnversionedShardManifests) {
  TempDir tmp;
  const fs::path dir = tmp.path() / "run";
  for (int i : {0, 1}) {
    auto r =
        RunFetchscope(Record(2) + " --shard " + std::to_string(i) + "/2 --out " + dir.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  const fs::path m1 = dir / "manifest_shard_0001_of_0002.json";
  auto manifest = nlohmann::json::parse(ReadFile(m1));
  EXPECT_EQ(manifest["schema_version"], 1);
  manifest["schema_version"] = 2;
  std::ofstream(m1) << manifest.dump(2);
  auto r = RunFetchscope("merge-manifests " + dir.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("'" + m1.string() +
                          "' has manifest schema version 2; this fetchscope reads versions 0 to 1: "
                          "use a newer fetchscope"),
            std::string::npos)
      << r.output;
  manifest.erase("schema_version");  // version 0: read as before, but without its parameters
  manifest.erase("parameters");
  std::ofstream(m1) << manifest.dump(2);
  r = RunFetchscope("merge-manifests " + dir.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("'" + m1.string() + "' does not record the run's parameters"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(dir / "manifest.json"));
}

// The environment of a Slurm array task and of a Kubernetes Indexed Job pod, as the binary sees it.
TEST_F(ShardRunTest, ShardFromSlurmAndKubernetesEnvironment) {
  TempDir tmp;
  const std::string bin = FETCHSCOPE_BIN;
  auto r = RunCommand("env SLURM_ARRAY_TASK_ID=1 SLURM_ARRAY_TASK_COUNT=3 " + bin + " " + kRun +
                      " --out " + tmp.path().string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto m = nlohmann::json::parse(ReadFile(tmp.path() / "manifest_shard_0001_of_0003.json"));
  EXPECT_EQ(m["shard"]["source"], "SLURM_ARRAY_TASK_ID");
  EXPECT_EQ(m["shard"]["episodes"], nlohmann::json({1, 4}));

  r = RunCommand("env JOB_COMPLETION_INDEX=2 " + bin + " " + kRun + " --shard-count 3 --out " +
                 tmp.path().string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  m = nlohmann::json::parse(ReadFile(tmp.path() / "manifest_shard_0002_of_0003.json"));
  EXPECT_EQ(m["shard"]["source"], "JOB_COMPLETION_INDEX");
  EXPECT_EQ(m["shard"]["episodes"], nlohmann::json({2, 5}));
}

struct BadShard {
  std::string env;   // assignments for env(1)
  std::string args;  // after the common record arguments
  std::string message;
};

void PrintTo(const BadShard& c, std::ostream* os) { *os << c.env << " " << c.args; }

class BadShardTest : public ::testing::TestWithParam<BadShard> {};

TEST_P(BadShardTest, ExitTwoNamingTheValueNothingWritten) {
  ClearShardEnvironment();
  TempDir tmp;
  auto r = RunCommand("env " + GetParam().env + " " + FETCHSCOPE_BIN + " " + kRun + " " +
                      GetParam().args + " --out " + (tmp.path() / "run").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("fetchscope: error: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(GetParam().message), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp.path() / "run"));
}

INSTANTIATE_TEST_SUITE_P(
    Cases, BadShardTest,
    ::testing::Values(
        BadShard{"", "--shard 3/3", "--shard '3/3': I must be below N"},
        BadShard{"", "--shard 0/0", "N must be at least 1"},
        BadShard{"", "--shard half", "'half' is not of the form I/N"},
        BadShard{"JOB_COMPLETION_INDEX=4", "", "JOB_COMPLETION_INDEX=4"},
        BadShard{"JOB_COMPLETION_INDEX=4", "--shard-count 4",
                 "JOB_COMPLETION_INDEX=4 must be below"},
        BadShard{"JOB_COMPLETION_INDEX=four", "--shard-count 8", "JOB_COMPLETION_INDEX='four'"},
        BadShard{"SLURM_ARRAY_TASK_ID=2 SLURM_ARRAY_TASK_COUNT=zz", "",
                 "SLURM_ARRAY_TASK_COUNT='zz'"},
        BadShard{"SLURM_ARRAY_TASK_ID=9 SLURM_ARRAY_TASK_COUNT=4", "", "SLURM_ARRAY_TASK_ID=9"},
        BadShard{"", "--shard-count 3", "needs JOB_COMPLETION_INDEX"},
        BadShard{"", "--jobs -1", "--jobs"}));

}  // namespace
}  // namespace fetchscope
