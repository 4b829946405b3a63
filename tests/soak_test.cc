// Soak: one `record` of 10,000 frames (197 episodes x 51 frames = 10,047) with flat memory. Minutes
// long, so it carries the ctest label `soak` and is built only with -DFETCHSCOPE_SOAK=ON:
//   cmake -S . -B build -DFETCHSCOPE_SOAK=ON && cmake --build build -j2 --target soak_test
//   ctest --test-dir build -L soak --output-on-failure
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::ReadFile;
using testing::TempDir;
namespace fs = std::filesystem;

// Resident set size of `pid` in KiB (0 if it has exited).
long RssKiB(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string key;
  while (status >> key) {
    if (key == "VmRSS:") {
      long kib = 0;
      status >> kib;
      return kib;
    }
    status.ignore(1 << 12, '\n');
  }
  return 0;
}

TEST(Soak, RecordTenThousandFramesWithFlatMemory) {
  unsetenv("DISPLAY");
  constexpr int kEpisodes = 197;  // x 51 frames (reset + 50 steps) = 10,047
  TempDir tmp;
  const fs::path out = tmp.path() / "run";
  const std::string command =
      "exec " + std::string(FETCHSCOPE_BIN) +
      " record --quiet --env-id FetchPickAndPlace-v4 --policy scripted --width 160 --height 120 "
      "--episodes " +
      std::to_string(kEpisodes) + " --out " + out.string() + " >" + (tmp.path() / "log").string() +
      " 2>&1";
  const pid_t pid = fork();
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  // RSS once warmed up (after 10 episodes: encoder, GL and buffers are all allocated), then the
  // largest RSS over the remaining ~9,500 frames.
  long warm = 0, peak_after = 0;
  int status = 0;
  while (waitpid(pid, &status, WNOHANG) != pid) {
    const long rss = RssKiB(pid);
    if (warm == 0 && fs::exists(out / "episode_010.json")) {
      warm = rss;
    } else if (warm != 0) {
      peak_after = std::max(peak_after, rss);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << ReadFile(tmp.path() / "log");
  const auto m = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  EXPECT_GE(m["frames"].get<long>(), 10000);
  ASSERT_GT(warm, 0);
  // flat: growth over the last 186 episodes below 8 MiB (leaking one 160x120 frame per episode
  // would be 10.7 MB; one encoder or scene per episode, far more)
  RecordProperty("rss_warm_kib", std::to_string(warm));
  RecordProperty("rss_peak_after_kib", std::to_string(peak_after));
  std::printf("RSS after 10 episodes %ld KiB, peak afterwards %ld KiB\n", warm, peak_after);
  EXPECT_LT(peak_after - warm, 8 * 1024);
}

}  // namespace
}  // namespace fetchscope
