// Kill anywhere: a record run SIGKILLed at any point (the OOM killer, a node failure, a preemption
// past its grace time) leaves a folder that --resume completes, byte for byte as a run that was
// never interrupted. The points are the places where record makes a file final (base/kill_point.h:
// the encoder's flush, and before and after each rename of a video, a contact sheet, a
// trajectory, the manifest and the report onto its final name), numbered as one run reaches them;
// the test spreads 28 of them (half evenly, half at random, seeded) over small runs, sharded and
// not, and sometimes kills the resume too; 6 more kills land after random delays in a run with
// worker processes.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::CommandResult;
using testing::EpisodeFiles;
using testing::ReadFile;
using testing::RunFetchscope;
using testing::TempDir;
namespace fs = std::filesystem;

// One process (--worker-mode thread), so that the kill points are counted in one place; tiny
// frames and few steps, so that each of the many runs is quick.
const std::string kRun =
    "record --quiet --env-id FetchPush-v4 --policy random --seed 5 --steps 3 --width 64 "
    "--height 48 --msaa 0 --backend osmesa --jobs 1 --worker-mode thread ";

// `args` with the hook armed at kill point `at` (0: not armed).
CommandResult RunKilledAt(const std::string& args, int at) {
  return testing::RunCommand("env FETCHSCOPE_TEST_KILL_AT=" + std::to_string(at) + " " +
                             FETCHSCOPE_BIN + " " + args);
}

// The visible names in `dir` (hidden temporaries of a killed attempt must be gone too).
std::set<std::string> Names(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

nlohmann::json ManifestEpisodes(const fs::path& path) {
  return nlohmann::json::parse(ReadFile(path))["episodes"];
}

class KillAnywhereTest : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const char* name : {"SLURM_ARRAY_TASK_ID", "SLURM_ARRAY_TASK_COUNT",
                             "JOB_COMPLETION_INDEX", "FETCHSCOPE_TEST_KILL_AT"}) {
      unsetenv(name);
    }
  }

  // Kills `args` (a run into `tmp`/k<i>) at `points` random kill points, resumes each (killing the
  // resume too now and then) and compares the folder with an uninterrupted run's.
  void KillAndResume(const std::string& args, const std::string& manifest, int points,
                     unsigned seed) {
    TempDir tmp;
    const fs::path ref = tmp.path() / "ref";
    CommandResult r = RunFetchscope(args + "--out " + ref.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const auto want = EpisodeFiles(ref);
    const auto want_names = Names(ref);
    const nlohmann::json want_episodes = ManifestEpisodes(ref / manifest);

    // how many kill points one run reaches
    r = testing::RunCommand("env FETCHSCOPE_TEST_KILL_AT=list " + std::string(FETCHSCOPE_BIN) +
                            " " + args + "--out " + (tmp.path() / "count").string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    int total = 0;
    std::set<std::string> kinds;
    const std::regex line("fetchscope: kill point (\\d+): ([^\\n]*)");
    for (std::sregex_iterator it(r.output.begin(), r.output.end(), line), end; it != end; ++it) {
      total = std::max(total, std::stoi((*it)[1]));
      kinds.insert((*it)[2]);
    }
    ASSERT_GE(total, 10) << r.output;
    // the encoder's flush, the videos' and the PNG sheets' renames, the JSON files' (trajectory,
    // manifest)
    for (const char* kind : {"video flush", "video renamed", "png written, not renamed",
                             "png renamed", "file written, not renamed", "file renamed"}) {
      EXPECT_TRUE(kinds.count(kind)) << kind << "\n" << r.output;
    }

    std::mt19937 rng(seed);
    std::uniform_int_distribution<int> pick(1, total);
    std::set<int> killed_at;
    for (int i = 0; i < points; ++i) {
      // half of them spread evenly over the run (every kind of point is hit), then at random
      const int half = points / 2;
      const int at = i < half ? 1 + i * total / half : pick(rng);
      killed_at.insert(at);
      const fs::path out = tmp.path() / ("k" + std::to_string(i));
      r = RunKilledAt(args + "--out " + out.string(), at);
      ASSERT_EQ(r.exit_code, 128 + SIGKILL) << "kill point " << at << ": " << r.output;
      // every third time, the resume is killed too (at an earlier point: it has less to do)
      if (i % 3 == 2) {
        r = RunKilledAt(args + "--resume --out " + out.string(), 1 + at / 3);
        ASSERT_TRUE(r.exit_code == 128 + SIGKILL || r.exit_code == 0)
            << "kill point " << at << ", resume killed at " << 1 + at / 3 << ": " << r.output;
      }
      r = RunFetchscope(args + "--resume --out " + out.string());
      ASSERT_EQ(r.exit_code, 0) << "kill point " << at << ": " << r.output;
      EXPECT_TRUE(EpisodeFiles(out) == want) << "kill point " << at;
      EXPECT_EQ(Names(out), want_names) << "kill point " << at;
      EXPECT_EQ(ManifestEpisodes(out / manifest), want_episodes) << "kill point " << at;
      fs::remove_all(out);
    }
    std::string list;
    for (int at : killed_at) list += " " + std::to_string(at);
    std::printf("killed at %zu of %d points:%s\n", killed_at.size(), total, list.c_str());
  }
};

TEST_F(KillAnywhereTest, UnshardedRunResumesByteIdentical) {
  KillAndResume(kRun + "--episodes 2 ", "manifest.json", 10, 25);
}

TEST_F(KillAnywhereTest, ShardResumesByteIdentical) {
  KillAndResume(kRun + "--episodes 4 --shard 1/2 ", "manifest_shard_0001_of_0002.json", 8, 2025);
}

// The default worker processes, the parent SIGKILLed after a random (seeded) delay over the run's
// length (its workers die with it): whatever was being written, --resume completes the run
// byte-identical. The delays only choose where the kill lands; nothing is asserted about time.
TEST_F(KillAnywhereTest, WorkerProcessesKilledAfterRandomDelaysResume) {
  const std::string args =
      "record --quiet --env-id FetchPush-v4 --policy random --seed 5 --steps 3 --width 64 "
      "--height 48 --msaa 0 --backend osmesa --jobs 2 ";
  TempDir tmp;
  for (const char* shard : {"", "--shard 0/2 "}) {
    SCOPED_TRACE(shard);
    const std::string run = args + "--episodes 4 " + shard;
    const fs::path ref = tmp.path() / "ref";
    const auto t0 = std::chrono::steady_clock::now();
    CommandResult r = RunFetchscope(run + "--out " + ref.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const double length =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const auto want = EpisodeFiles(ref);
    const auto want_names = Names(ref);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> delay(0.2 * length, length);
    for (int i = 0; i < 3; ++i) {
      const fs::path out = tmp.path() / ("k" + std::to_string(i));
      const pid_t pid = testing::SpawnFetchscope(run + "--out " + out.string(), tmp.path() / "log");
      usleep(static_cast<useconds_t>(delay(rng) * 1e6));
      kill(pid, SIGKILL);
      testing::WaitExit(pid);
      if (!fs::exists(out)) continue;  // killed before it made the folder: nothing to resume
      r = RunFetchscope(run + "--resume --out " + out.string());
      ASSERT_EQ(r.exit_code, 0) << r.output;
      EXPECT_TRUE(EpisodeFiles(out) == want) << i;
      EXPECT_EQ(Names(out), want_names) << i;
      fs::remove_all(out);
    }
    fs::remove_all(ref);
  }
}

// The refusals that stay: a file under a run's name that cannot be fetchscope's (no trajectory,
// no video with fetchscope's tags beside it), and --resume of a killed attempt of another run.
TEST_F(KillAnywhereTest, OnlyFilesThatCannotBeFetchscopesAreRefused) {
  TempDir tmp;
  const fs::path out = tmp.path() / "run";
  // killed at the rename of episode 0's video: episode_000.mp4 without its trajectory
  CommandResult r =
      testing::RunCommand("env FETCHSCOPE_TEST_KILL_AT=list " + std::string(FETCHSCOPE_BIN) + " " +
                          kRun + "--episodes 1 --out " + (tmp.path() / "count").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex("kill point (\\d+): video renamed")));
  const int renamed = std::stoi(m[1]);
  r = RunKilledAt(kRun + "--episodes 1 --out " + out.string(), renamed + 1);
  ASSERT_EQ(r.exit_code, 128 + SIGKILL) << r.output;
  ASSERT_TRUE(fs::exists(out / "episode_000.mp4"));
  ASSERT_FALSE(fs::exists(out / "episode_000.json"));
  // the default still refuses (it could be any run), pointing at --resume
  r = RunFetchscope(kRun + "--episodes 1 --out " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("without its manifest"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--resume"), std::string::npos) << r.output;
  // another seed's --resume is refused, naming the episode and what differs
  r = RunFetchscope(std::regex_replace(kRun, std::regex("--seed 5"), "--seed 6") +
                    "--episodes 1 --resume --out " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("holds files of another record run (episode_000 is not of --env-id "
                          "FetchPush-v4 --seed 6 --policy random)"),
            std::string::npos)
      << r.output;
  // a video that is not fetchscope's under a run's name: refused in every mode, left alone
  const std::string video = ReadFile(out / "episode_000.mp4");
  {
    std::ofstream f(out / "episode_000.mp4", std::ios::binary | std::ios::trunc);
    f << "not a fetchscope video";
  }
  for (const char* mode : {"", "--resume ", "--overwrite "}) {
    r = RunFetchscope(kRun + "--episodes 1 " + mode + "--out " + out.string());
    EXPECT_EQ(r.exit_code, 2) << mode << r.output;
    EXPECT_NE(r.output.find("holds episode_000.mp4, not written by fetchscope"), std::string::npos)
        << mode << r.output;
    EXPECT_EQ(ReadFile(out / "episode_000.mp4"), "not a fetchscope video") << mode;
  }
  // fetchscope's video back: --resume and --overwrite both record the run
  {
    std::ofstream f(out / "episode_000.mp4", std::ios::binary | std::ios::trunc);
    f << video;
  }
  r = RunFetchscope(kRun + "--episodes 1 --overwrite --out " + out.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

// Matroska writes its tag names in upper case: a killed attempt's webm (then gif) is recognised
// as fetchscope's all the same, and resumed byte-identical.
TEST_F(KillAnywhereTest, WebmAndGifOfAKilledAttemptAreRecognised) {
  TempDir tmp;
  const std::string run = kRun + "--episodes 1 --format webm,gif ";
  CommandResult r = RunFetchscope(run + "--out " + (tmp.path() / "ref").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (int at : {3, 6}) {  // after the webm's rename, after the gif's
    const fs::path out = tmp.path() / ("k" + std::to_string(at));
    r = RunKilledAt(run + "--out " + out.string(), at);
    ASSERT_EQ(r.exit_code, 128 + SIGKILL) << r.output;
    ASSERT_TRUE(fs::exists(out / "episode_000.webm"));
    ASSERT_FALSE(fs::exists(out / "episode_000.json"));
    r = RunFetchscope(run + "--resume --out " + out.string());
    ASSERT_EQ(r.exit_code, 0) << at << ": " << r.output;
    EXPECT_TRUE(EpisodeFiles(out) == EpisodeFiles(tmp.path() / "ref")) << at;
  }
}

// SIGTERM (scancel, a preemption's first signal) while a --quiet run writes: it finishes the file,
// writes its manifest, and still says how to record the rest (a batch job's log needs that line).
TEST_F(KillAnywhereTest, QuietRunStillSaysHowToRecordTheRest) {
  TempDir tmp;
  const fs::path out = tmp.path() / "run", log = tmp.path() / "log";
  setenv("FETCHSCOPE_TEST_KILL_AT", "3", 1);
  setenv("FETCHSCOPE_TEST_KILL_HOW", "pause", 1);
  const pid_t pid = testing::SpawnFetchscope(kRun + "--episodes 3 --out " + out.string(), log);
  unsetenv("FETCHSCOPE_TEST_KILL_AT");
  unsetenv("FETCHSCOPE_TEST_KILL_HOW");
  // the hook says when the run waits at the kill point (within a minute, however busy)
  for (int i = 0; i < 600 && ReadFile(log).find("paused at kill point") == std::string::npos; ++i) {
    usleep(100 * 1000);
  }
  ASSERT_NE(ReadFile(log).find("paused at kill point 3"), std::string::npos) << ReadFile(log);
  kill(pid, SIGTERM);
  EXPECT_EQ(testing::WaitExit(pid), 128 + SIGTERM) << ReadFile(log);
  EXPECT_NE(ReadFile(log).find("record: to record the rest, run: "), std::string::npos)
      << ReadFile(log);
  const nlohmann::json manifest = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  EXPECT_TRUE(manifest["interrupted"].get<bool>());
  const CommandResult r = RunFetchscope(kRun + "--episodes 3 --resume --out " + out.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

}  // namespace
}  // namespace fetchscope
