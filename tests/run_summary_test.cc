// What a run says it holds (run/run_summary.h): an interrupted run's summary and report count
// alike and name --resume, --resume summarises the whole run and says a whole run is whole.
#include "run/run_summary.h"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <thread>
#include <utility>

#include "inspect/report.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::AllFiles;
using testing::ReadFile;
using testing::RunFetchscope;
using testing::SpawnFetchscope;
using testing::TempDir;
using testing::WaitExit;
namespace fs = std::filesystem;

const std::string kSmall =
    "record --quiet --env-id FetchPush-v4 --width 32 --height 32 --steps 5 --policy random ";

class RunSafetyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    unsetenv("DISPLAY");
    for (const char* name : {"SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"}) unsetenv(name);
  }
};

// {successes, complete} from the summary's "success S/C complete"; {-1, -1} when absent.
std::pair<int, int> SummarySuccess(const std::string& output) {
  std::smatch m;
  if (!std::regex_search(output, m, std::regex("success (\\d+)/(\\d+) complete"))) return {-1, -1};
  return {std::stoi(m[1]), std::stoi(m[2])};
}

TEST_F(RunSafetyTest, InterruptedRunSummaryAndReportAgreeAndResumeCountsTheWholeRun) {
  TempDir tmp;
  const fs::path out = tmp.path() / "run", log = tmp.path() / "log";
  const std::string run =
      "record --env-id FetchPickAndPlace-v4 --width 48 --height 48 --policy random --seed 7 "
      "--out " +
      out.string();
  const pid_t pid = SpawnFetchscope(run + " --episodes 12", log);
  for (int i = 0; i < 1200 && !fs::exists(out / "episode_002.json"); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(150));  // into the next episode
  kill(pid, SIGINT);
  ASSERT_EQ(WaitExit(pid), 130) << ReadFile(log);
  const std::string output = ReadFile(log);
  const RecordedRun recorded = ReadRunFolder(out.string());
  ASSERT_TRUE(recorded.manifest.interrupted) << output;
  const nlohmann::json report = ReportData(recorded);
  const nlohmann::json& s = report["summary"];
  // the one rule: the rate over the complete episodes, the incomplete apart, in both
  const auto [successes, complete] = SummarySuccess(output);
  EXPECT_EQ(successes, s["successes"].get<int>()) << output;
  EXPECT_EQ(complete, s["complete"].get<int>()) << output;
  const int incomplete = s["incomplete"].get<int>();
  EXPECT_EQ(output.find(std::to_string(incomplete) + " incomplete") != std::string::npos,
            incomplete > 0)
      << output;
  // both name the command that finishes the run
  const std::string resume = ResumeCommand(recorded.manifest.command_line);
  EXPECT_NE(resume.find(" --resume"), std::string::npos);
  EXPECT_NE(output.find("to record the rest, run: " + resume), std::string::npos) << output;
  ASSERT_FALSE(report["notes"].empty());
  EXPECT_NE(report["notes"][0].get<std::string>().find("run: " + resume), std::string::npos)
      << report["notes"].dump();

  // --resume counts the whole run: the kept episodes too, and it extends the run to 14
  auto r = RunFetchscope(run + " --resume --episodes 14");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto [all_successes, all_complete] = SummarySuccess(r.output);
  EXPECT_EQ(all_complete, 14) << r.output;
  EXPECT_NE(r.output.find(" kept by --resume"), std::string::npos) << r.output;
  const nlohmann::json after = ReportData(ReadRunFolder(out.string()))["summary"];
  EXPECT_EQ(after["complete"], 14);
  EXPECT_EQ(after["successes"].get<int>(), all_successes);
  EXPECT_EQ(r.output.find("to record the rest"), std::string::npos) << r.output;

  // a whole run: said so, summarised, left as it is
  const auto whole = AllFiles(out);
  r = RunFetchscope(run + " --resume --episodes 14");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("record: --out '" + out.string() +
                          "' already holds the whole run (14 episode(s)): nothing to record; "
                          "success " +
                          std::to_string(all_successes) + "/14 complete"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("0 episode(s)"), std::string::npos) << r.output;
  EXPECT_TRUE(AllFiles(out) == whole);
}

// --resume of a finished run records nothing, says the run is whole and summarises it, and
// leaves every file as it was.
TEST_F(RunSafetyTest, ResumeOfAFinishedRunSaysItIsWhole) {
  TempDir tmp;
  const fs::path out = tmp.path() / "run";
  const std::string run =
      "record --env-id FetchPush-v4 --width 32 --height 32 --steps 5 --seed 2 --episodes 3 --out " +
      out.string();
  auto r = RunFetchscope(run);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto [successes, complete] = SummarySuccess(r.output);
  ASSERT_EQ(complete, 3) << r.output;
  const auto before = AllFiles(out);
  r = RunFetchscope(run + " --resume");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, "record: --out '" + out.string() +
                          "' already holds the whole run (3 episode(s)): nothing to record; "
                          "success " +
                          std::to_string(successes) + "/3 complete\n");
  EXPECT_TRUE(AllFiles(out) == before);
}

TEST(ResumeCommand, DropsOverwriteAndAddsResumeOnce) {
  EXPECT_EQ(ResumeCommand("fetchscope record --episodes 3 --overwrite --out x"),
            "fetchscope record --episodes 3 --out x --resume");
  EXPECT_EQ(ResumeCommand("fetchscope record --resume --out x"),
            "fetchscope record --resume --out x");
}

}  // namespace
}  // namespace fetchscope
