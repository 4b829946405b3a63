// The episode scheduler as every subcommand that runs episodes uses it: rollout and
// random-episodes give the JSON of --jobs 1 with any number of workers (processes or threads);
// --jobs 0 and the encoder budget count the cores this process may use (affinity mask, cgroup
// quota), not the machine's; record's manifest says which encoder it used and why.
#include <gtest/gtest.h>
#include <sched.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "cli/common.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::ReadFile;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::TempDir;
namespace fs = std::filesystem;

int AffinityCores() {
  cpu_set_t set;
  CPU_ZERO(&set);
  return sched_getaffinity(0, sizeof(set), &set) == 0 ? CPU_COUNT(&set) : 1;
}

// Runs `args --json-out DIR/NAME` and returns the JSON file's bytes.
std::string JsonOf(const TempDir& tmp, const std::string& name, const std::string& args) {
  const fs::path out = tmp.path() / (name + ".json");
  const auto r = RunFetchscope(args + " --json-out " + out.string());
  EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.output;
  return ReadFile(out);
}

// The random policy's generator runs across episodes and PickAndPlace draws the most per reset:
// a worker that starts at episode k must replay both to give episode k of a sequential run.
TEST(Scheduler, RolloutJsonIsTheSameWithAnyJobs) {
  TempDir tmp;
  const std::string run =
      "rollout --env-id FetchPickAndPlace-v4 --policy random --seed 11 --episodes 5 --steps 6";
  const std::string one = JsonOf(tmp, "j1", run + " --jobs 1");
  ASSERT_FALSE(one.empty());
  EXPECT_EQ(nlohmann::json::parse(one)["episodes"].size(), 5u);
  EXPECT_EQ(JsonOf(tmp, "j2", run + " --jobs 2"), one);
  EXPECT_EQ(JsonOf(tmp, "j3", run + " --jobs 3"), one);
  EXPECT_EQ(JsonOf(tmp, "t3", run + " --jobs 3 --worker-mode thread"), one);
  // a different seed must give different JSON, or the comparisons above prove nothing
  EXPECT_NE(JsonOf(tmp, "other",
                   "rollout --env-id FetchPickAndPlace-v4 --policy random --seed 12 "
                   "--episodes 5 --steps 6 --jobs 2"),
            one);
}

TEST(Scheduler, RandomEpisodesJsonIsTheSameWithAnyJobs) {
  TempDir tmp;
  const std::string run = "random-episodes --env-id FetchPush-v4 --n-episodes 6 --seed 4";
  const std::string one = JsonOf(tmp, "j1", run + " --jobs 1");
  ASSERT_FALSE(one.empty());
  EXPECT_EQ(nlohmann::json::parse(one)["episodes"].size(), 6u) << one.substr(0, 400);
  EXPECT_EQ(JsonOf(tmp, "j2", run + " --jobs 2"), one);
  EXPECT_EQ(JsonOf(tmp, "j4", run + " --jobs 4"), one);
}

// taskset (like Slurm's --cpus-per-task cpuset) leaves this process one core: --jobs 0 makes
// one worker and each worker encodes one episode at a time, whatever the machine has.
TEST(Scheduler, JobsZeroAndTheEncoderBudgetCountTheAffinityMask) {
  if (RunCommand("taskset -c 0 true").exit_code != 0) GTEST_SKIP() << "no taskset here";
  TempDir tmp;
  const std::string run =
      " record --quiet --no-report --env-id FetchReach-v4 --episodes 3 "
      "--steps 2 --width 48 --height 48 --jobs 0 --out ";
  auto r = RunCommand("taskset -c 0 " + std::string(FETCHSCOPE_BIN) + run +
                      (tmp.path() / "one").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  nlohmann::json m = nlohmann::json::parse(ReadFile(tmp.path() / "one" / "manifest.json"));
  EXPECT_EQ(m["jobs"], 1);
  EXPECT_EQ(m["video"]["encoders_per_worker"], 1);
  EXPECT_EQ(m["video"]["encoder_threads"], 1);

  // unrestricted: the workers and encoders follow this process's own cores
  const int cores = AffinityCores();
  r = RunFetchscope(run + (tmp.path() / "all").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  m = nlohmann::json::parse(ReadFile(tmp.path() / "all" / "manifest.json"));
  EXPECT_EQ(m["jobs"], std::min(cores, 3));
  EXPECT_EQ(m["video"]["encoders_per_worker"], std::max(1, cores / std::min(cores, 3)));
  // and the videos are the same bytes either way
  EXPECT_EQ(ReadFile(tmp.path() / "one" / "episode_002.mp4"),
            ReadFile(tmp.path() / "all" / "episode_002.mp4"));
}

// A container with a CPU limit (cgroup v2 cpu.max, v1 cfs_quota_us) sees every core of the
// node; the quota is what it may use. The smallest limit along the cgroup's ancestors counts.
TEST(Scheduler, CgroupQuotaIsReadFromTheProcessesCgroupAndItsAncestors) {
  TempDir tmp;
  const fs::path root = tmp.path() / "cgroup";
  auto write = [](const fs::path& path, const std::string& text) {
    fs::create_directories(path.parent_path());
    std::ofstream(path) << text;
  };
  const fs::path self = tmp.path() / "self_cgroup";
  write(self, "0::/kubepods/pod1/ctr\n");
  EXPECT_EQ(cli::CgroupCpuQuota(self.string(), root.string()), 0);  // no files: no quota
  write(root / "kubepods/pod1/ctr/cpu.max", "max 100000\n");
  EXPECT_EQ(cli::CgroupCpuQuota(self.string(), root.string()), 0);  // "max": unlimited
  write(root / "kubepods/pod1/cpu.max", "250000 100000\n");
  EXPECT_DOUBLE_EQ(cli::CgroupCpuQuota(self.string(), root.string()), 2.5);  // a parent's limit
  write(root / "kubepods/pod1/ctr/cpu.max", "600000 100000\n");
  EXPECT_DOUBLE_EQ(cli::CgroupCpuQuota(self.string(), root.string()), 2.5);  // the smaller one
  write(root / "cpu.max", "100000 100000\n");
  EXPECT_DOUBLE_EQ(cli::CgroupCpuQuota(self.string(), root.string()), 1.0);  // the root's, smaller

  // cgroup v1: cpu.cfs_quota_us / cpu.cfs_period_us, -1 meaning no limit
  const fs::path v1 = tmp.path() / "v1";
  const fs::path v1_self = tmp.path() / "v1_self";
  write(v1_self, "4:cpu,cpuacct:/\n");
  write(v1 / "cpu/cpu.cfs_quota_us", "-1\n");
  write(v1 / "cpu/cpu.cfs_period_us", "100000\n");
  EXPECT_EQ(cli::CgroupCpuQuota(v1_self.string(), v1.string()), 0);
  write(v1 / "cpu/cpu.cfs_quota_us", "350000\n");
  EXPECT_DOUBLE_EQ(cli::CgroupCpuQuota(v1_self.string(), v1.string()), 3.5);
}

// One encoder decision per run, made before the workers start: the manifest says which and
// why, and every episode's video is made with it.
TEST(Scheduler, ManifestSaysWhichEncoderAndWhy) {
  TempDir tmp;
  const auto r = RunFetchscope(
      "record --quiet --no-report --env-id FetchReach-v4 --episodes 2 "
      "--steps 2 --width 48 --height 48 --jobs 2 --codec auto --out " +
      (tmp.path() / "run").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json m = nlohmann::json::parse(ReadFile(tmp.path() / "run" / "manifest.json"));
  const nlohmann::json& video = m["video"];
  ASSERT_TRUE(video.contains("codec_reason")) << video.dump();
  const std::string codec = video["codec"];
  const std::string reason = video["codec_reason"];
  EXPECT_TRUE(reason.rfind("auto: ", 0) == 0) << reason;  // --codec auto decided, and says why
  if (!fs::exists("/dev/nvidiactl")) {
    EXPECT_EQ(codec, "libx264");
    EXPECT_NE(reason.find("no NVIDIA GPU"), std::string::npos) << reason;
  }
  for (const char* name : {"episode_000.mp4", "episode_001.mp4"}) {
    const auto probe = RunCommand(
        "ffprobe -v error -select_streams v:0 -show_entries "
        "stream=codec_name -of csv=p=0 " +
        (tmp.path() / "run" / name).string());
    ASSERT_EQ(probe.exit_code, 0) << probe.output;
    EXPECT_EQ(probe.output, "h264\n");  // libx264 and h264_nvenc both write H.264
  }
}

// bench --what node, small: the figures a user sizes a job with, side by side in one JSON. On
// this machine (software GL, so msaa auto is 0) record runs at --jobs 1 and at every usable
// core, as processes and as threads, each with the encoder it used.
TEST(Scheduler, BenchNodeReportsCoresEncoderRenderAndRecordRows) {
  TempDir tmp;
  const auto r = RunFetchscope(
      "bench --what node --backends egl --seconds 0.4 --width 48 "
      "--height 48 --json-out " +
      (tmp.path() / "b.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json node = nlohmann::json::parse(ReadFile(tmp.path() / "b.json"))["node"];
  const int cores = node["cores"];
  EXPECT_EQ(cores, AffinityCores());
  EXPECT_EQ(node["width"], 48);
  EXPECT_EQ(node["encoder"]["codec"], "libx264");
  EXPECT_FALSE(node["encoder"]["reason"].get<std::string>().empty());
  std::set<std::string> readbacks;
  for (const auto& row : node["render"]) {
    ASSERT_TRUE(row.contains("render_frames_per_s")) << row.dump();
    EXPECT_GT(row["render_frames_per_s"].get<double>(), 0);
    readbacks.insert(row["readback"].get<std::string>().substr(0, 4));
  }
  EXPECT_EQ(readbacks, (std::set<std::string>{"sync", "asyn"}));
  std::set<std::pair<int, std::string>> runs;
  for (const auto& row : node["record"]) {
    ASSERT_TRUE(row.contains("frames_per_s")) << row.dump();
    EXPECT_GT(row["frames_per_s"].get<double>(), 0);
    EXPECT_EQ(row["video"]["codec"], "libx264");
    EXPECT_EQ(row["msaa"], 0);  // auto on llvmpipe; no separate msaa 0 run then
    runs.insert({row["jobs"].get<int>(), row["worker_mode"].get<std::string>()});
  }
  std::set<std::pair<int, std::string>> expected = {{1, "process"}};
  if (cores > 1) {
    expected.insert({cores, "process"});
    expected.insert({cores, "thread"});
  }
  if (cores / 2 > 1) {
    expected.insert({cores / 2, "process"});
    expected.insert({cores / 2, "thread"});
  }
  EXPECT_EQ(runs, expected);
  EXPECT_NE(r.output.find("usable cores"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace fetchscope
