// Frame sizes (render/frame_limits.h): sizes beyond memory refused before anything, the frame
// pool bounded whatever the size and --steps, and a large record's peak memory bounded.
#include "render/frame_limits.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "encode/frame_pool.h"
#include "run/record_run.h"
#include "tests/test_util.h"

extern char** environ;

namespace fetchscope {
namespace {

using testing::CommandResult;
using testing::FilesIn;
using testing::LineCount;
using testing::RunFetchscope;
using testing::TempDir;
namespace fs = std::filesystem;

// Runs the fetchscope binary with `args` (no shell) and returns its peak resident memory in
// bytes, that of its worker processes included (wait4 reports the largest of them); -1 when it
// fails.
long PeakRssBytes(const std::vector<std::string>& args) {
  std::vector<std::string> all = {FETCHSCOPE_BIN};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) return -1;
  int status = 0;
  rusage usage{};
  if (wait4(pid, &status, 0, &usage) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    return -1;
  }
  return usage.ru_maxrss * 1024L;
}

TEST(FrameSize, TooLargeIsRefusedWithTheLimitBeforeAnything) {
  TempDir tmp;
  const fs::path png = tmp.path() / "big.png";
  CommandResult r = RunFetchscope("render --width 8192 --height 8192 -o " + png.string() + " 2>&1");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(LineCount(r.output), 1) << r.output;
  EXPECT_NE(r.output.find("8192x8192"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("4096x4096"), std::string::npos) << r.output;
  // two 4096-wide cameras make a frame over the limit too
  r = RunFetchscope("record --camera default,track --width 4096 --height 4096 --steps 1 --out " +
                    (tmp.path() / "run").string() + " 2>&1");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(LineCount(r.output), 1) << r.output;
  EXPECT_NE(r.output.find("8192x4096"), std::string::npos) << r.output;
  EXPECT_TRUE(FilesIn(tmp.path()).empty());
}

TEST(FrameSize, FramePoolStaysWithinItsBudgetWhateverTheSteps) {
  const size_t big = size_t{2048} * 2048 * 3;
  const size_t floor = 4 + kReadbackDepth + 2;
  EXPECT_EQ(BoundedFrameCount(floor, floor + 10001, big), kFramePoolBudgetBytes / big);
  EXPECT_EQ(BoundedFrameCount(floor, floor + 10001, size_t{8192} * 8192 * 3), floor);
  const size_t small = size_t{480} * 480 * 3;
  EXPECT_EQ(BoundedFrameCount(floor, floor + 51, small), floor + 51);  // as before: no change
  // a record worker's pool: bounded by the budget, not by --steps
  EXPECT_EQ(FramePoolSize(16, 10000, big), FramePoolSize(16, 50, big));
  EXPECT_LE(FramePoolSize(16, 10000, small) * small, kFramePoolBudgetBytes);
}

TEST(FrameSize, LargeRecordKeepsPeakMemoryBounded) {
#ifdef FETCHSCOPE_SANITIZED
  GTEST_SKIP() << "AddressSanitizer's shadow memory and quarantine make peak RSS meaningless";
#endif
  TempDir tmp;
  // 2048x2048: 12.6 MB a frame; the renderer, GL buffers, the frame pool, the encoder and the
  // contact sheet's tiles together stay near 550 MB
  const long large =
      PeakRssBytes({"record", "--width", "2048", "--height", "2048", "--steps", "3", "--jobs", "1",
                    "--no-report", "-q", "--out", (tmp.path() / "large").string()});
  ASSERT_GT(large, 0);
  EXPECT_LT(large, 700L << 20) << large / (1 << 20) << " MiB";
  // and memory does not grow with --steps: 120 steps (past the TimeLimit) hold what 3 hold
  std::vector<long> peaks;
  for (const char* steps : {"3", "120"}) {
    peaks.push_back(PeakRssBytes({"record", "--width", "256", "--height", "256", "--steps", steps,
                                  "--jobs", "1", "--no-report", "-q", "--out",
                                  (tmp.path() / (std::string("s") + steps)).string()}));
    ASSERT_GT(peaks.back(), 0) << steps;
  }
  EXPECT_LT(peaks[1], peaks[0] + (64L << 20))
      << peaks[0] / (1 << 20) << " MiB, " << peaks[1] / (1 << 20) << " MiB";
}

}  // namespace
}  // namespace fetchscope
