// Ctrl-C during `record --policy exec:...`: the terminal sends SIGINT to fetchscope's whole
// foreground process group. Every run must end as an interruption (exit 130, a manifest with
// "interrupted": true, the episode in progress marked incomplete), never as an error, and no
// policy child may outlive fetchscope. The exec child runs in its own process group and gets
// the caller's LD_LIBRARY_PATH back from the bundle launcher's FETCHSCOPE_CALLER_LD_LIBRARY_PATH.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::ReadFile;
using testing::TempDir;
using testing::WaitExit;
namespace fs = std::filesystem;

std::string PolicyScript() {
  return (testing::SourceDir() / "tests" / "data" / "exec" / "record_pid_policy.py").string();
}

// Starts `fetchscope ARGS` as a terminal starts a foreground job: in a process group of its
// own (whose id is the returned pid), with `env` added to the environment.
pid_t SpawnJob(const std::string& args, const fs::path& log, const std::vector<std::string>& env) {
  const std::string command =
      "exec " + std::string(FETCHSCOPE_BIN) + " " + args + " </dev/null >" + log.string() + " 2>&1";
  const pid_t pid = fork();
  if (pid == 0) {
    setpgid(0, 0);
    for (const std::string& e : env) putenv(const_cast<char*>(e.c_str()));
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  setpgid(pid, pid);
  return pid;
}

// The policy children noted in `dir` (one JSON file each).
std::vector<nlohmann::json> PolicyChildren(const fs::path& dir) {
  std::vector<nlohmann::json> out;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().extension() == ".json" && e.path().filename().string()[0] != '.') {
      out.push_back(nlohmann::json::parse(ReadFile(e.path())));
    }
  }
  return out;
}

// Waits (bounded, so a hang fails the test) until a policy child noted itself (at the first
// step of the first episode) or `pid` exited.
bool WaitForChild(const fs::path& dir, pid_t pid) {
  for (int i = 0; i < 6000; ++i) {  // 60 s
    if (!PolicyChildren(dir).empty()) return true;
    if (waitpid(pid, nullptr, WNOHANG) == pid) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

bool Alive(pid_t pid) { return kill(pid, 0) == 0 || errno != ESRCH; }

std::string RecordArgs(const fs::path& out) {
  return "record --env-id FetchReach-v4 --policy \"exec:python3 " + PolicyScript() +
         "\" --episodes 1000 --steps 50 --width 16 --height 16 --sheet-every 25 -q --out " +
         out.string();
}

TEST(ExecInterrupt, CtrlCAlwaysEndsAsAnInterruptionWithAManifest) {
  unsetenv("DISPLAY");
  std::mt19937 random(20261123);  // fixed: the same "random" moments every time
#ifdef FETCHSCOPE_SANITIZED
  const int runs = 12;  // the sanitizer stage checks memory; the Release run explores the races
#else
  const int runs = 20;  // about 2 s each: the random moments cover the episode and its end
#endif
  for (int run = 0; run < runs; ++run) {
    SCOPED_TRACE("run " + std::to_string(run));
    TempDir tmp;
    const fs::path out = tmp.path() / "run";
    const fs::path pids = tmp.path() / "pids";
    fs::create_directories(pids);
    const std::string pid_dir = "FETCHSCOPE_TEST_PID_DIR=" + pids.string();
    const pid_t pid = SpawnJob(RecordArgs(out), tmp.path() / "log", {pid_dir});
    ASSERT_TRUE(WaitForChild(pids, pid)) << ReadFile(tmp.path() / "log");
    std::this_thread::sleep_for(std::chrono::milliseconds(random() % 600));
    kill(-pid, SIGINT);  // Ctrl-C: the foreground group
    if (run % 2 == 1) {
      // the child dies of the same signal anyway (as if it had been in the group)
      std::this_thread::sleep_for(std::chrono::milliseconds(random() % 5));
      for (const nlohmann::json& child : PolicyChildren(pids))
        kill(child["pid"].get<int>(), SIGINT);
    }
    const int code = WaitExit(pid);
    const std::string log = ReadFile(tmp.path() / "log");
    ASSERT_EQ(code, 130) << log;
    EXPECT_EQ(log.find("killed by signal"), std::string::npos) << log;
    ASSERT_TRUE(fs::exists(out / "manifest.json")) << log;
    const auto m = nlohmann::json::parse(ReadFile(out / "manifest.json"));
    EXPECT_EQ(m["interrupted"], true);
    EXPECT_EQ(m["signal"], "SIGINT");
    EXPECT_TRUE(m["failures"].empty()) << m["failures"];
    ASSERT_GE(m["episodes"].size(), 1u);
    // the episodes before the last are whole; the last says whether it got to its end
    for (size_t i = 0; i < m["episodes"].size(); ++i) {
      const auto& e = m["episodes"][i];
      const auto t = nlohmann::json::parse(ReadFile(out / e["trajectory"].get<std::string>()));
      const bool complete = e["complete"].get<bool>();
      const bool whole = e["steps"].get<int>() == 50;
      EXPECT_EQ(t["episodes"][0]["complete"].get<bool>(), complete);
      EXPECT_EQ(complete, whole) << e;
      if (i + 1 < m["episodes"].size()) {
        EXPECT_TRUE(complete) << e;
      }
    }
    // no policy child outlives fetchscope, and none shared fetchscope's process group
    const std::vector<nlohmann::json> children = PolicyChildren(pids);
    ASSERT_FALSE(children.empty());
    for (const nlohmann::json& child : children) {
      EXPECT_FALSE(Alive(child["pid"].get<int>())) << "orphan policy process " << child;
      EXPECT_NE(child["pgid"].get<int>(), pid) << "the child was in the terminal's group";
    }
  }
}

// The child gets the caller's LD_LIBRARY_PATH back (the bundle launcher keeps it in
// FETCHSCOPE_CALLER_LD_LIBRARY_PATH, "__unset__" when there was none).
TEST(ExecInterrupt, ChildGetsTheCallersLibraryPath) {
  unsetenv("DISPLAY");
  for (const std::string caller : {"/caller/lib", "__unset__"}) {
    SCOPED_TRACE(caller);
    TempDir tmp;
    const fs::path pids = tmp.path() / "pids";
    fs::create_directories(pids);
    const testing::CommandResult r = testing::RunCommand(
        "FETCHSCOPE_TEST_PID_DIR=" + pids.string() +
        " FETCHSCOPE_CALLER_LD_LIBRARY_PATH=" + caller + " LD_LIBRARY_PATH=/bundle/lib " +
        FETCHSCOPE_BIN + " record --env-id FetchReach-v4 --policy \"exec:python3 " +
        PolicyScript() + "\" --episodes 1 --steps 2 --width 16 --height 16 -q --out " +
        (tmp.path() / "run").string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::vector<nlohmann::json> children = PolicyChildren(pids);
    ASSERT_EQ(children.size(), 1u);
    if (caller == "__unset__") {
      EXPECT_TRUE(children[0]["ld_library_path"].is_null()) << children[0];
    } else {
      EXPECT_EQ(children[0]["ld_library_path"], caller);
    }
  }
}

}  // namespace
}  // namespace fetchscope
