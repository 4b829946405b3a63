// Progress in batch logs: log lines every 10% of the episodes and every 30 s when stderr is not
// a terminal, the redrawn bar on a terminal; and a real record run with stderr into a pipe.
#include "run/progress.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "base/number_format.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::RunCommand;
using testing::TempDir;
namespace fs = std::filesystem;

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// Everything written to a tmpfile.
std::string Contents(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string s;
  char buffer[4096];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof(buffer), f)) > 0) s.append(buffer, n);
  return s;
}

TEST(ProgressReporterTest, LogLinesEveryTenPercentAndEveryThirtySeconds) {
  std::FILE* out = std::tmpfile();
  ASSERT_NE(out, nullptr);
  double now = 100;
  ProgressReporter::Options o;
  o.label = "record";
  o.episodes = 20;
  o.frames_per_episode = 51;
  o.out = out;
  ProgressReporter progress(o, [&] { return now; });
  // episode 1 of 20 is 5%: no line; episode 2 is 10%: a line
  now += 1;
  progress.Frames(51);
  progress.EpisodeDone();
  EXPECT_EQ(Contents(out), "");
  now += 1;
  progress.Frames(51);
  progress.EpisodeDone();
  std::vector<std::string> lines = Lines(Contents(out));
  ASSERT_EQ(lines.size(), 1u);
  // 102 frames in 2 s: 51 frames/s; 918 frames left: ETA 18 s
  EXPECT_EQ(lines[0],
            "record: progress 2/20 episodes (10%), 102/1020 frames, 51.0 frames/s, ETA 18 s");
  // a slow episode: frames alone print nothing until 30 s have passed since the last line
  now += 29;
  progress.Frames(10);
  EXPECT_EQ(Lines(Contents(out)).size(), 1u);
  now += 1.5;
  progress.Frames(10);
  lines = Lines(Contents(out));
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_NE(lines[1].find("2/20 episodes (10%), 122/1020 frames"), std::string::npos) << lines[1];
  // the rest of the run: one line per further 10%, the last at 100%
  for (int e = 3; e <= 20; ++e) {
    now += 0.5;
    progress.Frames(e == 3 ? 31 : 51);
    progress.EpisodeDone();
  }
  lines = Lines(Contents(out));
  EXPECT_EQ(lines.size(), 2u + 9u);
  EXPECT_NE(lines.back().find("20/20 episodes (100%), 1020/1020 frames"), std::string::npos)
      << lines.back();
  EXPECT_NE(lines.back().find("ETA 0 s"), std::string::npos) << lines.back();
  progress.Done("record: summary");
  EXPECT_EQ(Lines(Contents(out)).back(), "record: summary");
  EXPECT_EQ(Contents(out).find('\r'), std::string::npos);
  std::fclose(out);
}

TEST(ProgressReporterTest, TerminalRedrawsOneLineAndQuietPrintsNothing) {
  std::FILE* out = std::tmpfile();
  ASSERT_NE(out, nullptr);
  double now = 0;
  ProgressReporter::Options o;
  o.episodes = 2;
  o.frames_per_episode = 10;
  o.terminal = true;
  o.out = out;
  ProgressReporter progress(o, [&] { return now; });
  now = 1;
  progress.Frames(10);
  progress.EpisodeDone();
  const std::string text = Contents(out);
  EXPECT_EQ(text.rfind("\rrecord: 0/2 episodes  frame 10/20  10.0 frames/s  ETA 1 s", 0), 0u)
      << text;
  EXPECT_EQ(text.find('\n'), std::string::npos);
  progress.Done("done");
  EXPECT_EQ(Lines(Contents(out)).back().substr(Lines(Contents(out)).back().rfind('\r') + 1),
            "done");
  std::fclose(out);

  std::FILE* quiet_out = std::tmpfile();
  o.quiet = true;
  o.terminal = false;
  o.out = quiet_out;
  ProgressReporter quiet(o, [&] { return now; });
  quiet.Frames(20);
  quiet.EpisodeDone();
  quiet.EpisodeDone();
  quiet.Done("done");
  EXPECT_EQ(Contents(quiet_out), "");
  std::fclose(quiet_out);
}

TEST(ProgressInAPipeTest, RecordPrintsProgressLinesWhenStderrIsNotATerminal) {
  unsetenv("DISPLAY");
  TempDir tmp;
  // stderr into a pipe (cat), stdout elsewhere: what a Slurm or Kubernetes log sees
  const auto r = RunCommand(std::string(FETCHSCOPE_BIN) +
                            " record --env-id FetchReach-v4 --episodes 10 --steps 2 --width 32 "
                            "--height 32 --out " +
                            (tmp.path() / "out").string() + " 2>&1 >/dev/null | cat");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::regex progress_line(
      R"(record: progress (\d+)/10 episodes \((\d+)%\), (\d+)/30 frames( \(\d+ of episodes still running\))?, [0-9.]+ frames/s, ETA (\d+ s|unknown|finishing))");
  int lines = 0, last_done = 0;
  for (const std::string& line : Lines(r.output)) {
    std::smatch m;
    if (!std::regex_match(line, m, progress_line)) continue;
    ++lines;
    const int done = std::stoi(m[1]);
    EXPECT_GE(done, last_done) << line;
    EXPECT_EQ(std::stoi(m[2]), done * 10) << line;
    EXPECT_GE(std::stoi(m[3]), done * 3) << line;
    last_done = done;
  }
  // one line per 10% of 10 episodes (a 30 s line could add one on a very slow machine)
  EXPECT_GE(lines, 10) << r.output;
  EXPECT_EQ(last_done, 10) << r.output;
  EXPECT_EQ(r.output.find('\r'), std::string::npos) << "terminal bar in a pipe";
  EXPECT_NE(r.output.find("record: 10 episode(s)"), std::string::npos) << r.output;
}

// An episode that makes no frames for a while (an exec: policy thinking 3 s over step 1) still
// shows the run is alive in a batch log: with FETCHSCOPE_PROGRESS_INTERVAL=1 the scheduler's
// heartbeat prints lines while the frame count stands still, in-process (--jobs 1) and with
// worker processes (--jobs 2).
TEST(ProgressInAPipeTest, ALongStepStillPrintsProgressLines) {
  unsetenv("DISPLAY");
  TempDir tmp;
  const std::string policy =
      "exec:python3 -c \"import sys,time\nfor i,l in enumerate(sys.stdin):\n"
      "  time.sleep(3 if i==1 else 0); print('[0,0,0,0]', flush=True)\"";
  for (const char* jobs : {"1", "2"}) {
    SCOPED_TRACE(std::string("--jobs ") + jobs);
    const auto r = RunCommand(
        "FETCHSCOPE_PROGRESS_INTERVAL=1 " + std::string(FETCHSCOPE_BIN) +
        " record --env-id FetchReach-v4 --episodes 2 --steps 3 --width 32 --height 32 --jobs " +
        jobs + " --policy '" + policy + "' --out " + (tmp.path() / jobs).string() +
        " 2>&1 >/dev/null | cat");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    // lines printed while no episode was done yet: the heartbeat's (the 10% lines need one)
    int stalled = 0;
    for (const std::string& line : Lines(r.output)) {
      if (line.find("record: progress 0/2 episodes") != std::string::npos) ++stalled;
    }
    EXPECT_GE(stalled, 2) << r.output;
  }
  const auto bad = RunCommand("FETCHSCOPE_PROGRESS_INTERVAL=soon " + std::string(FETCHSCOPE_BIN) +
                              " record --episodes 1 --steps 1 --width 32 --height 32 --out " +
                              (tmp.path() / "bad").string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("FETCHSCOPE_PROGRESS_INTERVAL 'soon'"), std::string::npos)
      << bad.output;
  EXPECT_FALSE(fs::exists(tmp.path() / "bad"));
}

// Counts a reader can trust (issue 36): percentages that never round a shortfall up to 100%,
// frames of episodes still running said as such, "ETA 0 s" only when nothing is left.
TEST(ProgressCounts, PercentagesNeverRoundAShortfallUpOrAPartDown) {
  EXPECT_EQ(PercentText(997, 1000), "99.7%");
  EXPECT_EQ(PercentText(9999, 10000), "99.9%");
  EXPECT_EQ(PercentText(1000, 1000), "100%");
  EXPECT_EQ(PercentText(1, 10000), "0.1%");
  EXPECT_EQ(PercentText(0, 3), "0%");
  EXPECT_EQ(PercentText(1, 3), "33.3%");
  EXPECT_EQ(PercentText(2, 3), "66.7%");
  EXPECT_EQ(PercentText(3, 4), "75%");
  EXPECT_EQ(PercentText(0, 0), "100%");
}

TEST(ProgressCounts, FramesInFlightAndTheLastEpisodesEncodingAreSaidAsSuch) {
  std::FILE* out = std::tmpfile();
  ASSERT_NE(out, nullptr);
  double now = 0;
  ProgressReporter::Options o;
  o.episodes = 3;
  o.frames_per_episode = 51;
  o.log_percent_step = 1;
  o.out = out;
  ProgressReporter progress(o, [&] { return now; });
  // episode 0 done while episode 1 made its first frame: 52 frames, one of them in flight
  now = 1;
  progress.Frames(52);
  progress.EpisodeDone();
  std::vector<std::string> lines = Lines(Contents(out));
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0],
            "record: progress 1/3 episodes (33.3%), 52/153 frames (1 of episodes still running), "
            "52.0 frames/s, ETA 2 s");
  // every frame made, the last two episodes still encoding: not "ETA 0 s"
  now = 3;
  progress.Frames(101);
  progress.EpisodeDone();
  lines = Lines(Contents(out));
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_NE(lines[1].find("2/3 episodes (66.7%), 153/153 frames (51 of episodes still running)"),
            std::string::npos)
      << lines[1];
  EXPECT_NE(lines[1].find("ETA finishing"), std::string::npos) << lines[1];
  now = 4;
  progress.EpisodeDone();
  lines = Lines(Contents(out));
  EXPECT_NE(lines.back().find("3/3 episodes (100%), 153/153 frames, "), std::string::npos)
      << lines.back();
  EXPECT_NE(lines.back().find("ETA 0 s"), std::string::npos) << lines.back();
  std::fclose(out);
}

// Every printed line checked against the run's own numbers: the refusal counts the episode
// files only (not index.html), a Ctrl-C'd episode is never counted done, and rollout, whose
// JSON is on stdout, prints its progress on stderr in a long run (here every 0.2 s).
TEST(ProgressCounts, LinesAgreeWithTheRunsOwnNumbers) {
  unsetenv("DISPLAY");
  TempDir tmp;
  const std::string out = (tmp.path() / "two").string();
  const std::string record = std::string(FETCHSCOPE_BIN) +
                             " record --env-id FetchReach-v4 --episodes 2 --steps 3 --width 32 "
                             "--height 32 --quiet --out " +
                             out;
  ASSERT_EQ(RunCommand(record).exit_code, 0);
  const auto again = RunCommand(record);
  EXPECT_EQ(again.exit_code, 2);
  // 2 episodes: a video, a sheet and a trajectory each
  EXPECT_NE(again.output.find("(manifest.json and 6 episode files)"), std::string::npos)
      << again.output;

  const auto rollout = RunCommand(
      "FETCHSCOPE_PROGRESS_INTERVAL=0.2 " + std::string(FETCHSCOPE_BIN) +
      " rollout --env-id FetchPush-v4 --episodes 150 2>" + (tmp.path() / "err").string() +
      " | python3 -c 'import json, sys; print(len(json.load(sys.stdin)[\"episodes\"]))'");
  ASSERT_EQ(rollout.exit_code, 0) << rollout.output;
  EXPECT_EQ(rollout.output, "150\n") << "stdout holds the JSON alone";
  const std::regex line(
      R"(rollout: progress (\d+)/150 episodes \(([0-9.]+)%\), (\d+)/7500 steps, [0-9.]+ steps/s, ETA (\d+ s|unknown|finishing))");
  int seen = 0;
  for (const std::string& text : Lines(testing::ReadFile(tmp.path() / "err"))) {
    std::smatch m;
    if (!std::regex_match(text, m, line)) continue;
    ++seen;
    const int done = std::stoi(m[1]);
    EXPECT_EQ(std::stoi(m[3]), done * 50) << text;  // whole episodes only: no steps in flight
  }
  EXPECT_GE(seen, 1) << testing::ReadFile(tmp.path() / "err");
}

}  // namespace
}  // namespace fetchscope
