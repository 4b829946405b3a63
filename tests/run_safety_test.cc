// record never loses the user's files and says what a run holds (issue 19): --out may not be the
// run that --from replays (symlinks resolved); --overwrite removes only what fetchscope wrote; an
// --out nothing can be written in is refused before anything is rendered; an interrupted run's
// summary and report count alike and name --resume; --resume summarises the whole run, says a
// whole run is whole, and extends a run to a larger --episodes byte for byte.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <thread>

#include "inspect/report.h"
#include "run/run_summary.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::EpisodeFiles;
using testing::ReadFile;
using testing::RunFetchscope;
using testing::SpawnFetchscope;
using testing::TempDir;
using testing::WaitExit;
namespace fs = std::filesystem;

const std::string kSmall =
    "record --quiet --env-id FetchPush-v4 --width 32 --height 32 --steps 5 --policy random ";

void WriteText(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// Every file in `dir` (not below it), by name, with its bytes.
std::map<std::string, std::string> AllFiles(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.is_regular_file()) files[e.path().filename().string()] = ReadFile(e.path());
  }
  return files;
}

class RunSafetyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    unsetenv("DISPLAY");
    for (const char* name : {"SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"}) unsetenv(name);
  }
};

// --- 1. --out is --from: refused, by path or through a symlink, before anything changes

TEST_F(RunSafetyTest, OutThatIsTheFromRunIsRefusedThroughSymlinksToo) {
  TempDir tmp;
  const fs::path run = tmp.path() / "run", alias = tmp.path() / "alias";
  auto r = RunFetchscope(kSmall + "--episodes 2 --seed 3 --out " + run.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  fs::create_directory_symlink(run, alias);
  const auto before = AllFiles(run);
  for (const auto& [from, out] : std::vector<std::pair<fs::path, fs::path>>{
           {run, run}, {alias, run}, {run, alias}, {run / ".", alias / ""}}) {
    SCOPED_TRACE(from.string() + " -> " + out.string());
    r = RunFetchscope("record --quiet --from " + from.string() + " --out " + out.string() +
                      " --overwrite");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    // one line, naming both as given
    EXPECT_NE(r.output.find("--out '" + out.string() + "' is --from '" + from.string() + "'"),
              std::string::npos)
        << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_TRUE(AllFiles(run) == before) << "the source run changed";
  }
  // a folder inside the source, a source file inside --out: refused alike
  r = RunFetchscope("record --quiet --from " + alias.string() + " --out " + (run / "hd").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("lies inside --from"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(run / "hd"));
  r = RunFetchscope("record --quiet --from " + (alias / "episode_001.json").string() + " --out " +
                    run.string() + " --resume");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("holds --from"), std::string::npos) << r.output;
  EXPECT_TRUE(AllFiles(run) == before) << "the source run changed";
  // another folder is fine
  r = RunFetchscope("record --quiet --from " + alias.string() + " --out " +
                    (tmp.path() / "again").string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

// --- 2. --overwrite removes only the files fetchscope wrote

TEST_F(RunSafetyTest, OverwriteRefusesFilesFetchscopeDidNotWriteAndKeepsThem) {
  TempDir tmp;
  const fs::path run = tmp.path() / "run";
  auto r = RunFetchscope(kSmall + "--episodes 2 --seed 1 --out " + run.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // the user replaced the report with their own page
  WriteText(run / "index.html", "<html><body>my notes</body></html>\n");
  const auto before = AllFiles(run);
  r = RunFetchscope(kSmall + "--episodes 2 --seed 2 --overwrite --out " + run.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("holds index.html, not written by fetchscope"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("move them out of --out"), std::string::npos) << r.output;
  EXPECT_TRUE(AllFiles(run) == before) << "--overwrite touched the folder";
  // `report` does not replace it either
  r = RunFetchscope("report " + run.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("is not a report fetchscope wrote"), std::string::npos) << r.output;
  EXPECT_EQ(ReadFile(run / "index.html"), before.at("index.html"));
  // with --no-report the run leaves the page alone, and records
  r = RunFetchscope(kSmall + "--episodes 2 --seed 2 --overwrite --no-report --out " + run.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(ReadFile(run / "index.html"), before.at("index.html"));
  EXPECT_EQ(nlohmann::json::parse(ReadFile(run / "manifest.json"))["seed"], 2);

  // a web app's manifest.json and episode-like files: listed, a few then "and N more"
  const fs::path web = tmp.path() / "web";
  fs::create_directories(web);
  WriteText(web / "manifest.json", "{\"name\": \"my app\", \"icons\": []}\n");
  for (int k = 0; k < 4; ++k) WriteText(web / ("episode_00" + std::to_string(k) + ".mp4"), "x");
  const auto web_before = AllFiles(web);
  for (const char* mode : {"", "--overwrite ", "--resume "}) {
    r = RunFetchscope(kSmall + "--episodes 1 " + mode + "--out " + web.string());
    EXPECT_EQ(r.exit_code, 2) << mode << r.output;
    EXPECT_NE(r.output.find("holds episode_000.mp4, episode_001.mp4, episode_002.mp4 and 2 more, "
                            "not written by fetchscope"),
              std::string::npos)
        << mode << r.output;
    EXPECT_TRUE(AllFiles(web) == web_before) << mode;
  }
}

// A run killed before its manifest (SIGKILL) left fetchscope's episode files: --overwrite still
// replaces them, since each sits beside its fetchscope trajectory.
TEST_F(RunSafetyTest, OverwriteStillReplacesAKilledRunsEpisodes) {
  TempDir tmp;
  const fs::path run = tmp.path() / "run";
  auto r = RunFetchscope(kSmall + "--episodes 2 --seed 1 --no-report --out " + run.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  fs::remove(run / "manifest.json");
  r = RunFetchscope(kSmall + "--episodes 1 --seed 2 --overwrite --out " + run.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(fs::exists(run / "episode_001.mp4"));
  EXPECT_TRUE(fs::exists(run / "index.html"));
}

// --- 3. an --out nothing can be written in: one line before anything is rendered

TEST_F(RunSafetyTest, UnwritableOutIsRefusedBeforeRendering) {
  // /proc takes no new files, not even root's
  auto r = RunFetchscope(kSmall + "--episodes 1 --out /proc");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--out '/proc' is not writable"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("lost episode"), std::string::npos) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  // a folder under a regular file cannot be made, by anyone
  TempDir tmp;
  WriteText(tmp.path() / "file", "x");
  r = RunFetchscope(kSmall + "--episodes 1 --out " + (tmp.path() / "file" / "run").string());
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("cannot create output folder"), std::string::npos) << r.output;
}

TEST_F(RunSafetyTest, ReadOnlyFolderIsRefusedBeforeRendering) {
  if (geteuid() == 0) GTEST_SKIP() << "root ignores permission bits (see the /proc test)";
  TempDir tmp;
  const fs::path ro = tmp.path() / "ro";
  fs::create_directories(ro);
  chmod(ro.c_str(), 0555);
  auto r = RunFetchscope(kSmall + "--episodes 1 --out " + ro.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("is not writable"), std::string::npos) << r.output;
  // and a folder to be made in it
  r = RunFetchscope(kSmall + "--episodes 1 --out " + (ro / "sub").string());
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("lost episode"), std::string::npos) << r.output;
  chmod(ro.c_str(), 0755);
}

// --- 4. interrupted runs, --resume

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

// --episodes N --resume extends a finished run to N episodes, byte for byte as a fresh run of N;
// fewer than the run has is refused in one line.
TEST_F(RunSafetyTest, ResumeWithMoreEpisodesExtendsTheRunByteForByte) {
  TempDir tmp;
  const fs::path out = tmp.path() / "run", fresh = tmp.path() / "fresh";
  const std::string run = kSmall + "--seed 4 --no-report ";
  auto r = RunFetchscope(run + "--episodes 2 --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunFetchscope(run + "--episodes 4 --resume --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunFetchscope(run + "--episodes 4 --out " + fresh.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto extended = EpisodeFiles(out), expected = EpisodeFiles(fresh);
  ASSERT_EQ(extended.size(), expected.size());
  for (const auto& [name, bytes] : expected) {
    EXPECT_TRUE(extended.at(name) == bytes) << name << " differs after extending";
  }
  const auto m = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  const auto mf = nlohmann::json::parse(ReadFile(fresh / "manifest.json"));
  EXPECT_EQ(m["episodes"], mf["episodes"]);
  EXPECT_EQ(m["parameters"], mf["parameters"]);
  EXPECT_EQ(m["episodes_requested"], 4);
  // fewer: refused, naming both counts
  const auto before = AllFiles(out);
  r = RunFetchscope(run + "--episodes 3 --resume --out " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("with --episodes 3: the run there has 4; pass --episodes 4"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_TRUE(AllFiles(out) == before);
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
