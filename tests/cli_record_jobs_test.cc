// record --jobs N: workers with their own GL contexts on their own threads give exactly the
// files of --jobs 1, on EGL and on OSMesa, and a signal still finishes every worker's video.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>

#include "base/errors.h"
#include "cli/view_options.h"
#include "render/gl_context.h"
#include "render/renderer.h"
#include "render/view.h"
#include "src/assets.h"
#include "src/fetch_env.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::EpisodeFiles;
using testing::ReadFile;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::TempDir;
namespace fs = std::filesystem;

// Whether this machine can make a context of `backend` (else the test is skipped).
bool HasBackend(const std::string& backend) {
  try {
    CreateGlContext(backend);
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

class JobsTest : public ::testing::TestWithParam<const char*> {
 protected:
  void SetUp() override {
    unsetenv("DISPLAY");
    for (const char* name : {"SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX", "MUJOCO_GL"})
      unsetenv(name);
  }
};

// Random is the policy whose generator runs across episodes; PickAndPlace draws the most per
// reset (object, goal, in-the-air coin): a worker that starts at episode k must replay both.
TEST_P(JobsTest, ParallelWorkersWriteTheFilesOfOneJob) {
  if (!HasBackend(GetParam())) GTEST_SKIP() << GetParam() << " is not available here";
  TempDir tmp;
  const std::string run =
      std::string("record --quiet --env-id FetchPickAndPlace-v4 --policy random --seed 5 ") +
      "--episodes 5 --steps 5 --width 64 --height 64 --backend " + GetParam();
  std::map<int, std::map<std::string, std::string>> files;
  std::map<int, nlohmann::json> manifests;
  for (int jobs : {1, 2, 3}) {
    const fs::path out = tmp.path() / ("j" + std::to_string(jobs));
    auto r = RunFetchscope(run + " --jobs " + std::to_string(jobs) + " --out " + out.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    files[jobs] = EpisodeFiles(out);
    manifests[jobs] = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  }
  ASSERT_EQ(files[1].size(), 15u);  // video, sheet and trajectory of 5 episodes
  for (int jobs : {2, 3}) {
    EXPECT_EQ(manifests[jobs]["jobs"], jobs);
    EXPECT_EQ(manifests[jobs]["episodes"], manifests[1]["episodes"]) << "--jobs " << jobs;
    ASSERT_EQ(files[jobs].size(), files[1].size());
    for (const auto& [name, bytes] : files[1]) {
      EXPECT_TRUE(files[jobs][name] == bytes) << name << " differs with --jobs " << jobs;
    }
  }
  // asynchronous readback (the default on hardware GL) writes the same files as well
  const fs::path async_out = tmp.path() / "async";
  auto r = RunFetchscope(run + " --jobs 2 --readback async --out " + async_out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto async_files = EpisodeFiles(async_out);
  ASSERT_EQ(async_files.size(), files[1].size());
  for (const auto& [name, bytes] : files[1]) {
    EXPECT_TRUE(async_files.at(name) == bytes) << name << " differs with --readback async";
  }
  const auto async_manifest = nlohmann::json::parse(ReadFile(async_out / "manifest.json"));
  ASSERT_TRUE(async_manifest.contains("workers")) << async_manifest.dump();
  for (const auto& w : async_manifest["workers"]) {
    EXPECT_EQ(w.value("readback", "").rfind("async: requested", 0), 0u) << w.dump();
  }
}

// libx264 reads some bytes of its own heap buffers before writing them: unless every heap block
// starts the same (main() zero-fills them), a video's bytes depended on what the process had
// freed before, so on --jobs. This episode (FetchReach seed 2, episode 2) showed it: run with
// two different malloc fill patterns (MALLOC_PERTURB_, glibc's), and at 1 and 3 jobs, the
// files must not change.
TEST_P(JobsTest, VideoBytesDoNotDependOnWhatTheHeapHeldBefore) {
  if (!HasBackend(GetParam())) GTEST_SKIP() << GetParam() << " is not available here";
  TempDir tmp;
  const std::string run =
      std::string("record --quiet --env-id FetchReach-v4 --policy random --seed 2 ") +
      "--episodes 3 --steps 15 --width 160 --height 160 --overlay goal,achieved --backend " +
      GetParam();
  std::map<std::string, std::map<std::string, std::string>> files;
  for (const char* perturb : {"77", "165"}) {
    for (int jobs : {1, 3}) {
      const std::string name = std::string("p") + perturb + "j" + std::to_string(jobs);
      const fs::path out = tmp.path() / name;
      auto r = RunCommand(std::string("MALLOC_PERTURB_=") + perturb + " " + FETCHSCOPE_BIN + " " +
                          run + " --jobs " + std::to_string(jobs) + " --out " + out.string());
      ASSERT_EQ(r.exit_code, 0) << r.output;
      files[name] = EpisodeFiles(out);
    }
  }
  const auto& reference = files.begin()->second;
  ASSERT_EQ(reference.size(), 9u);
  for (const auto& [name, got] : files) {
    for (const auto& [file, bytes] : reference) {
      EXPECT_TRUE(got.at(file) == bytes) << file << " differs in run " << name;
    }
  }
}

// Workers stop mid-episode on SIGTERM, finish what they recorded so it plays, and the manifest
// lists those episodes and says the run was interrupted.
TEST_P(JobsTest, SignalFinishesEveryWorkersVideo) {
  if (!HasBackend(GetParam())) GTEST_SKIP() << GetParam() << " is not available here";
  TempDir tmp;
  const fs::path out = tmp.path() / "run";
  // SIGTERM once the first episode is written (however long the workers take to start on a
  // loaded machine), while the others are mid-episode
  auto r = RunCommand(std::string(FETCHSCOPE_BIN) +
                      " record --quiet --jobs 2 --episodes 500 --width 64 --height 64 --backend " +
                      GetParam() + " --out " + out.string() + " & pid=$!; i=0; while [ ! -e " +
                      (out / "episode_001.json").string() +
                      " ] && [ $i -lt 1200 ]; do sleep 0.1; i=$((i+1)); done; sleep 0.3; "
                      "kill -TERM $pid; wait $pid");
  EXPECT_EQ(r.exit_code, 143) << r.output;
  auto m = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  EXPECT_EQ(m["interrupted"], true);
  EXPECT_EQ(m["signal"], "SIGTERM");
  EXPECT_EQ(m["jobs"], 2);
  ASSERT_GE(m["episodes"].size(), 1u);
  EXPECT_LT(m["episodes"].size(), 500u);
  int previous = -1;
  for (const auto& e : m["episodes"]) {
    EXPECT_GT(e["index"].get<int>(), previous);  // in order
    previous = e["index"];
    auto probe = RunCommand(
        "ffprobe -v error -count_frames -show_entries stream=nb_read_frames -of csv=p=0 " +
        (out / e["video"].get<std::string>()).string());
    ASSERT_EQ(probe.exit_code, 0) << probe.output;
    EXPECT_EQ(std::stoi(probe.output), e["frames"].get<int>());
    EXPECT_TRUE(fs::exists(out / e["trajectory"].get<std::string>()));
  }
  for (const auto& e : fs::directory_iterator(out)) {
    EXPECT_NE(e.path().filename().string()[0], '.') << "leftover temporary " << e.path();
  }
}

// Several MuJoCo renderers, each on its own thread with its own context and model, render the
// same state to the same pixels as one alone does.
TEST_P(JobsTest, RenderersOnSeparateThreadsAgree) {
  if (!HasBackend(GetParam())) GTEST_SKIP() << GetParam() << " is not available here";
  const EnvSpec& spec = FindEnvSpec("FetchPush-v4");
  const AssetSource assets = ResolveAssets("bundled");
  constexpr int kThreads = 3, kSize = 64;
  std::vector<std::vector<uint8_t>> frames(kThreads);
  std::vector<std::string> errors(kThreads);
  std::vector<std::thread> threads;
  std::mutex setup;
  for (int i = 0; i < kThreads; ++i) {
    threads.emplace_back([&, i] {
      try {
        FetchEnv env(spec, assets);
        const Observation obs = env.Reset(7);
        cli::ViewOptions view;
        view.width = view.height = kSize;
        // made one at a time, as record does: MuJoCo binds its GL functions at the first
        std::unique_lock<std::mutex> lock(setup);
        auto gl = CreateGlContext(GetParam());
        Renderer renderer(*gl, env.model(), cli::ResolveRenderOptions(view, env.model()));
        lock.unlock();
        StepRecord record;
        record.obs = obs;
        frames[i].resize(kSize * kSize * 3);
        for (int repeat = 0; repeat < 5; ++repeat) {  // overlap the threads' GL work
          renderer.Render(env.data(), MakeFrameInfo(env, record), frames[i].data());
        }
      } catch (const std::exception& e) {
        errors[i] = e.what();
      }
    });
  }
  for (std::thread& t : threads) t.join();
  for (int i = 0; i < kThreads; ++i) {
    ASSERT_EQ(errors[i], "") << "thread " << i;
    EXPECT_TRUE(frames[i] == frames[0]) << "thread " << i;
  }
  EXPECT_GT(std::set<uint8_t>(frames[0].begin(), frames[0].end()).size(),
            16u);  // a scene, not a blank
}

INSTANTIATE_TEST_SUITE_P(Backends, JobsTest, ::testing::Values("osmesa", "egl"));

}  // namespace
}  // namespace fetchscope
