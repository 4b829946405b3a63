// record's --out folder holds one run: a folder with another run's files is refused (exit 2),
// --overwrite replaces that run wholly, --resume continues an interrupted run with the bytes of
// an uninterrupted one, and a run that fails leaves nothing that was not there before; --out may
// not be the run --from replays, --overwrite removes only what fetchscope wrote, and an --out
// nothing can be written in is refused before anything is rendered.
#include "run/run_folder.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "inspect/report.h"
#include "run/run_files.h"
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
using testing::AllFiles;

const std::string kSmall =
    "record --quiet --env-id FetchPush-v4 --width 32 --height 32 --steps 5 --policy random ";

void WriteText(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

std::set<std::string> Names(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

class RunFolderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    unsetenv("DISPLAY");
    for (const char* name : {"SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"}) unsetenv(name);
  }
};

// Which names in a folder are a record run's (and so never the user's).
TEST(RunFileName, NamesRecordWritesAndNothingElse) {
  for (const char* name : {"manifest.json", "manifest_shard_0001_of_0004.json"}) {
    ASSERT_TRUE(ParseRunFileName(name)) << name;
    EXPECT_TRUE(ParseRunFileName(name)->manifest) << name;
  }
  for (const auto& [name, k, hidden] : std::vector<std::tuple<std::string, int, bool>>{
           {"episode_000.mp4", 0, false},
           {"episode_007.webm", 7, false},
           {"episode_008.gif", 8, false},
           {"episode_012_sheet.png", 12, false},
           {"episode_1234.json", 1234, false},
           {"episode_002_depth.mp4", 2, false},
           {"episode_002_segmentation.webm", 2, false},
           {"episode_002_segmentation.gif", 2, false},
           {"episode_002_segmentation_legend.json", 2, false},
           {".episode_003.partial.mp4", 3, true},
           {".episode_003.partial.webm", 3, true},
           {".episode_005_depth.partial.gif", 5, true},
           {".episode_006.partial-4321.mp4", 6, true},
           {".episode_007_depth.partial-12.webm", 7, true},
           {".episode_004.json.tmp-ab12", 4, true},
           {".episode_004_segmentation_legend.json.tmp-1-2", 4, true}}) {
    const auto parsed = ParseRunFileName(name);
    ASSERT_TRUE(parsed) << name;
    EXPECT_EQ(parsed->episode, k) << name;
    EXPECT_EQ(parsed->hidden, hidden) << name;
    EXPECT_FALSE(parsed->manifest || parsed->report) << name;
  }
  // the run's report, written by record and `fetchscope report`
  for (const char* name : {"index.html", ".index.html.tmp-123-4"}) {
    ASSERT_TRUE(ParseRunFileName(name)) << name;
    EXPECT_TRUE(ParseRunFileName(name)->report) << name;
    EXPECT_EQ(ParseRunFileName(name)->episode, -1) << name;
  }
  for (const char* name :
       {"notes.txt", "episode_x.mp4", "episode_001.txt", "my_manifest.json", "episode_.json",
        ".hidden", "results.json", "episode_001_depth.png", "episode_001_normals.mp4",
        "episode_001.mkv", "index.htm", "episode_001_legend.json", ".manifest.replaced-12"}) {
    EXPECT_FALSE(ParseRunFileName(name)) << name;
  }
}

TEST_F(RunFolderTest, AFolderHoldingARunIsRefused) {
  TempDir tmp;
  const fs::path out = tmp.path() / "run";
  auto r = RunFetchscope(kSmall + "--episodes 2 --seed 1 --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto before = EpisodeFiles(out);
  const std::string manifest = ReadFile(out / "manifest.json");
  for (const char* seed : {"1", "2"}) {  // the same command, or another run
    r = RunFetchscope(kSmall + "--episodes 2 --seed " + seed + " --out " + out.string());
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("already holds a record run"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("--overwrite"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("--resume"), std::string::npos) << r.output;
    EXPECT_TRUE(EpisodeFiles(out) == before);
    EXPECT_EQ(ReadFile(out / "manifest.json"), manifest);
  }
  // episode files without a manifest (a run killed with SIGKILL) are another run's too
  fs::remove(out / "manifest.json");
  r = RunFetchscope(kSmall + "--episodes 2 --seed 1 --out " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("without its manifest"), std::string::npos) << r.output;
  // a folder with only the user's own files is fine, and they stay
  const fs::path mine = tmp.path() / "mine";
  fs::create_directories(mine);
  WriteText(mine / "notes.txt", "mine");
  r = RunFetchscope(kSmall + "--episodes 1 --out " + mine.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(ReadFile(mine / "notes.txt"), "mine");
}

TEST_F(RunFolderTest, OverwriteReplacesTheRunWholly) {
  TempDir tmp;
  const fs::path out = tmp.path() / "run", fresh = tmp.path() / "fresh";
  auto r = RunFetchscope(kSmall + "--episodes 3 --seed 1 --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  WriteText(out / "notes.txt", "mine");
  r = RunFetchscope(kSmall + "--episodes 2 --seed 2 --overwrite --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunFetchscope(kSmall + "--episodes 2 --seed 2 --out " + fresh.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto files = EpisodeFiles(out);
  EXPECT_EQ(files.size(), 6u);  // episode 2 of the earlier run is gone
  EXPECT_TRUE(files == EpisodeFiles(fresh)) << "--overwrite differs from a fresh run";
  EXPECT_EQ(ReadFile(out / "notes.txt"), "mine");
  EXPECT_EQ(nlohmann::json::parse(ReadFile(out / "manifest.json"))["seed"], 2);
  r = RunFetchscope(kSmall + "--episodes 2 --overwrite --resume --out " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
}

// Every file record and its report write belongs to the run: --overwrite leaves none of the
// earlier run's behind (its report, its layer videos and legends), and the user's stay.
TEST_F(RunFolderTest, OverwriteLeavesNoFileOfTheEarlierRun) {
  TempDir tmp;
  const fs::path out = tmp.path() / "a" / "run1";
  auto r = RunFetchscope(kSmall +
                         "--episodes 2 --seed 1 --layers rgb,segmentation,depth "
                         "--format mp4,gif --out " +
                         out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_TRUE(fs::exists(out / "index.html"));
  ASSERT_TRUE(fs::exists(out / "episode_001_segmentation_legend.json"));
  WriteText(out / "notes.txt", "mine");
  r = RunFetchscope(kSmall + "--episodes 1 --seed 2 --overwrite --no-report --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(Names(out),
            (std::set<std::string>{"episode_000.json", "episode_000.mp4", "episode_000_sheet.png",
                                   "manifest.json", "notes.txt"}));
  EXPECT_EQ(nlohmann::json::parse(ReadFile(out / "manifest.json"))["seed"], 2);
}

// --overwrite keeps the earlier run until the new one has its manifest: a new run that fails,
// or is interrupted before it has a whole episode, leaves the earlier run as it was.
TEST_F(RunFolderTest, OverwriteThatFailsKeepsTheEarlierRun) {
  TempDir tmp;
  const fs::path out = tmp.path() / "run";
  auto r = RunFetchscope(kSmall + "--episodes 2 --seed 1 --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  WriteText(out / "notes.txt", "mine");
  std::map<std::string, std::string> before;
  for (const std::string& name : Names(out)) before[name] = ReadFile(out / name);
  auto unchanged = [&](const std::string& what) {
    EXPECT_EQ(Names(out).size(), before.size()) << what;
    for (const auto& [name, bytes] : before) {
      EXPECT_TRUE(ReadFile(out / name) == bytes) << what << ": " << name;
    }
  };

  const std::string base =
      "record --quiet --env-id FetchPush-v4 --width 32 --height 32 --steps 5 --overwrite ";
  r = RunFetchscope(base +
                    "--episodes 1 --seed 2 --policy \"exec:read l; exit 3\" "
                    "--out " +
                    out.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  unchanged("a failing policy");

  // SIGINT once the earlier run is set aside, while the slow policy's first episode runs
  const pid_t pid =
      SpawnFetchscope(base +
                          "--episodes 1 --seed 3 --policy "
                          "'exec:while read l; do sleep 0.5; echo 0 0 0 0; done' --out " +
                          out.string(),
                      tmp.path() / "log");
  auto aside = [&] {
    for (const auto& e : fs::directory_iterator(out)) {
      if (e.path().filename().string().rfind(".manifest.replaced-", 0) == 0) return true;
    }
    return false;
  };
  for (int i = 0; i < 1200 && !aside(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_TRUE(aside()) << ReadFile(tmp.path() / "log");
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  kill(pid, SIGINT);
  EXPECT_EQ(WaitExit(pid), 130) << ReadFile(tmp.path() / "log");
  unchanged("SIGINT before an episode was complete");

  // a run killed outright leaves the set-aside folder: named by the next run, not lost
  fs::create_directories(out / ".manifest.replaced-99999");
  WriteText(out / ".manifest.replaced-99999" / "manifest.json", "{}");
  r = RunFetchscope(kSmall + "--episodes 2 --seed 1 --resume --out " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(".manifest.replaced-99999"), std::string::npos) << r.output;
  r = RunFetchscope(kSmall + "--episodes 1 --seed 4 --overwrite --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(fs::exists(out / ".manifest.replaced-99999"));
  EXPECT_EQ(Names(out),
            (std::set<std::string>{"episode_000.json", "episode_000.mp4", "episode_000_sheet.png",
                                   "index.html", "manifest.json", "notes.txt"}));
}

// --resume of a folder that does not exist (a requeued job that never started) records the
// whole run, and says so in one line.
TEST_F(RunFolderTest, ResumeWithNothingToResumeSaysSo) {
  TempDir tmp;
  const fs::path out = tmp.path() / "never";
  auto r = RunFetchscope(
      "record --env-id FetchPush-v4 --width 32 --height 32 --steps 5 --episodes 1 --no-report "
      "--resume --out " +
      out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("fetchscope: note: --resume: --out '" + out.string() +
                          "' holds no manifest.json: nothing to resume, recording the whole run\n"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(nlohmann::json::parse(ReadFile(out / "manifest.json"))["resumed"], false);
  EXPECT_TRUE(fs::exists(out / "episode_000.mp4"));
}

// Interrupt a run with SIGINT, --resume it (with other --jobs): the episode files are those of
// an uninterrupted run, byte for byte. The random policy's generator runs across episodes, so
// the resumed run must position it as if the run had never stopped.
TEST_F(RunFolderTest, ResumeAfterSigintGivesTheBytesOfAnUninterruptedRun) {
  TempDir tmp;
  const std::string run =
      "record --quiet --env-id FetchPickAndPlace-v4 --width 32 --height 32 "
      "--policy random --seed 7 --episodes 12 ";
  const fs::path whole = tmp.path() / "whole", out = tmp.path() / "run";
  auto r = RunFetchscope(run + "--out " + whole.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;

  const pid_t pid = SpawnFetchscope(run + "--out " + out.string(), tmp.path() / "log");
  for (int i = 0; i < 1200 && !fs::exists(out / "episode_002.json"); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  kill(pid, SIGINT);
  ASSERT_EQ(WaitExit(pid), 130) << ReadFile(tmp.path() / "log");
  const auto m = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  ASSERT_EQ(m["interrupted"], true);
  ASSERT_LT(m["episodes"].size(), 12u) << "the run ended before the signal";
  const auto& last = m["episodes"].back();
  EXPECT_EQ(last["complete"].get<bool>(), last["steps"].get<int>() == 50);

  // other parameters are refused, naming the first that differs
  r = RunFetchscope(run + "--steps 49 --resume --out " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--steps is 50 there and 49 here"), std::string::npos) << r.output;

  r = RunFetchscope(run + "--resume --jobs 2 --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto resumed = EpisodeFiles(out);
  const auto expected = EpisodeFiles(whole);
  ASSERT_EQ(resumed.size(), expected.size());
  for (const auto& [name, bytes] : expected) {
    EXPECT_TRUE(resumed.at(name) == bytes) << name << " differs after --resume";
  }
  const auto m2 = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  EXPECT_EQ(m2["interrupted"], false);
  EXPECT_EQ(m2["resumed"], true);
  const auto mw = nlohmann::json::parse(ReadFile(whole / "manifest.json"));
  EXPECT_EQ(m2["episodes"], mw["episodes"]);
  // resuming a finished run records nothing more
  r = RunFetchscope(run + "--resume --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(EpisodeFiles(out) == expected);
}

// merge-manifests counts an episode marked incomplete as missing, whatever its step count.
TEST_F(RunFolderTest, MergeManifestsTreatsIncompleteEpisodesAsMissing) {
  TempDir tmp;
  const fs::path out = tmp.path() / "run";
  auto r = RunFetchscope(kSmall + "--episodes 2 --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto m = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  EXPECT_EQ(m["episodes"][1]["complete"], true);
  m["episodes"][1]["complete"] = false;
  WriteText(out / "manifest.json", m.dump());
  r = RunFetchscope("merge-manifests --quiet --out " + (tmp.path() / "merged.json").string() + " " +
                    out.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("lacks episodes 1"), std::string::npos) << r.output;
}

// Run-time failures (a policy that crashes, one that hangs, an encoder that is not there)
// leave nothing: neither the folders this run made nor files in a folder that was there.
TEST_F(RunFolderTest, AFailedRunLeavesNothingBehind) {
  TempDir tmp;
  const std::string exec_run =
      "record --quiet --env-id FetchReach-v4 --width 32 --height 32 "
      "--steps 5 --episodes 3 ";
  for (const std::string& failing :
       {std::string("--policy \"exec:read l; echo 0 0 0 0; read l; exit 3\""),
        std::string("--exec-timeout 0.3 --policy \"exec:sleep 30\""),
        std::string("--policy random --codec h264_nvenc")}) {
    SCOPED_TRACE(failing);
    const fs::path nested = tmp.path() / "new" / "deeper" / "run";
    auto r = RunFetchscope(exec_run + failing + " --out " + nested.string());
    if (r.exit_code == 0 && failing.find("nvenc") != std::string::npos) {
      fs::remove_all(tmp.path() / "new");  // this machine has NVENC: nothing fails
      continue;
    }
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_FALSE(fs::exists(tmp.path() / "new")) << r.output;

    const fs::path existing = tmp.path() / "existing";
    fs::create_directories(existing);
    WriteText(existing / "notes.txt", "mine");
    r = RunFetchscope(exec_run + failing + " --out " + existing.string());
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_EQ(Names(existing), std::set<std::string>{"notes.txt"}) << r.output;
  }
}

class RunSafetyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    unsetenv("DISPLAY");
    for (const char* name : {"SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"}) unsetenv(name);
  }
};

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

}  // namespace
}  // namespace fetchscope
