// Signals during `record` and `golden update`: SIGINT/SIGTERM finish or drop the episode (scene)
// in progress, keep the ones already written whole and say "interrupted" (record: in the
// manifest); SIGKILL never leaves a truncated file under a final name (outputs are written under
// temporary names and renamed).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <thread>

#include "encode/png_io.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::DecodedFrames;
using testing::ReadFile;
using testing::RunCommand;
using testing::TempDir;
using testing::WaitExit;
namespace fs = std::filesystem;

// Starts `fetchscope ARGS` in the background (output to `log`); returns its pid.
pid_t Spawn(const std::string& args, const fs::path& log) {
  const std::string command =
      "exec " + std::string(FETCHSCOPE_BIN) + " " + args + " </dev/null >" + log.string() + " 2>&1";
  pid_t pid = fork();
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

// Waits (up to a generous bound, so a hung binary fails the test instead of hanging it) until
// `path` exists or the process exits. True if the file appeared.
bool WaitForFile(const fs::path& path, pid_t pid) {
  for (int i = 0; i < 1200; ++i) {  // 120 s
    if (fs::exists(path)) return true;
    if (waitpid(pid, nullptr, WNOHANG) == pid) return fs::exists(path);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return false;
}

// Every output under a final name is whole: videos decode, sheets decode, JSON parses.
void ExpectFinalFilesWhole(const fs::path& out) {
  for (const auto& e : fs::directory_iterator(out)) {
    const std::string name = e.path().filename().string();
    if (name[0] == '.') continue;  // a temporary (SIGKILL leaves those; they are hidden)
    SCOPED_TRACE(name);
    if (e.path().extension() == ".mp4") {
      EXPECT_GT(DecodedFrames(e.path()), 0);
    } else if (e.path().extension() == ".png") {
      EXPECT_NO_THROW(ReadPng(e.path().string()));
    } else if (e.path().extension() == ".json") {
      EXPECT_TRUE(nlohmann::json::accept(ReadFile(e.path())));
    } else if (name == "index.html") {  // the run's report
      const std::string html = ReadFile(e.path());
      EXPECT_EQ(html.substr(html.size() - 8), "</html>\n");
    } else {
      ADD_FAILURE() << "unexpected file";
    }
  }
}

const char kRecord[] =
    "record --env-id FetchPush-v4 --policy scripted --episodes 40 --width 96 --height 72 --out ";

class SignalsTest : public ::testing::TestWithParam<int> {
 protected:
  void SetUp() override { unsetenv("DISPLAY"); }
};

TEST_P(SignalsTest, RecordStopsCleanlyAndSaysInterrupted) {
  const int sig = GetParam();
  TempDir tmp;
  const fs::path out = tmp.path() / "run";
  const pid_t pid = Spawn(kRecord + out.string(), tmp.path() / "log");
  ASSERT_TRUE(WaitForFile(out / "episode_001.json", pid)) << ReadFile(tmp.path() / "log");
  kill(pid, sig);
  const int code = WaitExit(pid);
  const std::string log = ReadFile(tmp.path() / "log");
  EXPECT_EQ(code, 128 + sig) << log;
  EXPECT_EQ(log.find("terminate called"), std::string::npos) << log;

  ASSERT_TRUE(fs::exists(out / "manifest.json")) << log;
  const auto m = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  EXPECT_EQ(m["interrupted"], true);
  EXPECT_EQ(m["signal"], sig == SIGINT ? "SIGINT" : "SIGTERM");
  ASSERT_GE(m["episodes"].size(), 2u);
  EXPECT_LT(m["episodes"].size(), 40u);
  // every episode the manifest lists plays, with as many frames as it says
  std::set<std::string> listed = {"manifest.json", "index.html"};
  for (const auto& e : m["episodes"]) {
    for (const char* key : {"video", "sheet", "trajectory"}) {
      listed.insert(e[key].get<std::string>());
      EXPECT_TRUE(fs::exists(out / e[key].get<std::string>())) << e[key];
    }
    EXPECT_EQ(DecodedFrames(out / e["video"].get<std::string>()), e["frames"].get<int>());
  }
  // and nothing else is there: the episode in progress was finalized (and listed) or removed
  for (const auto& f : fs::directory_iterator(out)) {
    EXPECT_TRUE(listed.count(f.path().filename().string()))
        << "unlisted or temporary file " << f.path();
  }
  ExpectFinalFilesWhole(out);
}

INSTANTIATE_TEST_SUITE_P(IntAndTerm, SignalsTest, ::testing::Values(SIGINT, SIGTERM),
                         [](const ::testing::TestParamInfo<int>& info) {
                           return std::string(info.param == SIGINT ? "SIGINT" : "SIGTERM");
                         });

// SIGKILL cannot be caught: what protects the user is that every output is written under a
// temporary name and renamed when complete. Kill at a few moments; final names stay whole.
TEST(SignalsKill, SigkillLeavesNoTruncatedFileUnderAFinalName) {
  unsetenv("DISPLAY");
  for (const char* wait_for : {"episode_000.mp4", "episode_001_sheet.png", "episode_002.json"}) {
    SCOPED_TRACE(wait_for);
    TempDir tmp;
    const fs::path out = tmp.path() / "run";
    const pid_t pid = Spawn(kRecord + out.string(), tmp.path() / "log");
    ASSERT_TRUE(WaitForFile(out / wait_for, pid)) << ReadFile(tmp.path() / "log");
    kill(pid, SIGKILL);
    EXPECT_EQ(WaitExit(pid), 128 + SIGKILL);
    EXPECT_FALSE(fs::exists(out / "manifest.json"));
    ExpectFinalFilesWhole(out);
    // the videos under final names are complete episodes: reset frame + 50 steps
    for (const auto& e : fs::directory_iterator(out)) {
      if (e.path().extension() == ".mp4" && e.path().filename().string()[0] != '.') {
        EXPECT_EQ(DecodedFrames(e.path()), 51) << e.path();
      }
    }
  }
}

// `golden update` on a copy of golden/ without its images: SIGINT after the first scene stops
// after the scene in progress; every scene written has its PNG and its state, both whole.
TEST(SignalsGolden, GoldenUpdateStopsAfterTheSceneInProgress) {
  unsetenv("DISPLAY");
  TempDir tmp;
  const fs::path golden = tmp.path() / "golden";
  fs::copy(testing::SourceDir() / "golden", golden, fs::copy_options::recursive);
  for (const auto& e : fs::directory_iterator(testing::SourceDir() / "golden")) {
    const std::string name = e.path().filename().string();
    if (e.path().extension() == ".png" || name.find("_state.json") != std::string::npos) {
      fs::remove(golden / name);
    }
  }
  const auto manifest = nlohmann::json::parse(ReadFile(golden / "manifest.json"));
  const size_t scenes = manifest["scenes"].size();
  const std::string first = manifest["scenes"][0]["name"].get<std::string>();
  std::string args = "golden update --golden-dir " + golden.string();
  if (!testing::GenuineAssetsDir().empty()) {
    args += " --genuine-assets " + testing::GenuineAssetsDir().string();
  }
  const pid_t pid = Spawn(args, tmp.path() / "log");
  ASSERT_TRUE(WaitForFile(golden / (first + "_state.json"), pid)) << ReadFile(tmp.path() / "log");
  kill(pid, SIGINT);
  EXPECT_EQ(WaitExit(pid), 128 + SIGINT) << ReadFile(tmp.path() / "log");
  EXPECT_NE(ReadFile(tmp.path() / "log").find("interrupted by SIGINT"), std::string::npos);
  size_t written = 0;
  for (const auto& e : fs::directory_iterator(golden)) {
    const std::string name = e.path().filename().string();
    EXPECT_EQ(name.find(".tmp-"), std::string::npos) << "leftover temporary " << name;
    if (e.path().extension() != ".png") continue;
    ++written;
    EXPECT_NO_THROW(ReadPng(e.path().string())) << name;
    const fs::path state = golden / (e.path().stem().string() + "_state.json");
    ASSERT_TRUE(fs::exists(state)) << name << " without its state";
    EXPECT_TRUE(nlohmann::json::accept(ReadFile(state))) << state;
  }
  EXPECT_GE(written, 1u);
  EXPECT_LT(written, scenes);
}

// The pids of `parent`'s child processes (from /proc: PPid in each process's status).
std::set<pid_t> ChildrenOf(pid_t parent) {
  std::set<pid_t> children;
  for (const auto& e : fs::directory_iterator("/proc")) {
    const std::string name = e.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    const std::string status = ReadFile(e.path() / "status");
    const size_t at = status.find("PPid:");
    if (at != std::string::npos && std::atoi(status.c_str() + at + 5) == parent) {
      children.insert(std::atoi(name.c_str()));
    }
  }
  return children;
}

// Whether process `pid` still exists (a zombie counts as gone: it runs nothing).
bool Alive(pid_t pid) {
  const std::string status = ReadFile(fs::path("/proc") / std::to_string(pid) / "status");
  return !status.empty() && status.find("State:\tZ") == std::string::npos;
}

// Waits up to 10 s for every process of `pids` to be gone.
bool AllGone(const std::set<pid_t>& pids) {
  for (int i = 0; i < 100; ++i) {
    bool any = false;
    for (pid_t p : pids) any = any || Alive(p);
    if (!any) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return false;
}

// Every episode a manifest lists decodes with as many frames as it says, and every file under a
// final name is whole.
void ExpectListedEpisodesPlay(const nlohmann::json& m, const fs::path& out) {
  for (const auto& e : m["episodes"]) {
    EXPECT_EQ(DecodedFrames(out / e["video"].get<std::string>()), e["frames"].get<int>())
        << e.dump();
  }
  ExpectFinalFilesWhole(out);
}

// A `record --jobs 3` run started in the background, seen once its second episode is written.
struct JobsRun {
  pid_t pid = -1;           // the parent
  std::set<pid_t> workers;  // its worker processes
};

const char kRecordJobs[] =
    "record --env-id FetchPush-v4 --policy random --episodes 60 --steps 20 --width 64 --height 48 "
    "--jobs 3 --out ";

JobsRun StartJobsRun(const fs::path& out, const fs::path& log) {
  JobsRun run;
  run.pid = Spawn(kRecordJobs + out.string(), log);
  EXPECT_TRUE(WaitForFile(out / "episode_001.json", run.pid)) << ReadFile(log);
  run.workers = ChildrenOf(run.pid);
  return run;
}

// With worker processes, SIGINT and SIGTERM reach the parent; it stops every worker, each
// finishes the video it is writing so that it plays, the manifest says interrupted, and no
// worker outlives the run.
TEST_P(SignalsTest, WorkerProcessesStopCleanlyWithNoOrphans) {
  const int sig = GetParam();
  TempDir tmp;
  const fs::path out = tmp.path() / "run";
  const JobsRun run = StartJobsRun(out, tmp.path() / "log");
  const pid_t pid = run.pid;
  const std::set<pid_t>& workers = run.workers;
  EXPECT_EQ(workers.size(), 3u) << "one process per worker";
  kill(pid, sig);
  const int code = WaitExit(pid);
  const std::string log = ReadFile(tmp.path() / "log");
  EXPECT_EQ(code, 128 + sig) << log;
  EXPECT_TRUE(AllGone(workers)) << "a worker outlived the run";
  const auto m = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  EXPECT_EQ(m["interrupted"], true);
  EXPECT_EQ(m["worker_mode"], "process");
  ASSERT_GE(m["episodes"].size(), 2u);
  EXPECT_LT(m["episodes"].size(), 60u);
  std::set<long> manifest_pids;
  for (const auto& w : m["workers"]) manifest_pids.insert(w["pid"].get<long>());
  for (pid_t w : workers)
    EXPECT_TRUE(manifest_pids.count(w)) << "worker " << w << " not in the manifest";
  ExpectListedEpisodesPlay(m, out);
}

// Whether `pid` is stopped (state T in /proc/PID/stat), waiting up to 5 s for a SIGSTOP to land.
bool WaitStopped(pid_t pid) {
  for (int i = 0; i < 500; ++i) {
    const std::string stat = ReadFile("/proc/" + std::to_string(pid) + "/stat");
    const size_t paren = stat.rfind(')');
    if (paren == std::string::npos || paren + 2 >= stat.size()) return false;  // gone
    if (stat[paren + 2] == 'T' || stat[paren + 2] == 't') return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

// A worker caught recording: each is stopped (SIGSTOP) in turn while its open files are read, so
// that what it holds cannot change under the test, and the first with a file of the run folder
// open (the episode it is writing) is returned still stopped; a worker between two episodes, with
// nothing in hand, is let go (SIGCONT). -1 when none was caught within about 30 s.
pid_t StopAWorkerThatIsRecording(const std::set<pid_t>& workers, const fs::path& out) {
  const std::string folder = fs::weakly_canonical(out).string() + "/";
  for (int round = 0; round < 1000; ++round) {
    for (pid_t w : workers) {
      if (kill(w, SIGSTOP) != 0) continue;
      bool recording = false;
      std::error_code ec;
      if (WaitStopped(w)) {
        for (const auto& fd : fs::directory_iterator("/proc/" + std::to_string(w) + "/fd", ec)) {
          const fs::path target = fs::read_symlink(fd.path(), ec);
          if (!ec && target.string().rfind(folder, 0) == 0) recording = true;
        }
      }
      if (recording) return w;
      kill(w, SIGCONT);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return -1;
}

// A worker that dies (here SIGKILL, as the OOM killer would) is reported with the episode it
// was recording; the other workers' finished episodes stay and the manifest says what is
// missing; exit 1. The victim is caught with an episode file open: on a busy machine the first
// worker could be between two episodes, holding none, and lose nothing.
TEST(SignalsWorkers, DeadWorkerIsReportedAndTheOthersEpisodesStay) {
  unsetenv("DISPLAY");
  TempDir tmp;
  const fs::path out = tmp.path() / "run";
  const JobsRun run = StartJobsRun(out, tmp.path() / "log");
  const pid_t pid = run.pid;
  const std::set<pid_t>& workers = run.workers;
  ASSERT_EQ(workers.size(), 3u);
  const pid_t victim = StopAWorkerThatIsRecording(workers, out);
  ASSERT_NE(victim, -1) << "no worker was caught with an episode file open";
  kill(victim, SIGKILL);
  const int code = WaitExit(pid);
  const std::string log = ReadFile(tmp.path() / "log");
  EXPECT_EQ(code, 1) << log;
  EXPECT_NE(log.find("SIGKILL"), std::string::npos) << log;
  EXPECT_TRUE(AllGone(workers));
  ASSERT_TRUE(fs::exists(out / "manifest.json")) << log;
  const auto m = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  ASSERT_EQ(m["failures"].size(), 1u) << m.dump();
  const auto& failure = m["failures"][0];
  ASSERT_GE(failure["episodes"].size(), 1u) << "the episode it was recording";
  std::set<int> listed, missing;
  for (const auto& e : m["episodes"]) listed.insert(e["index"].get<int>());
  for (const auto& k : m["missing"]) missing.insert(k.get<int>());
  EXPECT_GE(listed.size(), 2u);
  for (const auto& k : failure["episodes"]) {
    EXPECT_TRUE(missing.count(k.get<int>())) << "lost episode " << k << " not listed as missing";
    EXPECT_FALSE(listed.count(k.get<int>()));
  }
  EXPECT_EQ(listed.size() + missing.size(), 60u) << "every episode is either recorded or missing";
  ExpectListedEpisodesPlay(m, out);
}

// SIGKILL of the parent cannot be caught: the workers die with it (PR_SET_PDEATHSIG).
TEST(SignalsWorkers, WorkersDieWithAKilledParent) {
  unsetenv("DISPLAY");
  TempDir tmp;
  const fs::path out = tmp.path() / "run";
  const JobsRun run = StartJobsRun(out, tmp.path() / "log");
  const pid_t pid = run.pid;
  const std::set<pid_t>& workers = run.workers;
  ASSERT_EQ(workers.size(), 3u);
  kill(pid, SIGKILL);
  WaitExit(pid);
  EXPECT_TRUE(AllGone(workers)) << "orphaned workers";
}

}  // namespace
}  // namespace fetchscope
