// Issue 19's limits and names: render's layer file names and its PNG-only -o, an edited env id
// in a recording named with its file and key, frame sizes beyond memory refused (and the frame
// pool bounded whatever the size and --steps), and --steps past the env's TimeLimit allowed and
// marked.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "encode/frame_pool.h"
#include "render/frame_limits.h"
#include "render/overlay.h"
#include "run/record_run.h"
#include "src/trajectory.h"
#include "test_util.h"

extern char** environ;

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::CommandResult;
using testing::ReadFile;
using testing::RunFetchscope;
using testing::TempDir;

std::set<std::string> FilesIn(const fs::path& dir) {
  std::set<std::string> files;
  for (const auto& entry : fs::directory_iterator(dir)) files.insert(entry.path().filename());
  return files;
}

int Lines(const std::string& text) {
  int n = 0;
  for (char c : text) n += c == '\n';
  return n + (!text.empty() && text.back() != '\n');
}

int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

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

// ---- render's file names: one rule, from --help alone

TEST(RenderNames, SeveralLayersNameEveryNonRgbLayerAfterIt) {
  TempDir tmp;
  const std::string common = "render --env-id FetchPush-v4 --width 64 --height 64 ";
  const fs::path lay = tmp.path() / "lay.png";
  CommandResult r = RunFetchscope(common + "--layers depth,segmentation -o " + lay.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // depth goes to lay_depth.png whether or not rgb is listed; nothing is called lay.png
  EXPECT_EQ(FilesIn(tmp.path()), (std::set<std::string>{"lay_depth.png", "lay_segmentation.png",
                                                        "lay_segmentation_legend.json"}));
  for (const char* name :
       {"lay_depth.png", "lay_segmentation.png", "lay_segmentation_legend.json"}) {
    EXPECT_NE(r.output.find((tmp.path() / name).string()), std::string::npos) << r.output;
  }
  const fs::path both = tmp.path() / "both.png";
  r = RunFetchscope(common + "--layers depth,rgb -o " + both.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(tmp.path() / "both_depth.png"));
  EXPECT_TRUE(fs::exists(both));
  // one layer: -o is that layer's file
  const fs::path alone = tmp.path() / "alone.png";
  r = RunFetchscope(common + "--layers depth -o " + alone.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(alone));
  EXPECT_FALSE(fs::exists(tmp.path() / "alone_depth.png"));
  // and --help states the rule
  const CommandResult help = RunFetchscope("render --help");
  std::string flat;
  for (char c : help.output) {
    if (c == '\n') c = ' ';
    if (c != ' ' || flat.empty() || flat.back() != ' ') flat += c;
  }
  EXPECT_NE(flat.find("with several, NAME.png holds rgb"), std::string::npos) << help.output;
}

TEST(RenderNames, RefusesAnOutputThatIsNotPng) {
  TempDir tmp;
  for (const char* name : {"x.jpg", "x.JPEG", "x"}) {
    SCOPED_TRACE(name);
    const fs::path out = tmp.path() / name;
    const CommandResult r =
        RunFetchscope("render --width 64 --height 64 -o " + out.string() + " 2>&1");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_EQ(Lines(r.output), 1) << r.output;
    EXPECT_NE(r.output.find(out.string()), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(".png"), std::string::npos) << r.output;
  }
  EXPECT_TRUE(FilesIn(tmp.path()).empty());
  const CommandResult upper =
      RunFetchscope("render --width 64 --height 64 -o " + (tmp.path() / "Y.PNG").string());
  EXPECT_EQ(upper.exit_code, 0) << upper.output;
}

// ---- an edited env id in a recording

TEST(EditedRecording, UnknownEnvIdNamesTheFileAndTheKey) {
  TempDir tmp;
  const fs::path t = tmp.path() / "t.json";
  CommandResult r =
      RunFetchscope("rollout --env-id FetchPush-v4 --steps 2 --json-out " + t.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  json j = json::parse(ReadFile(t));
  j["env_id"] = "FetchPusj-v4";
  std::ofstream(t) << j.dump();
  const fs::path out = tmp.path() / "run";
  r = RunFetchscope("record --from " + t.string() + " --out " + out.string() + " 2>&1");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(Lines(r.output), 1) << r.output;
  EXPECT_NE(r.output.find(t.string() + ": env_id: unknown env id 'FetchPusj-v4'"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("did you mean 'FetchPush-v4'"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
  // the same file as a replay policy
  r = RunFetchscope("rollout --policy replay:" + t.string() + " 2>&1");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find(t.string() + ": env_id: unknown env id 'FetchPusj-v4'"),
            std::string::npos)
      << r.output;
}

// ---- frame sizes

TEST(FrameSize, TooLargeIsRefusedWithTheLimitBeforeAnything) {
  TempDir tmp;
  const fs::path png = tmp.path() / "big.png";
  CommandResult r = RunFetchscope("render --width 8192 --height 8192 -o " + png.string() + " 2>&1");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(Lines(r.output), 1) << r.output;
  EXPECT_NE(r.output.find("8192x8192"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("4096x4096"), std::string::npos) << r.output;
  // two 4096-wide cameras make a frame over the limit too
  r = RunFetchscope("record --camera default,track --width 4096 --height 4096 --steps 1 --out " +
                    (tmp.path() / "run").string() + " 2>&1");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(Lines(r.output), 1) << r.output;
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

// ---- --steps past the TimeLimit

TEST(PastTimeLimit, RolloutMarksEveryStepAfterTheLimit) {
  TempDir tmp;
  const fs::path t = tmp.path() / "t.json";
  const CommandResult r = RunFetchscope(
      "rollout --env-id FetchReach-v4 --steps 53 --episodes 2 --json-out " + t.string() + " 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(Count(r.output, "TimeLimit"), 1) << r.output;  // said once
  EXPECT_NE(r.output.find("steps 51..53"), std::string::npos) << r.output;
  const json j = json::parse(ReadFile(t));
  ASSERT_TRUE(j.contains("note"));
  EXPECT_NE(j["note"].get<std::string>().find("TimeLimit"), std::string::npos);
  for (const json& e : j["episodes"]) {
    ASSERT_EQ(e["steps"].size(), 54u);
    for (const json& s : e["steps"]) {
      const int step = s["t"].get<int>();
      EXPECT_EQ(s.contains("past_time_limit"), step > 50) << step;
      if (step > 50) {
        EXPECT_EQ(s["past_time_limit"], true);
      }
    }
    EXPECT_EQ(e["past_time_limit"],
              (json{{"max_episode_steps", 50}, {"first_step", 51}, {"steps", 3}}));
  }
  // the file reads back and writes the same bytes
  EXPECT_EQ(TrajectoryText(ParseTrajectory(ReadFile(t), t.string())), ReadFile(t));
  // within the limit nothing is marked or said
  const CommandResult within = RunFetchscope("rollout --env-id FetchReach-v4 --steps 50 2>&1");
  ASSERT_EQ(within.exit_code, 0) << within.output;
  EXPECT_EQ(within.output.find("past_time_limit"), std::string::npos);
  EXPECT_EQ(within.output.find("TimeLimit"), std::string::npos);
  EXPECT_EQ(within.output.find("\"note\""), std::string::npos);
}

TEST(PastTimeLimit, RecordMarksTheTrajectoryAndTheHud) {
  TempDir tmp;
  const fs::path out = tmp.path() / "run";
  const CommandResult r = RunFetchscope(
      "record --env-id FetchReach-v4 --steps 52 --width 64 --height 64 --no-report "
      "--out " +
      out.string() + " 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(Count(r.output, "TimeLimit"), 1) << r.output;
  const Trajectory t = ReadTrajectory((out / "episode_000.json").string());
  ASSERT_EQ(t.episodes.front().steps.size(), 53u);
  EXPECT_FALSE(t.episodes.front().steps[50].past_time_limit);
  EXPECT_TRUE(t.episodes.front().steps[51].past_time_limit);
  EXPECT_TRUE(t.episodes.front().steps[52].past_time_limit);
  // record --from replays it, marks and all
  const fs::path again = tmp.path() / "again";
  const CommandResult from =
      RunFetchscope("record --from " + out.string() +
                    " --width 64 --height 64 --no-report -q --out " + again.string() + " 2>&1");
  ASSERT_EQ(from.exit_code, 0) << from.output;
  EXPECT_EQ(ReadFile(again / "episode_000.json"), ReadFile(out / "episode_000.json"));

  FrameInfo info;
  info.step = 51;
  info.past_time_limit = 50;
  EXPECT_NE(FormatHud(info, OverlaySet{}).values.find("51 past limit 50"), std::string::npos);
  info.step = 50;
  info.past_time_limit = 0;
  EXPECT_EQ(FormatHud(info, OverlaySet{}).values.substr(0, 3), "50\n");
}

}  // namespace
}  // namespace fetchscope
