// Randomized looks in runs (--randomize on record, record --from and rollout), black box: the
// frames change and differ between episodes while the states stay the plain run's; the draw is
// stored with each episode (trajectory, manifest, Minari and robomimic); record --from redraws
// the stored look bit for bit and --randomize none the plain look; a dataset's stored camera
// pose and its episode's drawn fovy project the object onto its segmentation pixels.
// (The engine itself, its ranges, contrast rule and bad config files: tests/look_test.cc.)
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::ReadFile;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::TempDir;

const char* kRun =
    "record --env-id FetchPush-v4 --policy scripted --episodes 2 --steps 6 --width 96 "
    "--height 96 --format apng --no-report --quiet";
const char* kAll = " --randomize colors,textures,lighting,camera";

// Compares the frames of two APNG files: per frame, the share of pixels that differ (PIL).
json FrameDifferences(const std::string& py, const fs::path& a, const fs::path& b) {
  const auto r = RunCommand(py +
                            " -c 'import sys, json\n"
                            "from PIL import Image\n"
                            "def frames(p):\n"
                            "    im = Image.open(p); out = []\n"
                            "    for t in range(im.n_frames):\n"
                            "        im.seek(t); out.append(im.convert(\"RGB\").tobytes())\n"
                            "    return out\n"
                            "A, B = frames(sys.argv[1]), frames(sys.argv[2])\n"
                            "assert len(A) == len(B), (len(A), len(B))\n"
                            "print(json.dumps([sum(x[i:i + 3] != y[i:i + 3] for i in "
                            "range(0, len(x), 3)) / (len(x) / 3) for x, y in zip(A, B)]))' '" +
                            a.string() + "' '" + b.string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return json::parse(r.output, nullptr, false);
}

json EpisodeOf(const fs::path& run, int k) {
  char name[32];
  std::snprintf(name, sizeof(name), "episode_%03d.json", k);
  return json::parse(ReadFile((run / name).string()))["episodes"][0];
}

TEST(LookRun, RecordDrawsEachEpisodeKeepsThePhysicsAndRecordFromRedrawsItExactly) {
  TempDir dir;
  const fs::path plain = dir.path() / "plain", look = dir.path() / "look";
  ASSERT_EQ(RunFetchscope(std::string(kRun) + " --out '" + plain.string() + "'").exit_code, 0);
  const auto made = RunFetchscope(std::string(kRun) + kAll + " --out '" + look.string() + "'");
  ASSERT_EQ(made.exit_code, 0) << made.output;
  const json manifest = json::parse(ReadFile((look / "manifest.json").string()));
  for (int k : {0, 1}) {
    const json a = EpisodeOf(plain, k), b = EpisodeOf(look, k);
    EXPECT_EQ(a["steps"], b["steps"]) << "episode " << k << ": the look changed the physics";
    EXPECT_FALSE(a.contains("look"));
    ASSERT_TRUE(b["look"].is_object()) << b.dump().substr(0, 300);
    EXPECT_EQ(b["look"]["kinds"], json::array({"colors", "textures", "lighting", "camera"}));
    EXPECT_EQ(manifest["episodes"][k]["look"], b["look"]) << "manifest entry " << k;
  }
  EXPECT_NE(EpisodeOf(look, 0)["look"]["seed"], EpisodeOf(look, 1)["look"]["seed"]);
  // the report lists each episode's draw, its 64-bit seed as text (a page's numbers are doubles)
  ASSERT_EQ(RunFetchscope("report '" + look.string() + "'").exit_code, 0);
  const std::string html = ReadFile((look / "index.html").string());
  EXPECT_NE(html.find("\"has_look\":true"), std::string::npos);
  EXPECT_NE(html.find("\"look_seed\":\"" + EpisodeOf(look, 1)["look"]["seed"].dump() + "\""),
            std::string::npos);

  // --from without --randomize: the stored looks; --randomize none: the plain look
  const std::string common = " --width 96 --height 96 --format apng --no-report --quiet";
  const fs::path again = dir.path() / "again", none = dir.path() / "none";
  ASSERT_EQ(RunFetchscope("record --from '" + look.string() + "'" + common + " --out '" +
                          again.string() + "'")
                .exit_code,
            0);
  ASSERT_EQ(RunFetchscope("record --from '" + look.string() + "' --randomize none" + common +
                          " --out '" + none.string() + "'")
                .exit_code,
            0);
  EXPECT_EQ(EpisodeOf(again, 1)["look"], EpisodeOf(look, 1)["look"]);
  EXPECT_FALSE(EpisodeOf(none, 1).contains("look"));

  const std::string py = testing::PythonWithPil();
  if (py.empty()) GTEST_SKIP() << "python3 with PIL not found: the frames are not compared";
  for (const char* episode : {"episode_000.apng", "episode_001.apng"}) {
    const json changed = FrameDifferences(py, plain / episode, look / episode);
    ASSERT_TRUE(changed.is_array() && changed.size() == 7u) << changed;
    for (const json& share : changed) EXPECT_GT(share.get<double>(), 0.10) << episode;
    for (const json& share : FrameDifferences(py, look / episode, again / episode)) {
      EXPECT_EQ(share.get<double>(), 0.0) << episode << ": record --from drew another look";
    }
    for (const json& share : FrameDifferences(py, plain / episode, none / episode)) {
      EXPECT_EQ(share.get<double>(), 0.0) << episode << ": --randomize none is not plain";
    }
  }
  const json between = FrameDifferences(py, look / "episode_000.apng", look / "episode_001.apng");
  EXPECT_GT(between[0].get<double>(), 0.10) << "two episodes drew the same look";
}

// A dataset under a camera draw: the look is each episode's attribute (Minari and robomimic),
// the cameras' poses are stored per step, and the stored pose with the episode's drawn fovy
// puts the object's position on pixels its segmentation names as the object.
TEST(LookRun, ADatasetStoresTheDrawAndItsCameraProjectsTheObjectOntoItsSegmentation) {
  const std::string py = testing::PythonWithH5py();
  if (py.empty()) GTEST_SKIP() << "python3 with h5py and numpy not found";
  TempDir dir;
  const auto r = RunFetchscope(
      "rollout --env-id FetchPush-v4 --policy scripted --episodes 3 --steps 8 --obs-camera "
      "external_camera_0 --obs-size 96x72 --obs-layers rgb,segmentation --randomize camera,colors "
      "--minari fs/look-v0 --minari-root '" +
      (dir.path() / "root").string() + "' --robomimic '" + (dir.path() / "demo.hdf5").string() +
      "'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string script = R"(import sys, json, h5py, numpy as np
root, demo = sys.argv[1], sys.argv[2]
f = h5py.File(root + "/fs/look-v0/data/main_data.hdf5", "r")
meta = json.load(open(root + "/fs/look-v0/data/metadata.json"))
camera = meta["pixels"]["cameras"][0]
legend = meta["pixels"]["segmentation_legend"]
object_id = [e["id"] for e in legend if e.get("body") == "object0" and not e.get("site")][0]
assert [e["body"] for e in legend if e["id"] in (25, 26)] == ["robot0:r_gripper_finger_link", "robot0:l_gripper_finger_link"]
out = {"moving": camera["moving"], "hits": 0, "tried": 0, "fovys": [], "demo_looks": 0, "looks": []}
r = h5py.File(demo, "r")
for k in range(3):
    e = f["episode_%d" % k]
    look = json.loads(e.attrs["look"])
    out["looks"].append(look)
    out["demo_looks"] += json.loads(r["data/demo_%d" % k].attrs["look"]) == look
    fovy = look["cameras"]["external_camera_0"]["fovy"]
    out["fovys"].append(fovy)
    W, H = camera["width"], camera["height"]
    fy = (H / 2) / np.tan(np.radians(fovy) / 2)
    poses = e["infos/camera_pose/external_camera_0"][()]
    seg = e["observations/segmentation/external_camera_0"][()]
    obs = e["observations/observation"][()]
    for t in range(len(poses)):
        x, y, z, qw, qx, qy, qz = poses[t]
        R = np.array([[1 - 2*(qy*qy + qz*qz), 2*(qx*qy - qz*qw), 2*(qx*qz + qy*qw)],
                      [2*(qx*qy + qz*qw), 1 - 2*(qx*qx + qz*qz), 2*(qy*qz - qx*qw)],
                      [2*(qx*qz - qy*qw), 2*(qy*qz + qx*qw), 1 - 2*(qx*qx + qy*qy)]])
        c = R.T @ (obs[t, 3:6] - np.array([x, y, z]))
        u = (W - 1) / 2 + fy * c[0] / -c[2]
        v = (H - 1) / 2 - fy * c[1] / -c[2]
        out["tried"] += 1
        hit = int(seg[t, int(round(v)), int(round(u))] == object_id)
        out["hits"] += hit
        if not hit: out.setdefault("missed", []).append([k, t, int(seg[t, int(round(v)), int(round(u))])])
print(json.dumps(out)))";
  std::ofstream(dir.path() / "project.py") << script;
  const auto p = RunCommand(py + " '" + (dir.path() / "project.py").string() + "' '" +
                            (dir.path() / "root").string() + "' '" +
                            (dir.path() / "demo.hdf5").string() + "'");
  ASSERT_EQ(p.exit_code, 0) << p.output;
  const json out = json::parse(p.output);
  EXPECT_TRUE(out["moving"].get<bool>()) << "a jittered camera's pose is stored per step";
  EXPECT_EQ(out["tried"], 27);
  // a miss is the gripper's finger in front of the block (the scripted push reaches it), never
  // the table, the floor or another body: the projection lands on the block or its occluder
  EXPECT_GE(out["hits"].get<int>(), 22) << out;
  for (const json& miss : out.value("missed", json::array())) {
    EXPECT_TRUE(miss[2] == 25 || miss[2] == 26) << "not a finger over the block: " << out;
  }
  EXPECT_EQ(out["demo_looks"], 3) << "robomimic's demos store the same draws";
  std::set<double> fovys(out["fovys"].begin(), out["fovys"].end());
  EXPECT_EQ(fovys.size(), 3u) << "each episode its own fovy: " << out["fovys"];
  // record --from the dataset draws each episode as the dataset stored it
  const fs::path again = dir.path() / "again";
  const auto from =
      RunFetchscope("record --from fs/look-v0 --minari-root '" + (dir.path() / "root").string() +
                    "' --width 64 --height 64 --no-report --quiet --out '" + again.string() + "'");
  ASSERT_EQ(from.exit_code, 0) << from.output;
  for (int k = 0; k < 3; ++k) EXPECT_EQ(EpisodeOf(again, k)["look"], out["looks"][k]) << k;
}

// --look-seed draws the same episodes under other looks: the looks of --seed 9, the states of
// --seed 0.
TEST(LookRun, ALookSeedDrawsTheSameEpisodesUnderOtherLooks) {
  TempDir dir;
  const std::string run =
      "record --env-id FetchReach-v4 --policy random --steps 3 --width 64 --height 64 "
      "--randomize colors,lighting --no-report --no-sheets --quiet";
  const fs::path a = dir.path() / "a", b = dir.path() / "b", c = dir.path() / "c";
  ASSERT_EQ(RunFetchscope(run + " --seed 0 --look-seed 9 --out '" + a.string() + "'").exit_code, 0);
  ASSERT_EQ(RunFetchscope(run + " --seed 9 --out '" + b.string() + "'").exit_code, 0);
  ASSERT_EQ(RunFetchscope(run + " --seed 0 --out '" + c.string() + "'").exit_code, 0);
  EXPECT_EQ(EpisodeOf(a, 0)["look"], EpisodeOf(b, 0)["look"]);
  EXPECT_NE(EpisodeOf(a, 0)["look"], EpisodeOf(c, 0)["look"]);
  EXPECT_EQ(EpisodeOf(a, 0)["steps"], EpisodeOf(c, 0)["steps"]);
  const auto alone = RunFetchscope("record --env-id FetchReach-v4 --look-seed 3 --out '" +
                                   (dir.path() / "d").string() + "'");
  EXPECT_EQ(alone.exit_code, 2);
  EXPECT_EQ(testing::LineCount(alone.output), 1) << alone.output;
  EXPECT_NE(alone.output.find("--look-seed 3 without --randomize"), std::string::npos)
      << alone.output;
}

TEST(LookRun, LooksWithoutImagesOrRangesWithoutLooksAreOneLine) {
  TempDir dir;
  const auto rollout = RunFetchscope("rollout --env-id FetchPush-v4 --randomize colors");
  EXPECT_EQ(rollout.exit_code, 2);
  EXPECT_EQ(testing::LineCount(rollout.output), 1) << rollout.output;
  EXPECT_NE(rollout.output.find("rollout renders none; accepted: with --obs-camera"),
            std::string::npos)
      << rollout.output;
  std::ofstream(dir.path() / "ranges.json") << R"({"camera_fovy": [-1, 1]})";
  const auto config = RunFetchscope("record --env-id FetchReach-v4 --randomize-config '" +
                                    (dir.path() / "ranges.json").string() + "' --out '" +
                                    (dir.path() / "out").string() + "'");
  EXPECT_EQ(config.exit_code, 2);
  EXPECT_EQ(testing::LineCount(config.output), 1) << config.output;
  EXPECT_NE(config.output.find("without --randomize sets ranges for nothing"), std::string::npos)
      << config.output;
  EXPECT_FALSE(fs::exists(dir.path() / "out"));
  const auto kind = RunFetchscope("record --env-id FetchReach-v4 --randomize colours --out '" +
                                  (dir.path() / "out").string() + "'");
  EXPECT_EQ(kind.exit_code, 2);
  EXPECT_EQ(testing::LineCount(kind.output), 1) << kind.output;
  EXPECT_NE(kind.output.find("colours"), std::string::npos) << kind.output;
  EXPECT_FALSE(fs::exists(dir.path() / "out"));
  // record --from a run whose stored look is not one: one line before anything is written
  const fs::path run = dir.path() / "run";
  ASSERT_EQ(RunFetchscope("record --env-id FetchReach-v4 --steps 2 --width 64 --height 64 "
                          "--randomize colors --no-report --quiet --out '" +
                          run.string() + "'")
                .exit_code,
            0);
  json edited = json::parse(ReadFile((run / "episode_000.json").string()));
  edited["episodes"][0]["look"]["kinds"] = json::array({"glitter"});
  std::ofstream(run / "episode_000.json") << edited.dump();
  const auto from = RunFetchscope("record --from '" + run.string() + "' --out '" +
                                  (dir.path() / "again").string() + "'");
  EXPECT_EQ(from.exit_code, 2) << from.output;
  EXPECT_EQ(testing::LineCount(from.output), 1) << from.output;
  EXPECT_NE(from.output.find("episode 0: look"), std::string::npos) << from.output;
  EXPECT_FALSE(fs::exists(dir.path() / "again"));
}

}  // namespace
}  // namespace fetchscope
