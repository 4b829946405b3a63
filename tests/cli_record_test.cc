// Black-box tests of render and record (real EGL/OSMesa, real libx264, checked with ffprobe,
// ffmpeg's decoder and libpng), and record's worker (RecordRunner) in-process; --steps past the
// TimeLimit marked in the trajectory and the HUD.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "encode/frame_pool.h"
#include "encode/png_io.h"
#include "render/frame_limits.h"
#include "render/layers.h"
#include "render/overlay.h"
#include "run/record_run.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/trajectory.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::ReadFile;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::TempDir;
namespace fs = std::filesystem;
using testing::CommandResult;
using testing::Count;

class RecordTest : public ::testing::Test {
 protected:
  void SetUp() override { unsetenv("DISPLAY"); }
};

TEST_F(RecordTest, WritesPlayableVideoSheetTrajectoryAndManifest) {
  TempDir tmp;
  const fs::path out = tmp.path() / "run";
  auto r = RunFetchscope(
      "record --env-id FetchPush-v4 --policy scripted --episodes 2 --seed 4 --width 160 "
      "--height 120 --out " +
      out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* name : {"episode_000", "episode_001"}) {
    const fs::path mp4 = out / (std::string(name) + ".mp4");
    auto probe = RunCommand(
        "ffprobe -v error -count_frames -show_entries "
        "stream=codec_name,pix_fmt,width,height,nb_read_frames,r_frame_rate -of json " +
        mp4.string());
    ASSERT_EQ(probe.exit_code, 0) << probe.output;
    auto s = nlohmann::json::parse(probe.output)["streams"][0];
    EXPECT_EQ(s["codec_name"], "h264");
    EXPECT_EQ(s["pix_fmt"], "yuv420p");
    EXPECT_EQ(s["nb_read_frames"], "51");  // reset frame + 50 steps
    EXPECT_EQ(s["r_frame_rate"], "25/1");
    EXPECT_EQ(s["width"], 160);
    const Image sheet = ReadPng((out / (std::string(name) + "_sheet.png")).string());
    EXPECT_GT(sheet.width, 160);
    auto traj = nlohmann::json::parse(ReadFile(out / (std::string(name) + ".json")));
    EXPECT_EQ(traj["env_id"], "FetchPush-v4");
    EXPECT_EQ(traj["episodes"][0]["steps"].size(), 51u);
  }
  auto m = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  EXPECT_EQ(m["interrupted"], false);
  EXPECT_EQ(m["episodes"].size(), 2u);
  EXPECT_EQ(m["video"]["codec"], "libx264");
  EXPECT_FALSE(m["backend"]["gl_renderer"].get<std::string>().empty());
  EXPECT_EQ(m["assets"]["sha256"].get<std::string>().size(), 64u);
  for (const auto& e : fs::directory_iterator(out)) {
    EXPECT_NE(e.path().filename().string()[0], '.') << "leftover temporary " << e.path();
  }
}

// Rendering never feeds back into the simulation: record and rollout agree exactly.
TEST_F(RecordTest, RecordTrajectoryEqualsRollout) {
  TempDir tmp;
  for (const char* id : {"FetchPickAndPlace-v4", "FetchReach-v4"}) {
    const fs::path out = tmp.path() / id;
    ASSERT_EQ(
        RunFetchscope(
            std::string("record --quiet --width 96 --height 96 --steps 20 --seed 9 --env-id ") +
            id + " --out " + out.string())
            .exit_code,
        0);
    const std::string rollout = (tmp.path() / (std::string(id) + ".json")).string();
    ASSERT_EQ(RunFetchscope(std::string("rollout --steps 20 --seed 9 --env-id ") + id +
                            " --json-out " + rollout)
                  .exit_code,
              0);
    auto a = nlohmann::json::parse(ReadFile(out / "episode_000.json"));
    auto b = nlohmann::json::parse(ReadFile(rollout));
    EXPECT_EQ(a["episodes"][0]["steps"], b["episodes"][0]["steps"]) << id;
  }
}

// Frame k of the video is the state after step k: each frame is closest to a fresh render of
// exactly that step.
TEST_F(RecordTest, VideoFrameKIsTheStateAfterStepK) {
  TempDir tmp;
  const int w = 128, h = 128, steps = 12;
  const std::string common =
      " --env-id FetchPickAndPlace-v4 --policy random --seed 3 --overlay none --width 128 --height "
      "128 --backend osmesa";
  const std::string video = " --crf 8";
  ASSERT_EQ(RunFetchscope("record --quiet --steps " + std::to_string(steps) + common + video +
                          " --out " + tmp.path().string())
                .exit_code,
            0);
  const fs::path raw = tmp.path() / "frames.rgb";
  auto dec = RunCommand("ffmpeg -v error -i " + (tmp.path() / "episode_000.mp4").string() +
                        " -f rawvideo -pix_fmt rgb24 " + raw.string());
  ASSERT_EQ(dec.exit_code, 0) << dec.output;
  const std::string frames = ReadFile(raw);
  const size_t frame_bytes = static_cast<size_t>(w) * h * 3;
  ASSERT_EQ(frames.size(), frame_bytes * (steps + 1));
  for (int k : {0, 1, 6, 12}) {
    const std::string png = (tmp.path() / ("k" + std::to_string(k) + ".png")).string();
    auto r = RunFetchscope("render --steps " + std::to_string(k) + common + " -o " + png);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const Image img = ReadPng(png);
    int best = -1;
    double best_err = 1e300;
    for (int f = 0; f <= steps; ++f) {
      double err = 0;
      for (size_t i = 0; i < frame_bytes; ++i) {
        err += std::abs(static_cast<int>(static_cast<uint8_t>(frames[f * frame_bytes + i])) -
                        img.pixels[i]);
      }
      if (err < best_err) {
        best_err = err;
        best = f;
      }
    }
    EXPECT_EQ(best, k) << "video frame closest to render --steps " << k;
    EXPECT_LT(best_err / frame_bytes, 3.0);  // only H.264 loss remains
  }
}

TEST_F(RecordTest, SigintFinishesTheCurrentVideoAndMarksTheManifest) {
  TempDir tmp;
  const fs::path out = tmp.path() / "run";
  auto r =
      RunCommand("timeout --preserve-status -s INT 4 " + std::string(FETCHSCOPE_BIN) +
                 " record --quiet --episodes 500 --width 64 --height 64 --out " + out.string());
  EXPECT_EQ(r.exit_code, 130) << r.output;
  auto m = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  EXPECT_EQ(m["interrupted"], true);
  EXPECT_EQ(m["signal"], "SIGINT");
  ASSERT_GE(m["episodes"].size(), 1u);
  EXPECT_LT(m["episodes"].size(), 500u);
  // every listed video plays to its last frame; nothing half-written remains
  for (const auto& e : m["episodes"]) {
    auto probe = RunCommand(
        "ffprobe -v error -count_frames -show_entries stream=nb_read_frames -of csv=p=0 " +
        (out / e["video"].get<std::string>()).string());
    ASSERT_EQ(probe.exit_code, 0) << probe.output;
    EXPECT_EQ(std::stoi(probe.output), e["frames"].get<int>());
  }
  for (const auto& e : fs::directory_iterator(out)) {
    EXPECT_NE(e.path().filename().string()[0], '.') << "leftover temporary " << e.path();
  }
}

TEST_F(RecordTest, ExecPolicyDrivesTheRecording) {
  TempDir tmp;
  const fs::path script = tmp.path() / "policy.py";
  std::ofstream(script) << "import sys, json\n"
                           "for line in sys.stdin:\n"
                           "    obs = json.loads(line)\n"
                           "    g, a = obs['desired_goal'], obs['achieved_goal']\n"
                           "    print(json.dumps([max(-1, min(1, (g[i] - a[i]) / 0.05)) for i in "
                           "range(3)] + [0]), flush=True)\n";
  auto r = RunFetchscope(
      "record --quiet --env-id FetchReach-v4 --width 64 --height 64 --policy 'exec:python3 " +
      script.string() + "' --out " + tmp.path().string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto m = nlohmann::json::parse(ReadFile(tmp.path() / "manifest.json"));
  EXPECT_EQ(m["episodes"][0]["is_success"], true);  // a proportional controller reaches the goal
}

struct BadRender {
  std::string args;
  int exit_code;
  std::string message;
};

// gtest prints the command line instead of the bytes of the struct
void PrintTo(const BadRender& c, std::ostream* os) { *os << c.args; }

class BadRenderTest : public ::testing::TestWithParam<BadRender> {};

TEST_P(BadRenderTest, OneClearLineNothingWritten) {
  unsetenv("DISPLAY");
  TempDir tmp;
  std::string args = GetParam().args;
  const size_t pos = args.find("OUT");
  if (pos != std::string::npos) args.replace(pos, 3, tmp.path().string());
  auto r = RunFetchscope(args);
  EXPECT_EQ(r.exit_code, GetParam().exit_code) << r.output;
  EXPECT_NE(r.output.find(GetParam().message), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("fetchscope: error: "), std::string::npos) << r.output;
  EXPECT_LE(std::count(r.output.begin(), r.output.end(), '\n'), 2) << r.output;
  for (const auto& e : fs::recursive_directory_iterator(tmp.path())) {
    ADD_FAILURE() << "left behind: " << e.path();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Render, BadRenderTest,
    ::testing::Values(BadRender{"render --backend vulkan -o OUT/f.png", 2, "vulkan"},
                      BadRender{"render --camera nosuchcam -o OUT/f.png", 2, "head_camera_rgb"},
                      BadRender{"render --camera free:lookat=1,2 -o OUT/f.png", 2, "lookat"},
                      BadRender{"render --camera free:zoom=3 -o OUT/f.png", 2, "zoom"},
                      BadRender{"render --width 0 -o OUT/f.png", 2, "width"},
                      BadRender{"render --height -5 -o OUT/f.png", 2, "height"},
                      BadRender{"render --width 100000 -o OUT/f.png", 2, "100000"},
                      BadRender{"render --width 9000 --height 9000 -o OUT/f.png", 2, "9000"},
                      BadRender{"render --overlay goal,sparkles -o OUT/f.png", 2, "sparkles"},
                      BadRender{"render --layers rgb,normals -o OUT/f.png", 2, "normals"},
                      BadRender{"render -o /proc/nope/f.png", 2, "/proc/nope"},
                      BadRender{"record --codec mpeg2 --out OUT/r", 2, "mpeg2"},
                      BadRender{"record --crf 99 --out OUT/r", 2, "99"},
                      BadRender{"record --out /proc/nope/run", 2, "/proc/nope/run"},
                      BadRender{"record --layers rgb,segmentaton --out OUT/r", 2,
                                "unknown layer 'segmentaton' (did you mean 'segmentation'?)"},
                      BadRender{"record --layers depth,depth --out OUT/r", 2,
                                "--layers names 'depth' twice"},
                      BadRender{"record --layers rgb,,depth --out OUT/r", 2, "empty entry"}));

// ---- RecordRunner in-process (run/record_run.h), with a channel standing in for the scheduler

// Collects what a runner reports, as the scheduler's channel would.
class CollectingChannel : public WorkerChannel {
 public:
  void Progress(int n) override { frames += n; }
  void Done(int episode, nlohmann::json result) override {
    std::lock_guard<std::mutex> lock(mutex);
    done[episode] = std::move(result);
  }
  bool StopRequested() const override { return false; }

  std::atomic<int> frames{0};
  std::mutex mutex;
  std::map<int, nlohmann::json> done;
};

// A small plan: FetchPush-v4, random policy, 4 steps, 64x48, mp4 with the depth layer.
RecordPlan SmallPlan(const fs::path& out, int encoders) {
  RecordPlan plan;
  plan.spec = &FindEnvSpec("FetchPush-v4");
  plan.seed = 3;
  plan.seed_text = "3";
  plan.assets = ResolveAssets("bundled");
  plan.policy = PolicySpec::Random();
  plan.steps = 4;
  plan.policy_context.seed = plan.seed;
  plan.policy_context.steps_per_episode = plan.steps;
  plan.policy_context.episodes = 3;
  plan.view.render.width = 64;
  plan.view.render.height = 48;
  plan.out = out.string();
  plan.video.width = 64;
  plan.video.height = 48;
  plan.video.codec = "libx264";
  plan.formats = {FindVideoFormat("mp4")};
  plan.layers = {Layer::kDepth};
  plan.encoders = encoders;
  return plan;
}

TEST_F(RecordTest, RecordRunnerWritesTheSameBytesWithOneOrThreeEncoders) {
  TempDir tmp;
  std::map<std::string, std::string> files[2];
  for (int i = 0; i < 2; ++i) {
    const fs::path out = tmp.path() / ("encoders_" + std::to_string(i));
    fs::create_directories(out);
    const RecordPlan plan = SmallPlan(out, i == 0 ? 1 : 3);
    CollectingChannel channel;
    {
      RecordRunner runner(plan, 0);
      const nlohmann::json worker = runner.Start();
      EXPECT_EQ(worker["worker"], 0);
      EXPECT_FALSE(worker["gl_renderer"].get<std::string>().empty());
      runner.Run(0, channel);
      runner.Run(2, channel);  // episode 1 skipped: 2 starts where a sequential run reaches it
      runner.Finish(channel);
    }
    EXPECT_EQ(channel.frames.load(), 2 * (plan.steps + 1));
    ASSERT_EQ(channel.done.size(), 2u);
    for (const auto& [k, json] : channel.done) {
      const EpisodeResult result = EpisodeResultFromJson(json);  // as the parent reads it
      const ManifestEpisode& entry = result.entry;
      EXPECT_EQ(entry.index, k);
      EXPECT_EQ(result.worker, 0);
      EXPECT_EQ(entry.frames, plan.steps + 1);
      ASSERT_TRUE(entry.hindsight);
      EXPECT_EQ(entry.hindsight->transitions, plan.steps);
      EXPECT_EQ(entry.layers.at("depth").details["scales"].size(), 1u);
    }
    files[i] = testing::EpisodeFiles(out);
    EXPECT_EQ(files[i].count("episode_002_depth.mp4"), 1u);
    EXPECT_EQ(files[i].count("episode_001.mp4"), 0u);
  }
  ASSERT_EQ(files[0].size(), files[1].size());
  for (const auto& [name, bytes] : files[0]) {
    EXPECT_TRUE(files[1][name] == bytes) << name << " differs with 3 encoders";
  }
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
