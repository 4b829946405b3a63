// record --from (re-rendering recorded trajectories) and the hindsight overlay, black-box:
// the real binary, real GL, real libx264, decoded with ffmpeg; an edited env id named with its
// file and key.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "encode/frame_pool.h"
#include "render/frame_limits.h"
#include "render/overlay.h"
#include "run/record_run.h"
#include "src/trajectory.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::EpisodeFiles;
using testing::ReadFile;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::TempDir;
namespace fs = std::filesystem;
using nlohmann::json;
using testing::CommandResult;
using testing::LineCount;

constexpr char kRun[] =
    "record --quiet --env-id FetchPickAndPlace-v4 --policy scripted --seed 5 --episodes 2 "
    "--steps 12 --width 96 --height 96 --overlay none --crf 8";

// The first decoded frame of `mp4` as rgb24 bytes.
std::string FirstFrame(const fs::path& mp4) {
  const fs::path raw = mp4.string() + ".rgb";
  auto r = RunCommand("ffmpeg -v error -y -i " + mp4.string() +
                      " -frames:v 1 -f rawvideo -pix_fmt rgb24 " + raw.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return ReadFile(raw);
}

void Tamper(const fs::path& file, const std::function<void(nlohmann::json&)>& edit) {
  nlohmann::json j = nlohmann::json::parse(ReadFile(file));
  edit(j["episodes"][0]["steps"]);
  std::ofstream(file, std::ios::trunc) << j.dump(1);
}

class RecordFromTest : public ::testing::Test {
 protected:
  void SetUp() override { unsetenv("DISPLAY"); }
};

TEST_F(RecordFromTest, SameEpisodesFromThreeCameras) {
  TempDir tmp;
  const fs::path run = tmp.path() / "run";
  auto r = RunFetchscope(std::string(kRun) + " --out " + run.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;

  // the same view again: the very same files (trajectories, videos, sheets)
  const fs::path same = tmp.path() / "same";
  r = RunFetchscope("record --quiet --width 96 --height 96 --overlay none --crf 8 --from " +
                    run.string() + " --out " + same.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(EpisodeFiles(same) == EpisodeFiles(run))
      << "re-rendering the same view changed a file";
  const auto manifest = nlohmann::json::parse(ReadFile(same / "manifest.json"));
  EXPECT_EQ(manifest["from"], run.string());
  EXPECT_EQ(manifest["env_id"], "FetchPickAndPlace-v4");
  EXPECT_EQ(manifest["seed"], 5);
  EXPECT_EQ(manifest["episodes"].size(), 2u);

  // three other cameras: the trajectories are the recorded ones, the pictures differ
  std::vector<std::string> first_frames = {FirstFrame(run / "episode_001.mp4")};
  for (const char* camera : {"external_camera_0", "track", "head_camera_rgb"}) {
    const fs::path out = tmp.path() / camera;
    r = RunFetchscope(
        std::string("record --quiet --width 96 --height 96 --overlay default --camera ") + camera +
        " --from " + run.string() + " --out " + out.string());
    ASSERT_EQ(r.exit_code, 0) << camera << ": " << r.output;
    for (const char* name : {"episode_000.json", "episode_001.json"}) {
      EXPECT_EQ(ReadFile(out / name), ReadFile(run / name)) << camera << " " << name;
    }
    const std::string frame = FirstFrame(out / "episode_001.mp4");
    ASSERT_EQ(frame.size(), 96u * 96 * 3) << camera;
    for (const std::string& other : first_frames) EXPECT_NE(frame, other) << camera;
    first_frames.push_back(frame);
  }

  // tiled: two cameras side by side, each 96 wide
  const fs::path tiled = tmp.path() / "tiled";
  r = RunFetchscope(
      "record --quiet --width 96 --height 96 --camera default,external_camera_0 --from " +
      (run / "episode_001.json").string() + " --out " + tiled.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto probe = RunCommand("ffprobe -v error -show_entries stream=width,height -of json " +
                          (tiled / "episode_001.mp4").string());
  auto s = nlohmann::json::parse(probe.output)["streams"][0];
  EXPECT_EQ(s["width"], 192);
  EXPECT_EQ(s["height"], 96);
  EXPECT_FALSE(fs::exists(tiled / "episode_000.mp4")) << "only the episode in the file";
  EXPECT_EQ(ReadFile(tiled / "episode_001.json"), ReadFile(run / "episode_001.json"));
}

TEST_F(RecordFromTest, TamperedTrajectoryIsCaughtAtTheRightStep) {
  TempDir tmp;
  const fs::path run = tmp.path() / "run";
  auto r = RunFetchscope(std::string(kRun) + " --out " + run.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;

  struct Change {
    const char* what;
    int step;
    std::function<void(nlohmann::json&)> edit;
    const char* names;
  };
  const std::vector<Change> changes = {
      {"an action", 7,
       [](nlohmann::json& steps) {
         const double a = steps[7]["action"][0].get<double>();  // stays inside the clip range
         steps[7]["action"][0] = a > 0 ? a - 0.25 : a + 0.25;
       },
       "observation["},
      {"an observation", 5,
       [](nlohmann::json& steps) {
         steps[5]["observation"][3] = steps[5]["observation"][3].get<double>() + 1e-12;
       },
       "observation[3]"},
      {"an achieved goal", 9, [](nlohmann::json& steps) { steps[9]["achieved_goal"][2] = 0.5; },
       "achieved_goal[2]"},
      {"the reset", 0, [](nlohmann::json& steps) { steps[0]["desired_goal"][0] = 1.0; },
       "desired_goal[0]"},
  };
  for (const Change& c : changes) {
    const fs::path file = tmp.path() / "tampered.json";
    fs::copy_file(run / "episode_000.json", file, fs::copy_options::overwrite_existing);
    Tamper(file, c.edit);
    const fs::path out = tmp.path() / "out";
    fs::remove_all(out);
    r = RunFetchscope("record --quiet --width 64 --height 64 --from " + file.string() + " --out " +
                      out.string());
    EXPECT_EQ(r.exit_code, 1) << c.what << ": " << r.output;
    const std::string where = "episode 0 step " + std::to_string(c.step) + ":";
    EXPECT_NE(r.output.find(where), std::string::npos) << c.what << ": " << r.output;
    EXPECT_NE(r.output.find(c.names), std::string::npos) << c.what << ": " << r.output;
    EXPECT_NE(r.output.find("tampered.json"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("difference"), std::string::npos) << r.output;
    // one line: the step, the field, recorded and replayed values; no scheduler tail
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_NE(r.output.find(" recorded "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(", replayed "), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("lost episode"), std::string::npos) << r.output;
    // nothing under a final name
    EXPECT_FALSE(fs::exists(out / "episode_000.mp4")) << c.what;
    EXPECT_FALSE(fs::exists(out / "manifest.json")) << c.what;
  }

  // a run folder whose second episode was edited: stopped before anything is rendered, even
  // the untouched first episode
  const fs::path edited = tmp.path() / "edited";
  fs::copy(run, edited);
  const fs::path file = edited / "episode_001.json";
  nlohmann::json j = nlohmann::json::parse(ReadFile(file));
  j["episodes"][0]["steps"][4]["reward"] = 0.5;
  std::ofstream(file, std::ios::trunc) << j.dump(1);
  const fs::path out = tmp.path() / "out_run";
  r = RunFetchscope("record --width 64 --height 64 --from " + edited.string() + " --out " +
                    out.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("episode_001.json: episode 1 step 4: reward recorded 0.5, replayed -1"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_FALSE(fs::exists(out)) << "nothing written";
}

// Decoded frames of `mp4` as rgb24.
std::string Frames(const fs::path& mp4) {
  const fs::path raw = mp4.string() + ".all.rgb";
  auto r = RunCommand("ffmpeg -v error -y -i " + mp4.string() + " -f rawvideo -pix_fmt rgb24 " +
                      raw.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return ReadFile(raw);
}

// record --from with --layers: a segmentation (and a depth) video per episode with the right
// frame count, the legend naming the colours it shows, and the same bytes with --jobs 2 (which
// also reads frames back asynchronously, as on hardware GL: the layers are drawn between an rgb
// frame's queued readback and its collection).
TEST_F(RecordFromTest, ReRenderWithLayersIsProbedAndTheSameWithJobs) {
  TempDir tmp;
  const fs::path run = tmp.path() / "run";
  auto r = RunFetchscope(
      "record --quiet --env-id FetchPush-v4 --policy scripted --seed 3 --episodes 2 --steps 6 "
      "--width 48 --height 48 --out " +
      run.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::map<int, std::map<std::string, std::string>> files;
  for (int jobs : {1, 2}) {
    const fs::path out = tmp.path() / ("j" + std::to_string(jobs));
    r = RunFetchscope(
        "record --quiet --width 96 --height 72 --layers rgb,segmentation,depth "
        "--crf 0 --format mp4,gif --jobs " +
        std::to_string(jobs) + (jobs == 2 ? " --readback async" : " --readback sync") + " --from " +
        run.string() + " --out " + out.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    files[jobs] = EpisodeFiles(out);
  }
  // per episode: 2 formats x 3 layers, the sheet, the trajectory and the legend
  ASSERT_EQ(files[1].size(), 2u * 9);
  for (const auto& [name, bytes] : files[1]) {
    EXPECT_TRUE(files[2][name] == bytes) << name << " differs between --jobs 1 and --jobs 2";
  }
  const fs::path out = tmp.path() / "j1";
  const auto manifest = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  EXPECT_EQ(manifest["layers"], nlohmann::json({"rgb", "segmentation", "depth"}));
  for (int k = 0; k < 2; ++k) {
    const std::string stem = "episode_00" + std::to_string(k);
    SCOPED_TRACE(stem);
    const auto& layers = manifest["episodes"][k]["layers"];
    EXPECT_EQ(layers["segmentation"]["video"], stem + "_segmentation.mp4");
    EXPECT_EQ(layers["segmentation"]["videos"]["gif"]["file"], stem + "_segmentation.gif");
    EXPECT_EQ(layers["segmentation"]["videos"]["mp4"]["frames"], 7);
    EXPECT_EQ(layers["depth"]["video"], stem + "_depth.mp4");
    EXPECT_EQ(layers["segmentation"]["legend"], stem + "_segmentation_legend.json");
    const auto& scale = layers["depth"]["scales"][0];
    EXPECT_EQ(scale["camera"], "default");
    EXPECT_LT(scale["near_m"].get<double>(), scale["far_m"].get<double>());
    for (const char* layer : {"_segmentation.mp4", "_depth.mp4"}) {
      const auto probe = RunCommand(
          "ffprobe -v error -count_frames -show_entries stream=codec_name,width,height,"
          "nb_read_frames -of json " +
          (out / (stem + layer)).string());
      ASSERT_EQ(probe.exit_code, 0) << probe.output;
      const auto stream = nlohmann::json::parse(probe.output)["streams"][0];
      EXPECT_EQ(stream["nb_read_frames"], "7") << layer;  // the reset frame and 6 steps
      EXPECT_EQ(stream["width"], 96) << layer;
      EXPECT_EQ(stream["height"], 72) << layer;
    }

    // the segmentation frame shows the legend's colours (to within the video's chroma loss)
    // on black, nothing else; the depth frame is grey
    const auto legend = nlohmann::json::parse(ReadFile(out / (stem + "_segmentation_legend.json")));
    EXPECT_EQ(legend["frames"], 7);
    std::set<std::string> bodies;
    for (const auto& o : legend["objects"]) bodies.insert(o["body"].get<std::string>());
    EXPECT_TRUE(bodies.count("object0")) << legend.dump();
    EXPECT_TRUE(bodies.count("table0")) << legend.dump();
    const std::string seg = FirstFrame(out / (stem + "_segmentation.mp4"));
    ASSERT_EQ(seg.size(), 96u * 72 * 3);
    int coloured = 0, near_legend = 0;
    for (size_t i = 0; i < seg.size(); i += 3) {
      const int r8 = static_cast<uint8_t>(seg[i]), g8 = static_cast<uint8_t>(seg[i + 1]),
                b8 = static_cast<uint8_t>(seg[i + 2]);
      if (r8 + g8 + b8 < 40) continue;  // background
      ++coloured;
      for (const auto& o : legend["objects"]) {
        const int dr = r8 - o["rgb"][0].get<int>(), dg = g8 - o["rgb"][1].get<int>(),
                  db = b8 - o["rgb"][2].get<int>();
        if (dr * dr + dg * dg + db * db < 40 * 40) {
          ++near_legend;
          break;
        }
      }
    }
    // the robot, table, block and floor take about a fifth of the frame, the rest is black;
    // yuv420p halves the colour resolution, so edge pixels stray from the legend
    EXPECT_GT(coloured, 96 * 72 / 8);
    EXPECT_LT(coloured, 96 * 72 / 2);
    EXPECT_GT(near_legend, coloured * 2 / 3) << near_legend << " of " << coloured;
    const std::string depth = FirstFrame(out / (stem + "_depth.mp4"));
    ASSERT_EQ(depth.size(), 96u * 72 * 3);
    int grey = 0;
    for (size_t i = 0; i < depth.size(); i += 3) {
      grey += std::abs(depth[i] - depth[i + 1]) < 6 && std::abs(depth[i + 1] - depth[i + 2]) < 6;
    }
    EXPECT_GT(grey, 96 * 72 * 9 / 10);
    EXPECT_NE(depth, FirstFrame(out / (stem + ".mp4")));
  }
  // the trajectories are the recorded ones; the contact sheets stay rgb (the same as without
  // layers at this size)
  EXPECT_EQ(ReadFile(out / "episode_001.json"), ReadFile(run / "episode_001.json"));
}

// An episode that SIGINT cut short stays incomplete when re-rendered: in its trajectory, its
// manifest entry and the manifest's incomplete_episodes, although the re-render itself ran
// to its end.
TEST_F(RecordFromTest, AnIncompleteEpisodeStaysIncomplete) {
  TempDir tmp;
  const fs::path run = tmp.path() / "run", log = tmp.path() / "log";
  // a policy that answers every 30 ms: the signal lands inside an episode
  const std::string command =
      std::string("exec ") + FETCHSCOPE_BIN +
      " record --quiet --env-id FetchReach-v4 --width 32 --height 32 --episodes 20 --policy "
      "'exec:while read l; do sleep 0.03; echo 0.1 0 0 0; done' --out " +
      run.string() + " >" + log.string() + " 2>&1";
  const pid_t pid = fork();
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  for (int i = 0; i < 1200 && !fs::exists(run / "episode_001.json"); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 130) << ReadFile(log);
  const auto source = nlohmann::json::parse(ReadFile(run / "manifest.json"));
  ASSERT_EQ(source["interrupted"], true);
  const int k = source["episodes"].back()["index"];
  ASSERT_EQ(source["episodes"].back()["complete"], false) << source["episodes"].dump();
  const std::string name = "episode_00" + std::to_string(k) + ".json";

  const fs::path out = tmp.path() / "out";
  auto r = RunFetchscope("record --quiet --width 32 --height 32 --from " + run.string() +
                         " --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto manifest = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  EXPECT_EQ(manifest["interrupted"], false) << "the re-render was not interrupted";
  EXPECT_EQ(manifest["incomplete_episodes"], nlohmann::json::array({k}));
  ASSERT_EQ(manifest["episodes"].size(), static_cast<size_t>(k + 1));
  EXPECT_EQ(manifest["episodes"][k]["complete"], false);
  EXPECT_EQ(manifest["episodes"][k]["steps"], source["episodes"].back()["steps"]);
  EXPECT_EQ(manifest["episodes"][0]["complete"], true);
  const auto trajectory = nlohmann::json::parse(ReadFile(out / name));
  EXPECT_EQ(trajectory["episodes"][0]["complete"], false);
  EXPECT_EQ(ReadFile(out / name), ReadFile(run / name))
      << "the re-rendered trajectory is the recorded one";
  // and so merge-manifests counts it as missing, as for the original run
  r = RunFetchscope("merge-manifests --quiet --out " + (tmp.path() / "merged.json").string() + " " +
                    out.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("lacks episodes " + std::to_string(k)), std::string::npos) << r.output;
}

TEST_F(RecordFromTest, HindsightOverlayKeepsTrajectoriesAndIsTheSameWithAnyJobs) {
  TempDir tmp;
  // lossless video: the rendered frames themselves are compared (see the report: lossy x264
  // output of replayed runs was seen to differ with the encoders per worker)
  const std::string base =
      "record --quiet --env-id FetchReach-v4 --policy random --seed 2 --episodes 3 --steps 15 "
      "--width 160 --height 160 --crf 0 ";
  const fs::path plain = tmp.path() / "plain", one = tmp.path() / "one", two = tmp.path() / "two";
  // no HUD (its "HER n/4" row would make every frame differ): only the markers can
  ASSERT_EQ(RunFetchscope(base + "--overlay goal,achieved --out " + plain.string()).exit_code, 0);
  auto r = RunFetchscope(base + "--overlay goal,achieved,hindsight --jobs 1 --out " + one.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunFetchscope(base + "--overlay goal,achieved,hindsight --jobs 2 --out " + two.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto m1 = nlohmann::json::parse(ReadFile(one / "manifest.json"));
  const auto m2 = nlohmann::json::parse(ReadFile(two / "manifest.json"));
  const auto m0 = nlohmann::json::parse(ReadFile(plain / "manifest.json"));
  for (int k = 0; k < 3; ++k) {
    const std::string name = "episode_00" + std::to_string(k);
    // the same frames, sheet and trajectory with --jobs 1 and --jobs 2
    EXPECT_TRUE(Frames(one / (name + ".mp4")) == Frames(two / (name + ".mp4"))) << name;
    EXPECT_TRUE(ReadFile(one / (name + "_sheet.png")) == ReadFile(two / (name + "_sheet.png")))
        << name;
    EXPECT_EQ(ReadFile(one / (name + ".json")), ReadFile(two / (name + ".json")));
    // the episode is run, then rendered from its replay: the same trajectory as without
    EXPECT_EQ(ReadFile(one / (name + ".json")), ReadFile(plain / (name + ".json")));
    // the markers show on every frame after the reset (each ends a transition), not on the
    // reset frame
    const std::string with = Frames(one / (name + ".mp4")),
                      without = Frames(plain / (name + ".mp4"));
    constexpr size_t kFrameBytes = 160 * 160 * 3;
    ASSERT_EQ(with.size(), 16 * kFrameBytes);
    ASSERT_EQ(without.size(), with.size());
    for (size_t t = 0; t < 16; ++t) {
      const bool same =
          with.compare(t * kFrameBytes, kFrameBytes, without, t * kFrameBytes, kFrameBytes) == 0;
      EXPECT_EQ(same, t == 0) << name << " frame " << t;
    }
    const auto& h = m1["episodes"][k]["hindsight"];
    EXPECT_EQ(h, m2["episodes"][k]["hindsight"]);
    EXPECT_EQ(h, m0["episodes"][k]["hindsight"]) << "the counts do not depend on the overlay";
    EXPECT_EQ(h["k"], 4);
    EXPECT_EQ(h["transitions"], 15);
    // random Reach rarely succeeds; relabelled goals do: at least the last transition's four
    EXPECT_GE(h["relabelled_successes"].get<int>(), 4);
    EXPECT_GE(h["relabelled_successes"].get<int>(), h["original_successes"].get<int>());
    EXPECT_LE(h["relabelled_successes"].get<int>(), 4 * 15);
  }
}

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
  EXPECT_EQ(LineCount(r.output), 1) << r.output;
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

}  // namespace
}  // namespace fetchscope
