// A real Slurm: Debian's slurm-wlm and munge, one node, everything under a temp folder
// (tests/slurm/local_cluster.sh starts munged, slurmctld and slurmd and stops them by PID). The
// test submits the committed scripts the cluster guide shows (examples/slurm/record.sbatch and
// merge.sbatch, as they are) the way docs/guide/clusters.md tells a user to, and checks that each
// merged run is byte-identical to an unsharded one:
//   - a 4-task array, with its merge submitted at once (afterany);
//   - a task cancelled (scancel) while it writes, then requeued (scontrol requeue);
//   - a task SIGKILLed while it writes, an early merge refused naming it, then only its index
//     resubmitted (--array=1) and the merge submitted again.
// Skips, saying so, where the packages are absent or the test is not root (CI installs them:
// tools/install-deps.sh --ci).
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <regex>
#include <string>
#include <thread>

#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::CommandResult;
using testing::EpisodeFiles;
using testing::PythonWithH5py;
using testing::ReadFile;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::SourceDir;
using testing::TempDir;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The record options of every run here: small and quick.
const std::string kOptions =
    "--env-id FetchPush-v4 --policy random --seed 3 --steps 4 --width 64 --height 48 --msaa 0 "
    "--backend osmesa --episodes 8 --jobs 1";

// The sbatch lines the guide shows (docs/guide/clusters.md: `jobid=$(sbatch --parsable
// --array=0-3 examples/slurm/record.sbatch OUT ...)` and `sbatch --dependency=afterany:$jobid
// examples/slurm/merge.sbatch OUT`), run with this test's OUT and options in place of the
// guide's: the scripts they name are the committed ones.
struct GuideLines {
  std::string record;  // sbatch --array=0-3 examples/slurm/record.sbatch
  std::string merge;   // sbatch --dependency=afterany:... examples/slurm/merge.sbatch
};

class SlurmTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (geteuid() != 0) GTEST_SKIP() << "the Slurm test runs slurmctld as root; not root here";
    const CommandResult which = RunCommand(
        "PATH=$PATH:/usr/sbin; command -v munged && command -v slurmctld && "
        "command -v slurmd && command -v sbatch");
    if (which.exit_code != 0) {
      GTEST_SKIP() << "Slurm is not installed (Debian: slurm-wlm and munge, which "
                      "tools/install-deps.sh --ci installs); the Slurm test is skipped";
    }
    for (const char* name :
         {"SLURM_ARRAY_TASK_ID", "SLURM_ARRAY_TASK_COUNT", "SLURM_JOB_ID", "JOB_COMPLETION_INDEX",
          "FETCHSCOPE_TEST_KILL_AT", "FETCHSCOPE_TEST_KILL_HOW", "FETCHSCOPE_TEST_KILL_IF",
          "FETCHSCOPE_LOG_DIR"}) {
      unsetenv(name);
    }
    tmp_ = std::make_unique<TempDir>();
    const fs::path cluster = tmp_->path() / "slurm";
    fs::create_directories(cluster);
    const auto t0 = Clock::now();
    const CommandResult r = RunCommand((SourceDir() / "tests/slurm/local_cluster.sh").string() +
                                       " start " + cluster.string());
    started_ = true;  // stopped in TearDown whatever happened
    cluster_ = cluster;
    ASSERT_EQ(r.exit_code, 0) << r.output;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(r.output, m, std::regex("SLURM_CONF=(\\S+)"))) << r.output;
    setenv("SLURM_CONF", m[1].str().c_str(), 1);
    std::printf("slurm: munged, slurmctld and slurmd up, node idle, in %.2f s\n", Since(t0));
    // fetchscope from PATH, as on a cluster (the jobs inherit the submitting environment)
    const fs::path bin = tmp_->path() / "bin";
    fs::create_directories(bin);
    fs::create_symlink(FETCHSCOPE_BIN, bin / "fetchscope");
    const char* path = std::getenv("PATH");
    setenv("PATH", (bin.string() + ":/usr/sbin:" + (path ? path : "/usr/bin:/bin")).c_str(), 1);
    work_ = tmp_->path() / "work";  // where sbatch runs: the logs go to work/fetchscope-logs
    fs::create_directories(work_);
    fs::create_symlink(SourceDir() / "examples", work_ / "examples");
    guide_ = ReadGuideLines();
    run_start_ = Clock::now();
  }

  void TearDown() override {
    if (started_) {
      std::printf("slurm: test ran %.1f s\n", Since(run_start_));
      RunCommand((SourceDir() / "tests/slurm/local_cluster.sh").string() + " stop " +
                 cluster_.string());
    }
  }

  // The guide's sbatch lines for a record array and its merge.
  static GuideLines ReadGuideLines() {
    const std::string guide = ReadFile(SourceDir() / "docs/guide/clusters.md");
    GuideLines lines;
    std::smatch m;
    if (std::regex_search(guide, m,
                          std::regex("jobid=\\$\\((sbatch --parsable --array=0-3 "
                                     "examples/slurm/record\\.sbatch [^)\\n]*)\\)"))) {
      lines.record = m[1];
    }
    if (std::regex_search(guide, m,
                          std::regex("\\n(sbatch --dependency=afterany:\\$jobid "
                                     "examples/slurm/merge\\.sbatch [^\\n]*)"))) {
      lines.merge = m[1];
    }
    return lines;
  }

  // `line` from the guide with its OUT (the word after the script) and options replaced.
  static std::string Adapted(const std::string& line, const std::string& out, bool options) {
    const std::regex script("(examples/slurm/(record|merge)\\.sbatch) .*");
    return std::regex_replace(line, script, "$1 " + out + (options ? " " + kOptions : ""));
  }

  // Runs `command` in the work folder; its output, checked for success.
  std::string Shell(const std::string& command) {
    const CommandResult r = RunCommand("cd " + work_.string() + " && " + command);
    EXPECT_EQ(r.exit_code, 0) << command << ": " << r.output;
    return r.output;
  }

  // The job id sbatch printed (--parsable: alone; else "Submitted batch job ID").
  std::string Submit(const std::string& command) {
    const std::string out = Shell(command);
    std::smatch m;
    EXPECT_TRUE(std::regex_search(out, m, std::regex("(\\d+)\\s*$"))) << out;
    return m.empty() ? "0" : m[1].str();
  }

  // Waits until every task of `job` has ended (at most 3 minutes).
  void WaitFor(const std::string& job) {
    const auto t0 = Clock::now();
    const std::regex active(
        "JobState=(PENDING|RUNNING|COMPLETING|CONFIGURING|SUSPENDED|REQUEUE|"
        "SIGNALING|STAGE_OUT|RESIZING)");
    while (Since(t0) < 180) {
      const CommandResult r = RunCommand("scontrol -o show job " + job);
      if (r.exit_code == 0 && !std::regex_search(r.output, active)) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    ADD_FAILURE() << "job " << job << " still queued after 180 s: "
                  << RunCommand("squeue; tail -n 20 " + (cluster_ / "log/*").string()).output;
  }

  // Waits until the node is idle again (at most 60 s): a cancelled or killed task's node cleans
  // up after the task's state is final, and a task started during that can fail at its launch.
  void WaitNodeIdle() {
    const auto t0 = Clock::now();
    while (Since(t0) < 60) {
      if (RunCommand("sinfo -h -o %T").output.find("idle") == 0) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    ADD_FAILURE() << "the node is not idle after 60 s: " << RunCommand("sinfo").output;
  }

  // Requeues task `task` of `job` and lets it start now (Slurm holds a requeued job back for a
  // while); waits until it has ended. A launch that fails on the node (state FAILED before the
  // script wrote a line: Slurm's own, not fetchscope's) is requeued again, at most twice, with
  // what Slurm said about it in the test's output.
  // `expect_in_log`: a pattern the log holds once the requeued script has run.
  void RequeueAndWait(const std::string& job, int task, const std::regex& expect_in_log) {
    const std::string id = job + "_" + std::to_string(task);
    for (int attempt = 0; attempt < 3; ++attempt) {
      WaitNodeIdle();
      Shell("scontrol requeue " + id + " && scontrol update JobId=" + id + " StartTime=now");
      WaitFor(job);
      if (State(id) == "COMPLETED" || std::regex_search(ReadFile(Log(job, task)), expect_in_log)) {
        return;
      }
      std::printf("slurm: requeued %s ended %s before its script ran: %s\n", id.c_str(),
                  State(id).c_str(), RunCommand("scontrol -o show job " + id).output.c_str());
    }
  }

  // The JobState of `job` ("COMPLETED", "CANCELLED"...).
  std::string State(const std::string& job) {
    const CommandResult r = RunCommand("scontrol -o show job " + job);
    std::smatch m;
    return std::regex_search(r.output, m, std::regex("JobState=(\\S+)")) ? m[1].str() : r.output;
  }

  // Waits until `file` holds `text` (at most 2 minutes).
  static bool WaitForText(const fs::path& file, const std::string& text) {
    const auto t0 = Clock::now();
    while (Since(t0) < 120) {
      if (ReadFile(file).find(text) != std::string::npos) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return false;
  }

  fs::path Log(const std::string& job, int task) const {
    return work_ / "fetchscope-logs" / ("record_" + job + "_" + std::to_string(task) + ".log");
  }

  // The merged run in `out` against the unsharded reference.
  void ExpectSameAsUnsharded(const fs::path& out) {
    ASSERT_TRUE(fs::exists(out / "manifest.json")) << out;
    if (reference_.empty()) {
      const fs::path ref = tmp_->path() / "unsharded";
      const CommandResult r =
          RunFetchscope("record --quiet " + kOptions + " --out " + ref.string());
      ASSERT_EQ(r.exit_code, 0) << r.output;
      reference_ = EpisodeFiles(ref);
      ASSERT_EQ(reference_.size(), 8u * 3);
    }
    EXPECT_TRUE(EpisodeFiles(out) == reference_) << out;
  }

  std::unique_ptr<TempDir> tmp_;
  fs::path cluster_, work_;
  bool started_ = false;
  GuideLines guide_;
  Clock::time_point run_start_;
  std::map<std::string, std::string> reference_;
};

// The guide's recipe as it stands: a 4-task array and its merge, submitted together.
TEST_F(SlurmTest, ArrayAndMergeAsTheGuideShows) {
  ASSERT_FALSE(guide_.record.empty()) << "docs/guide/clusters.md shows no record array line";
  ASSERT_FALSE(guide_.merge.empty()) << "docs/guide/clusters.md shows no afterany merge line";
  const fs::path out = tmp_->path() / "run";
  const std::string job = Submit(Adapted(guide_.record, out.string(), true));
  const std::string merge = Submit(
      std::regex_replace(Adapted(guide_.merge, out.string(), false), std::regex("\\$jobid"), job));
  WaitFor(merge);
  for (int task = 0; task < 4; ++task) {
    EXPECT_EQ(State(job + "_" + std::to_string(task)), "COMPLETED") << ReadFile(Log(job, task));
  }
  EXPECT_EQ(State(merge), "COMPLETED")
      << ReadFile(work_ / "fetchscope-logs" / ("merge_" + merge + ".log"));
  ExpectSameAsUnsharded(out);
}

// The guide's pixel-dataset recipe: a 4-task array of dataset.sbatch and its dataset-merge.sbatch
// give the dataset of the unsharded run.
TEST_F(SlurmTest, PixelDatasetArrayAndMergeAsTheGuideShows) {
  const std::string guide = ReadFile(SourceDir() / "docs/guide/clusters.md");
  std::smatch array, merge;
  ASSERT_TRUE(std::regex_search(
      guide, array,
      std::regex("jobid=\\$\\((sbatch --parsable --array=0-3 examples/slurm/dataset\\.sbatch "
                 "([^ ]+) ([^)\\n]*))\\)")))
      << "docs/guide/clusters.md shows no dataset array line";
  ASSERT_TRUE(std::regex_search(guide, merge,
                                std::regex("\\n(sbatch --dependency=afterany:\\$jobid "
                                           "examples/slurm/dataset-merge\\.sbatch [^\\n]*)")))
      << "docs/guide/clusters.md shows no dataset merge line";
  const fs::path root = tmp_->path() / "datasets";
  const std::string env = "env MINARI_DATASETS_PATH=" + root.string() + " ";
  const std::string job = Submit(env + array[1].str());
  const std::string merged =
      Submit(env + std::regex_replace(merge[1].str(), std::regex("\\$jobid"), job));
  WaitFor(merged);
  for (int task = 0; task < 4; ++task) {
    EXPECT_EQ(State(job + "_" + std::to_string(task)), "COMPLETED") << ReadFile(
        work_ / "fetchscope-logs" / ("dataset_" + job + "_" + std::to_string(task) + ".log"));
  }
  EXPECT_EQ(State(merged), "COMPLETED")
      << ReadFile(work_ / "fetchscope-logs" / ("dataset-merge_" + merged + ".log"));
  const std::string id = array[2].str();
  const auto r = RunFetchscope("rollout " + array[3].str() + " --minari-root " + root.string() +
                               " --minari " + id.substr(0, id.rfind("-v")) + "-whole-v0");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string py = PythonWithH5py();
  if (py.empty()) return;  // the merge ran; comparing needs h5py
  const auto same = RunCommand(
      py + " " + (SourceDir() / "tests/pixel/same_hdf5.py").string() + " " +
      (root / id / "data/main_data.hdf5").string() + " " +
      (root / (id.substr(0, id.rfind("-v")) + "-whole-v0") / "data/main_data.hdf5").string() +
      " 2>&1");
  EXPECT_EQ(same.exit_code, 0) << same.output;
}

// scancel while task 2 writes (it waits at a kill point until the signal comes): the log says how
// to record the rest; scontrol requeue runs the same script again, which resumes.
TEST_F(SlurmTest, CancelledTaskRequeuedResumes) {
  const fs::path out = tmp_->path() / "run";
  const std::string job = Submit(
      "env FETCHSCOPE_TEST_KILL_AT=4 FETCHSCOPE_TEST_KILL_HOW=pause "
      "FETCHSCOPE_TEST_KILL_IF=SLURM_ARRAY_TASK_ID=2,SLURM_RESTART_COUNT= " +
      Adapted(guide_.record, out.string(), true));
  ASSERT_TRUE(WaitForText(Log(job, 2), "paused at kill point")) << ReadFile(Log(job, 2));
  Shell("scancel " + job + "_2");
  WaitFor(job);
  EXPECT_EQ(State(job + "_2"), "CANCELLED");
  EXPECT_NE(ReadFile(Log(job, 2)).find("to record the rest, run:"), std::string::npos)
      << ReadFile(Log(job, 2));
  // requeued: Slurm holds it for a while (BeginTime); the test lets it start now
  // a later attempt ran the script (the second, or a third where the second failed at its launch
  // and RequeueAndWait requeued it again)
  const std::regex rerun("attempt [2-9]");
  RequeueAndWait(job, 2, rerun);
  EXPECT_EQ(State(job + "_2"), "COMPLETED") << ReadFile(Log(job, 2));
  EXPECT_TRUE(std::regex_search(ReadFile(Log(job, 2)), rerun)) << ReadFile(Log(job, 2));
  WaitNodeIdle();
  const std::string merge = Submit(Adapted(
      std::regex_replace(guide_.merge, std::regex("--dependency=\\S+ "), ""), out.string(), false));
  WaitFor(merge);
  ExpectSameAsUnsharded(out);
}

// Task 1 SIGKILLed while it writes (a node failure, the OOM killer): it leaves files and no
// manifest. The merge refuses, naming the missing shard; resubmitting only index 1 records shard
// 1/4 (the count comes from the other shards' manifests); the merge then succeeds.
TEST_F(SlurmTest, KilledTaskResubmittedAloneCompletesTheRun) {
  const fs::path out = tmp_->path() / "run";
  const std::string job = Submit(
      "env FETCHSCOPE_TEST_KILL_AT=3 FETCHSCOPE_TEST_KILL_HOW=pause "
      "FETCHSCOPE_TEST_KILL_IF=SLURM_ARRAY_TASK_ID=1 " +
      Adapted(guide_.record, out.string(), true));
  ASSERT_TRUE(WaitForText(Log(job, 1), "paused at kill point")) << ReadFile(Log(job, 1));
  // SIGKILL to every process of the task at once, as a node failure or the OOM killer would
  // (scancel --signal=KILL lets Slurm send SIGTERM first); only this cluster's task (its
  // SLURM_CONF), should another test's cluster run a job of the same id
  Shell(
      "pids=$(for pid in $(pgrep -x fetchscope); do tr '\\0' '\\n' </proc/$pid/environ | "
      "grep -qx SLURM_ARRAY_JOB_ID=" +
      job +
      " && tr '\\0' '\\n' </proc/$pid/environ | grep -qx SLURM_ARRAY_TASK_ID=1 && "
      "tr '\\0' '\\n' </proc/$pid/environ | grep -qxF \"SLURM_CONF=$SLURM_CONF\" && "
      "echo $pid; done); test -n \"$pids\" && kill -KILL $pids");
  WaitFor(job);
  EXPECT_FALSE(fs::exists(out / "manifest_shard_0001_of_0004.json"));
  EXPECT_TRUE(fs::exists(out / "episode_001.mp4"));  // what the killed attempt left
  const std::string merge_line = Adapted(
      std::regex_replace(guide_.merge, std::regex("--dependency=\\S+ "), ""), out.string(), false);
  WaitNodeIdle();  // the killed task's node cleans up first
  std::string merge = Submit(merge_line);
  WaitFor(merge);
  EXPECT_EQ(State(merge), "FAILED");
  const std::string merge_log = ReadFile(work_ / "fetchscope-logs" / ("merge_" + merge + ".log"));
  EXPECT_NE(merge_log.find("shard 1/4 has no manifest"), std::string::npos) << merge_log;
  EXPECT_FALSE(fs::exists(out / "manifest.json"));
  // only index 1 again, with the same OUT and options
  WaitNodeIdle();
  const std::string again = Submit(std::regex_replace(Adapted(guide_.record, out.string(), true),
                                                      std::regex("--array=0-3"), "--array=1"));
  WaitFor(again);
  EXPECT_EQ(State(again + "_1"), "COMPLETED") << ReadFile(Log(again, 1));
  EXPECT_NE(ReadFile(Log(again, 1)).find("records shard 1/4"), std::string::npos)
      << ReadFile(Log(again, 1));
  WaitNodeIdle();
  merge = Submit(merge_line);
  WaitFor(merge);
  EXPECT_EQ(State(merge), "COMPLETED")
      << ReadFile(work_ / "fetchscope-logs" / ("merge_" + merge + ".log"));
  ExpectSameAsUnsharded(out);
}

}  // namespace
}  // namespace fetchscope
