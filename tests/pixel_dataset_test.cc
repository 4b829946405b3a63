// Pixel datasets (docs/guide/datasets.md, "Pixel datasets"): each step's camera images in the
// Minari dataset of rollout, record and record --from, checked against `fetchscope render` and
// read back with h5py and PIL (tests/pixel/check_pixel_dataset.py): rgb bit for bit, depth within
// 1 mm, segmentation naming the same objects, the stored intrinsics and poses projecting the
// object onto its own pixels, state fields bitwise equal to a dataset without images.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "src/trajectory.h"
#include "test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using fetchscope::testing::PythonWithH5py;
using fetchscope::testing::PythonWithPil;
using fetchscope::testing::ReadFile;
using fetchscope::testing::RunCommand;
using fetchscope::testing::RunFetchscope;
using fetchscope::testing::SourceDir;
using fetchscope::testing::TempDir;

std::string Checker() { return (SourceDir() / "tests/pixel/check_pixel_dataset.py").string(); }

// Renders camera `name` (--camera `camera`) of FetchPush's scripted episode 0 at each step, as
// RENDER_DIR/NAME_tT.png with its depth and segmentation.
void RenderSteps(const fs::path& dir, const std::string& name, const std::string& camera,
                 const std::string& size, std::initializer_list<int> steps) {
  const auto x = size.find('x');
  for (int t : steps) {
    const auto r = RunFetchscope(
        "render --env-id FetchPush-v4 --policy scripted --seed 3 --overlay none --layers "
        "rgb,depth,segmentation --steps " +
        std::to_string(t) + " --camera " + camera + " --width " + size.substr(0, x) + " --height " +
        size.substr(x + 1) + " -o " + (dir / (name + "_t" + std::to_string(t) + ".png")).string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
}

TEST(PixelDataset, RolloutImagesAreRendersPixelsAndTheCamerasProjectTheObject) {
  const std::string py = PythonWithPil();
  if (py.empty()) GTEST_SKIP() << "python3-h5py, python3-numpy or python3-pil is not installed";
  unsetenv("DISPLAY");
  TempDir tmp;
  const std::string root = " --minari-root " + (tmp.path() / "ds").string();
  // a fixed model camera, the tracking camera and a free camera whose commas stay its own
  const std::string cameras =
      " --obs-camera external_camera_0 --obs-camera grip=track"
      " --obs-camera top=free:lookat=1.3,0.75,0.45,distance=1.1,azimuth=180,elevation=-75";
  auto r = RunFetchscope(
      "rollout --env-id FetchPush-v4 --policy scripted --seed 3 --episodes 2 --steps 12 --jobs 2 "
      "--minari tt/pix-v0 --obs-layers depth,rgb,segmentation --obs-size 64x48" +
      cameras + root);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunFetchscope(
      "rollout --env-id FetchPush-v4 --policy scripted --seed 3 --episodes 2 --steps 12 "
      "--minari tt/plain-v0" +
      root);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fs::path renders = tmp.path() / "renders";
  fs::create_directories(renders);
  RenderSteps(renders, "external_camera_0", "external_camera_0", "64x48", {0, 6, 12});
  RenderSteps(renders, "grip", "track", "64x48", {0, 6, 12});
  RenderSteps(renders, "top", "free:lookat=1.3,0.75,0.45,distance=1.1,azimuth=180,elevation=-75",
              "64x48", {0, 6, 12});
  r = RunCommand(py + " " + Checker() + " " + (tmp.path() / "ds/tt/pix-v0").string() + " " +
                 renders.string() + " 0,6,12 object0 " + (tmp.path() / "ds/tt/plain-v0").string() +
                 " 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // nothing of the staging is left beside the datasets
  for (const auto& entry : fs::directory_iterator(tmp.path() / "ds")) {
    EXPECT_EQ(entry.path().filename().string().rfind(".fetchscope-pixels", 0), std::string::npos)
        << entry.path();
  }
}

TEST(PixelDataset, MetadataDescribesTheCamerasAndTheLayout) {
  const std::string py = PythonWithPil();
  if (py.empty()) GTEST_SKIP() << "python3-h5py, python3-numpy or python3-pil is not installed";
  unsetenv("DISPLAY");
  TempDir tmp;
  const fs::path ds = tmp.path() / "ds";
  auto r = RunFetchscope(
      "rollout --env-id FetchReach-v4 --policy zero --episodes 1 --steps 3 --minari tt/meta-v0 "
      "--obs-camera external_camera_0 --obs-camera gripper_camera_rgb --obs-size 40x30 "
      "--minari-root " +
      ds.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string script = R"PY(
import io, json, sys
import h5py, numpy as np
from PIL import Image
d = sys.argv[1]
m = json.load(open(d + "/data/metadata.json"))
p = m["pixels"]
assert p["layers"] == ["rgb"], p["layers"]
assert (p["width"], p["height"]) == (40, 30)
cams = {c["name"]: c for c in p["cameras"]}
assert list(cams) == ["external_camera_0", "gripper_camera_rgb"], list(cams)
g = cams["gripper_camera_rgb"]
assert g["moving"] is True and "pose" not in g, g
assert abs(g["fovy"] - 50) < 1e-4, g["fovy"]
assert abs(g["fy"] - 15 / np.tan(np.radians(25))) < 1e-3 and g["fx"] == g["fy"], g
assert (g["cx"], g["cy"]) == (19.5, 14.5), g
assert g["K"] == [[g["fx"], 0.0, g["cx"]], [0.0, g["fy"], g["cy"]], [0.0, 0.0, 1.0]]
space = json.loads(m["observation_space"].replace("-Infinity", "-1e999").replace("Infinity", "1e999"))
sub = space["subspaces"]
assert list(sub) == ["achieved_goal", "desired_goal", "images", "observation"], list(sub)
box = sub["images"]["subspaces"]["gripper_camera_rgb"]
assert box["dtype"] == "uint8" and box["shape"] == [30, 40, 3], box
assert np.array(box["low"]).shape == (30, 40, 3) and np.array(box["high"]).max() == 255
f = h5py.File(d + "/data/main_data.hdf5", "r")
e = f["episode_0"]
pose = e["infos/camera_pose/gripper_camera_rgb"][()]
assert pose.shape == (4, 7), pose.shape
assert np.allclose(np.linalg.norm(pose[:, 3:], axis=1), 1)
im = e["observations/images/gripper_camera_rgb"]
assert im.shape == (4,), im.shape
a = np.array(Image.open(io.BytesIO(im[2].tobytes())))
assert a.shape == (30, 40, 3) and a.dtype == np.uint8, a.shape
print("ok")
)PY";
  const fs::path file = tmp.path() / "meta.py";
  std::ofstream(file) << script;
  r = RunCommand(py + " " + file.string() + " " + (ds / "tt/meta-v0").string() + " 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

TEST(PixelDataset, RecordAndRecordFromWriteTheSameBytesWhateverTheJobs) {
  const std::string py = PythonWithPil();
  if (py.empty()) GTEST_SKIP() << "python3-h5py, python3-numpy or python3-pil is not installed";
  unsetenv("DISPLAY");
  TempDir tmp;
  const std::string ds = (tmp.path() / "ds").string();
  const std::string common =
      " --env-id FetchPickAndPlace-v4 --policy scripted --episodes 3 --steps 10 --format webm "
      "--width 64 --height 64 --no-report -q --obs-camera external_camera_0 --obs-camera "
      "gripper_camera_rgb --obs-layers rgb,depth --obs-size 48x48 --minari-root " +
      ds;
  for (int jobs : {1, 2}) {
    const std::string j = std::to_string(jobs);
    const auto r = RunFetchscope("record" + common + " --jobs " + j + " --minari tt/rec" + j +
                                 "-v0 --robomimic " + (tmp.path() / ("rm" + j + ".hdf5")).string() +
                                 " --out " + (tmp.path() / ("run" + j)).string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  EXPECT_EQ(ReadFile(tmp.path() / "ds/tt/rec1-v0/data/main_data.hdf5"),
            ReadFile(tmp.path() / "ds/tt/rec2-v0/data/main_data.hdf5"));
  EXPECT_EQ(ReadFile(tmp.path() / "rm1.hdf5"), ReadFile(tmp.path() / "rm2.hdf5"));
  // record's robomimic file: the Minari dataset's images and each step's state
  const std::string rm =
      "import h5py, io, sys, numpy as np\n"
      "from PIL import Image\n"
      "r = h5py.File(sys.argv[1], 'r'); m = h5py.File(sys.argv[2], 'r')\n"
      "assert sorted(r['data']) == ['demo_0', 'demo_1', 'demo_2'], list(r['data'])\n"
      "for i in range(3):\n"
      "  d, e = r['data/demo_%d' % i], m['episode_%d' % i]\n"
      "  assert d['states'].shape == (10, 1 + 22 + 21 + 7), d['states'].shape\n"
      "  for t in (0, 9):\n"
      "    png = "
      "np.array(Image.open(io.BytesIO(e['observations/images/external_camera_0'][t].tobytes())))\n"
      "    assert np.array_equal(d['obs/external_camera_0_image'][t], png), (i, t)\n"
      "print('ok')\n";
  const auto rc = RunCommand(py + " -c \"" + rm + "\" " + (tmp.path() / "rm1.hdf5").string() + " " +
                             (tmp.path() / "ds/tt/rec1-v0/data/main_data.hdf5").string() + " 2>&1");
  EXPECT_EQ(rc.exit_code, 0) << rc.output;
  // the manifest lists the cameras and the dataset's images as lists, never one comma string
  const nlohmann::json m = nlohmann::json::parse(ReadFile(tmp.path() / "run1/manifest.json"));
  EXPECT_EQ(m.at("cameras"), nlohmann::json::array({"default"})) << m.at("cameras").dump();
  EXPECT_EQ(m.at("obs").at("cameras"),
            nlohmann::json::parse(R"([{"name": "external_camera_0", "camera": "external_camera_0"},
                {"name": "gripper_camera_rgb", "camera": "gripper_camera_rgb"}])"));
  EXPECT_EQ(m.at("obs").at("layers"), nlohmann::json::parse(R"(["rgb", "depth"])"));
  EXPECT_EQ(m.at("obs").at("size"), nlohmann::json::parse("[48, 48]"));
  // the run's replay writes the same images
  const auto r = RunFetchscope("record --from " + (tmp.path() / "run1").string() +
                               " --format webm --width 64 --height 64 --no-report -q "
                               "--obs-camera external_camera_0 --obs-camera gripper_camera_rgb "
                               "--obs-layers rgb,depth --obs-size 48x48 --minari tt/from-v0 "
                               "--minari-root " +
                               ds + " --out " + (tmp.path() / "from").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string script =
      "import h5py, sys\n"
      "a = h5py.File(sys.argv[1], 'r'); b = h5py.File(sys.argv[2], 'r')\n"
      "for e in a:\n"
      "  for k in ('images', 'depth'):\n"
      "    for c in a[e]['observations'][k]:\n"
      "      x, y = a[e]['observations'][k][c], b[e]['observations'][k][c]\n"
      "      assert len(x) == len(y) == 11, (len(x), len(y))\n"
      "      for t in range(len(x)):\n"
      "        assert x[t].tobytes() == y[t].tobytes(), (e, k, c, t)\n"
      "print('ok')\n";
  const auto c = RunCommand(py + " -c \"" + script + "\" " +
                            (tmp.path() / "ds/tt/rec1-v0/data/main_data.hdf5").string() + " " +
                            (tmp.path() / "ds/tt/from-v0/data/main_data.hdf5").string() + " 2>&1");
  EXPECT_EQ(c.exit_code, 0) << c.output;
  for (const auto& entry : fs::directory_iterator(tmp.path())) {
    EXPECT_EQ(entry.path().filename().string().rfind(".fetchscope-pixels", 0), std::string::npos)
        << entry.path();
  }
}

TEST(PixelDataset, ADataCollectorDatasetBecomesAPixelDatasetWithItsFieldsCopied) {
  const std::string py = PythonWithPil();
  if (py.empty()) GTEST_SKIP() << "python3-h5py, python3-numpy or python3-pil is not installed";
  unsetenv("DISPLAY");
  TempDir tmp;
  const fs::path root = tmp.path() / "ds";
  const fs::path rollout = tmp.path() / "collector.json";
  auto r = RunFetchscope(
      "rollout --env-id FetchPickAndPlace-v4 --policy random --episodes 2 --steps 8 --seed 11 "
      "--json-out " +
      rollout.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunCommand(py + " " + (SourceDir() / "tests/data/minari/minari_in_h5py.py").string() + " " +
                 root.string() + " mine/collector-v0 collector " + rollout.string() + " 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunFetchscope("record --from " + (root / "mine/collector-v0").string() +
                    " --width 40 --height 40 --format webm --no-report -q --out " +
                    (tmp.path() / "run").string() + " --minari mine/pixels-v0 --minari-root " +
                    root.string() + " --obs-camera external_camera_0 --obs-size 32x32");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string script =
      "import h5py, sys\n"
      "a = h5py.File(sys.argv[1], 'r'); b = h5py.File(sys.argv[2], 'r')\n"
      "assert sorted(a) == sorted(b), (sorted(a), sorted(b))\n"
      "for e in a:\n"
      "  for k in ('actions', 'observations/observation', 'observations/achieved_goal',\n"
      "            'observations/desired_goal', 'terminations', 'truncations'):\n"
      "    assert a[e][k][()].tobytes() == b[e][k][()].tobytes(), (e, k)\n"
      "  assert b[e]['observations/images/external_camera_0'].shape == (9,)\n"
      "print('ok')\n";
  r = RunCommand(py + " -c \"" + script + "\" " +
                 (root / "mine/collector-v0/data/main_data.hdf5").string() + " " +
                 (root / "mine/pixels-v0/data/main_data.hdf5").string() + " 2>&1");
  EXPECT_EQ(r.exit_code, 0)
      << r.output;  // a pixel dataset is a dataset record --from reads: the same images again
  r = RunFetchscope("record --from " + (root / "mine/pixels-v0").string() +
                    " --width 40 --height 40 --format webm --no-report -q --out " +
                    (tmp.path() / "again").string() + " --minari mine/again-v0 --minari-root " +
                    root.string() + " --obs-camera external_camera_0 --obs-size 32x32");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string same =
      "import h5py, sys\n"
      "a = h5py.File(sys.argv[1], 'r'); b = h5py.File(sys.argv[2], 'r')\n"
      "for e in a:\n"
      "  for k in ('actions', 'observations/observation', "
      "'observations/images/external_camera_0'):\n"
      "    x, y = a[e][k], b[e][k]\n"
      "    assert len(x) == len(y) and all(x[i].tobytes() == y[i].tobytes() for i in "
      "range(len(x))), (e, k)\n"
      "print('ok')\n";
  r = RunCommand(py + " -c \"" + same + "\" " +
                 (root / "mine/pixels-v0/data/main_data.hdf5").string() + " " +
                 (root / "mine/again-v0/data/main_data.hdf5").string() + " 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

// --robomimic beside --minari: robomimic's layout, the same pixels as the Minari dataset (obs
// row t = step t, next_obs row t = step t + 1), states, dones, masks; the same bytes for any
// --jobs; --no-next-obs leaves next_obs out.
TEST(PixelDataset, RobomimicFileHoldsRobomimicsLayoutAndTheSamePixels) {
  const std::string py = PythonWithPil();
  if (py.empty()) GTEST_SKIP() << "python3-h5py, python3-numpy or python3-pil is not installed";
  unsetenv("DISPLAY");
  TempDir tmp;
  const std::string ds = (tmp.path() / "ds").string();
  const std::string common =
      "rollout --env-id FetchPickAndPlace-v4 --policy scripted --episodes 5 --steps 12 "
      "--obs-camera external_camera_0 --obs-camera grip=track --obs-layers rgb,depth "
      "--obs-size 40x32 --minari-root " +
      ds;
  for (int jobs : {1, 2}) {
    const std::string j = std::to_string(jobs);
    const auto r = RunFetchscope(common + " --jobs " + j + " --minari tt/both" + j +
                                 "-v0 --valid-fraction 0.2 --robomimic " +
                                 (tmp.path() / ("rm" + j + ".hdf5")).string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("wrote robomimic file"), std::string::npos) << r.output;
  }
  EXPECT_EQ(ReadFile(tmp.path() / "rm1.hdf5"), ReadFile(tmp.path() / "rm2.hdf5"));
  auto r =
      RunFetchscope(common + " --no-next-obs --robomimic " + (tmp.path() / "lean.hdf5").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string script = R"PY(
import io, json, sys
import h5py, numpy as np
from PIL import Image
rm = h5py.File(sys.argv[1], "r")
mi = h5py.File(sys.argv[2] + "/data/main_data.hdf5", "r")
lean = h5py.File(sys.argv[3], "r")
data = rm["data"]
demos = sorted(data.keys(), key=lambda k: int(k[5:]))  # as get_dataset_info.py sorts them
assert demos == ["demo_%d" % i for i in range(5)], demos
env = json.loads(data.attrs["env_args"])
assert list(env) == ["env_name", "type", "env_kwargs"] and env["type"] == 2, env
assert env["env_name"] == "FetchPickAndPlace-v4" and env["env_kwargs"]["max_episode_steps"] == 12
assert data.attrs["total"] == sum(data[d].attrs["num_samples"] for d in demos) == 60
assert [m.decode() for m in rm["mask/valid"][()]] == ["demo_4"], rm["mask/valid"][()]
assert [m.decode() for m in rm["mask/train"][()]] == ["demo_%d" % i for i in range(4)]
for i, d in enumerate(demos):
    g, e = data[d], mi["episode_%d" % i]
    n = g.attrs["num_samples"]
    assert n == 12 and g["actions"].dtype == np.float64 and g["actions"].shape == (12, 4)
    assert np.array_equal(g["actions"][()], e["actions"][()].astype(np.float64))
    assert np.array_equal(g["rewards"][()], e["rewards"][()].astype(np.float64))
    assert g["dones"].dtype == np.int64 and g["dones"][-1] == 1
    assert np.array_equal(g["dones"][:-1], e["infos/is_success"][1:-1].astype(np.int64))
    st = g["states"][()]
    assert st.dtype == np.float64 and st.shape[0] == 12
    assert np.allclose(np.diff(st[:, 0]), 0.04), st[:, 0]  # time, 20 substeps of 2 ms
    for k in ("observation", "achieved_goal", "desired_goal"):
        assert np.array_equal(g["obs"][k][()], e["observations"][k][:-1]), k
        assert np.array_equal(g["next_obs"][k][()], e["observations"][k][1:]), k
    for cam in ("external_camera_0", "grip"):
        im = g["obs"][cam + "_image"]
        assert im.dtype == np.uint8 and im.shape == (12, 32, 40, 3), im.shape
        dp = g["obs"][cam + "_depth"]
        assert dp.dtype == np.float32 and dp.shape == (12, 32, 40, 1), dp.shape
        for t in (0, 5, 11):
            png = np.array(Image.open(io.BytesIO(e["observations/images"][cam][t].tobytes())))
            assert np.array_equal(im[t], png), (d, cam, t)
            nxt = np.array(Image.open(io.BytesIO(e["observations/images"][cam][t + 1].tobytes())))
            assert np.array_equal(g["next_obs"][cam + "_image"][t], nxt), (d, cam, t)
            assert np.array_equal(dp[t][..., 0], e["observations/depth"][cam][t]), (d, cam, t)
        assert np.array_equal(g["obs"][cam + "_camera_pose"][()], e["infos/camera_pose"][cam][:-1])
    assert "next_obs" not in lean["data"][d] and "obs" in lean["data"][d]
    assert "mask" not in lean
print("ok")
)PY";
  const fs::path file = tmp.path() / "robomimic.py";
  std::ofstream(file) << script;
  r = RunCommand(py + " " + file.string() + " " + (tmp.path() / "rm1.hdf5").string() + " " +
                 (tmp.path() / "ds/tt/both1-v0").string() + " " +
                 (tmp.path() / "lean.hdf5").string() + " 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

// --stop-after-success K cuts an episode K steps after its first success and leaves every episode
// the start of the same episode without it (the random policy's draws included), whatever --jobs;
// --keep successful keeps the successes, says how many were tried and lists them.
TEST(EpisodeSelection, StopAfterSuccessCutsAndKeepSuccessfulKeepsTheSuccesses) {
  const std::string py = PythonWithH5py();
  if (py.empty()) GTEST_SKIP() << "python3-h5py is not installed";
  TempDir tmp;
  const std::string run =
      "rollout --env-id FetchReach-v4 --policy random --episodes 30 --steps 50 --seed 5 ";
  const fs::path full = tmp.path() / "full.json", cut = tmp.path() / "cut.json";
  auto r = RunFetchscope(run + "--json-out " + full.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunFetchscope(run + "--jobs 2 --stop-after-success 2 --json-out " + cut.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Trajectory a = ReadTrajectory(full.string()), b = ReadTrajectory(cut.string());
  ASSERT_EQ(a.episodes.size(), b.episodes.size());
  int shorter = 0;
  std::vector<int> successes;
  for (size_t k = 0; k < a.episodes.size(); ++k) {
    const TrajectoryEpisode &x = a.episodes[k], &y = b.episodes[k];
    if (x.steps.back().is_success) successes.push_back(static_cast<int>(k));
    ASSERT_LE(y.steps.size(), x.steps.size());
    EXPECT_TRUE(y.complete);
    nlohmann::json prefix = StepsJson(x);
    prefix.erase(prefix.begin() + static_cast<long>(y.steps.size()), prefix.end());
    EXPECT_EQ(StepsJson(y), prefix) << "episode " << k;
    if (y.steps.size() < x.steps.size()) {
      ++shorter;
      int first = -1;  // it ends 2 steps after its first success after a step
      for (size_t t = 1; t < x.steps.size() && first < 0; ++t) {
        if (x.steps[t].is_success) first = static_cast<int>(t);
      }
      EXPECT_EQ(static_cast<int>(y.steps.size()) - 1, first + 2) << "episode " << k;
    }
  }
  EXPECT_GE(shorter, 1);  // the seed makes some: the check above ran
  ASSERT_FALSE(successes.empty());
  r = RunFetchscope(run + "--keep successful --minari tt/keep-v0 --minari-root " +
                    (tmp.path() / "ds").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("kept " + std::to_string(successes.size()) +
                          " successful episode(s) of 30 tried"),
            std::string::npos)
      << r.output;
  const nlohmann::json meta =
      nlohmann::json::parse(ReadFile(tmp.path() / "ds/tt/keep-v0/data/metadata.json"));
  EXPECT_EQ(meta.at("total_episodes").get<size_t>(), successes.size());
  EXPECT_EQ(meta.at("selection").at("episodes").get<std::vector<int>>(), successes);
  EXPECT_EQ(meta.at("selection").at("tried").get<int>(), 30);
  // no success at all: nothing written, one line
  r = RunFetchscope(
      "rollout --env-id FetchReach-v4 --policy zero --episodes 2 --steps 3 --keep successful "
      "--minari tt/none-v0 --minari-root " +
      (tmp.path() / "ds").string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("none of the 2 episode(s) ended in success"), std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(tmp.path() / "ds/tt/none-v0"));
}

// record --no-sheets: no contact sheet, a manifest without one, a report, and --resume keeps the
// episodes recorded so.
TEST(DatasetRun, NoSheetsWritesNoSheetAndResumes) {
  unsetenv("DISPLAY");
  TempDir tmp;
  const std::string out = (tmp.path() / "run").string();
  const std::string args =
      "record --env-id FetchReach-v4 --policy scripted --steps 6 --width "
      "48 --height 48 --format webm --no-sheets --out " +
      out;
  auto r = RunFetchscope(args + " --episodes 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunFetchscope(args + " --episodes 3 --resume");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const auto& entry : fs::directory_iterator(out)) {
    EXPECT_EQ(entry.path().string().find("sheet"), std::string::npos) << entry.path();
  }
  const nlohmann::json m = nlohmann::json::parse(ReadFile(fs::path(out) / "manifest.json"));
  EXPECT_EQ(m.at("sheet_every").get<int>(), -1);
  ASSERT_EQ(m.at("episodes").size(), 3u);
  for (const auto& e : m.at("episodes")) EXPECT_FALSE(e.contains("sheet")) << e.dump();
  EXPECT_TRUE(fs::exists(fs::path(out) / "index.html"));
  EXPECT_NE(r.output.find("2 kept by --resume"), std::string::npos) << r.output;
}

// rollout --shard I/N writes one dataset per shard; merge-datasets joins them, in any order, into
// the dataset of the whole run (every group, dataset, attribute and value the same; metadata.json
// the same but for the id), Minari and robomimic alike; shards of another run, a shard twice or
// one missing are refused.
TEST(DatasetShards, MergeGivesTheWholeRunsDataset) {
  const std::string py = PythonWithPil();
  if (py.empty()) GTEST_SKIP() << "python3-h5py, python3-numpy or python3-pil is not installed";
  unsetenv("DISPLAY");
  TempDir tmp;
  const fs::path ds = tmp.path() / "ds";
  const std::string run =
      "rollout --env-id FetchPush-v4 --policy random --episodes 7 --steps 8 --seed 4 "
      "--obs-camera external_camera_0 --obs-size 32x32 --obs-layers rgb,depth --minari-root " +
      ds.string();
  auto r = RunFetchscope(run + " --minari tt/whole-v0 --robomimic " +
                         (tmp.path() / "whole.hdf5").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (int i = 0; i < 3; ++i) {
    const std::string n = std::to_string(i);
    r = RunFetchscope(run + " --shard " + n + "/3 --minari tt/s" + n + "-v0 --robomimic " +
                      (tmp.path() / ("s" + n + ".hdf5")).string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  const std::string root = " --minari-root " + ds.string();
  r = RunFetchscope("merge-datasets --minari tt/merged-v0 tt/s2-v0 tt/s0-v0 tt/s1-v0" + root);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("3 shard(s), 7 episode(s)"), std::string::npos) << r.output;
  const fs::path s0 = tmp.path() / "s0.hdf5", s1 = tmp.path() / "s1.hdf5",
                 s2 = tmp.path() / "s2.hdf5";
  r = RunFetchscope("merge-datasets --robomimic " + (tmp.path() / "merged.hdf5").string() + " " +
                    s1.string() + " " + s2.string() + " " + s0.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string same = py + " " + (SourceDir() / "tests/pixel/same_hdf5.py").string() + " ";
  r = RunCommand(same + (ds / "tt/whole-v0/data/main_data.hdf5").string() + " " +
                 (ds / "tt/merged-v0/data/main_data.hdf5").string() + " 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = RunCommand(same + (tmp.path() / "whole.hdf5").string() + " " +
                 (tmp.path() / "merged.hdf5").string() + " 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  std::string merged_meta = ReadFile(ds / "tt/merged-v0/data/metadata.json");
  const std::string id = "\"tt/merged-v0\"";
  merged_meta.replace(merged_meta.find(id), id.size(), "\"tt/whole-v0\"");
  EXPECT_EQ(merged_meta, ReadFile(ds / "tt/whole-v0/data/metadata.json"));
  // refused, each in one line, nothing written
  r = RunFetchscope("merge-datasets --minari tt/bad-v0 tt/s0-v0 tt/s1-v0" + root);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("missing shard(s) 2 of 3"), std::string::npos) << r.output;
  r = RunFetchscope("merge-datasets --minari tt/bad-v0 tt/s0-v0 tt/s0-v0 tt/s1-v0 tt/s2-v0" + root);
  EXPECT_NE(r.output.find("is shard 0 again"), std::string::npos) << r.output;
  r = RunFetchscope("merge-datasets --minari tt/bad-v0 tt/whole-v0" + root);
  EXPECT_NE(r.output.find("records no shard of a run"), std::string::npos) << r.output;
  r = RunFetchscope(
      "rollout --env-id FetchPush-v4 --policy random --episodes 7 --steps 8 --seed 5 "
      "--obs-camera external_camera_0 --obs-size 32x32 --obs-layers rgb,depth --shard 1/3 "
      "--minari tt/other-v0" +
      root);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunFetchscope("merge-datasets --minari tt/bad-v0 tt/s0-v0 tt/other-v0 tt/s2-v0" + root);
  EXPECT_NE(r.output.find("is a shard of another run"), std::string::npos) << r.output;
  EXPECT_EQ(fetchscope::testing::LineCount(r.output), 1) << r.output;
  EXPECT_FALSE(fs::exists(ds / "tt/bad-v0"));
}

// Peak RSS (KiB) of `fetchscope ARGS` run to its end (wait4's ru_maxrss); -1 when it failed.
long PeakRssKiB(const std::string& args) {
  const std::string command =
      "exec " + fetchscope::testing::FetchscopeBinary() + " " + args + " >/dev/null 2>&1";
  const pid_t pid = fork();
  if (pid == 0) {
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  int status = 0;
  rusage usage{};
  if (wait4(pid, &status, 0, &usage) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    return -1;
  }
  return usage.ru_maxrss;
}

// Memory stays flat over a long pixel run: 600 episodes take no more than 60 (the staging
// files and the writer's buffers are per episode, not per run).
TEST(PixelDataset, MemoryStaysFlatOverALongRun) {
  unsetenv("DISPLAY");
  TempDir tmp;
  const std::string args =
      "rollout --env-id FetchPush-v4 --policy random --steps 5 --obs-camera external_camera_0 "
      "--obs-size 32x32 --obs-layers rgb,depth --robomimic " +
      (tmp.path() / "r.hdf5").string() + " --overwrite --minari-root " +
      (tmp.path() / "ds").string() + " --minari tt/long-v0 --episodes ";
  const long short_run = PeakRssKiB(args + "60");
  const long long_run = PeakRssKiB(args + "600");
  ASSERT_GT(short_run, 0);
  ASSERT_GT(long_run, 0);
  RecordProperty("rss_60_episodes_kib", std::to_string(short_run));
  RecordProperty("rss_600_episodes_kib", std::to_string(long_run));
  std::printf("peak RSS: 60 episodes %ld KiB, 600 episodes %ld KiB\n", short_run, long_run);
  // 540 more episodes x 6 steps x (32x32 rgb + depth) = 23 MB of images if any were kept
  EXPECT_LT(long_run - short_run, 8 * 1024);
}

// SIGINT during a pixel run: exit 130, nothing written, no staging folder and no datasets folder
// that the run made.
TEST(PixelDataset, InterruptedRunLeavesNothing) {
  unsetenv("DISPLAY");
  TempDir tmp;
  const fs::path root = tmp.path() / "ds";
  const pid_t pid = fetchscope::testing::SpawnFetchscope(
      "rollout --env-id FetchPush-v4 --episodes 400 --steps 50 --jobs 2 --minari tt/sig-v0 "
      "--obs-camera external_camera_0 --obs-size 64x64 --minari-root " +
          root.string(),
      tmp.path() / "log");
  // interrupted once the workers are writing images
  bool staging = false;
  for (int i = 0; i < 600 && !staging; ++i) {
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(root, ec)) {
      staging = staging || e.path().filename().string().rfind(".fetchscope-pixels", 0) == 0;
    }
    if (!staging) usleep(100 * 1000);
  }
  ASSERT_TRUE(staging) << ReadFile(tmp.path() / "log");
  // the staging folder comes before the scheduler installs its handlers: wait for them, so that
  // SIGINT is the command's to handle even on a loaded machine
  ASSERT_TRUE(fetchscope::testing::WaitForSignalHandler(pid, SIGINT))
      << ReadFile(tmp.path() / "log");
  kill(pid, SIGINT);
  EXPECT_EQ(fetchscope::testing::WaitExit(pid), 130) << ReadFile(tmp.path() / "log");
  EXPECT_NE(ReadFile(tmp.path() / "log").find("interrupted (SIGINT); nothing written"),
            std::string::npos);
  EXPECT_FALSE(fs::exists(root)) << "the run left " << root;
}

// Each bad value: one line naming it, a non-zero exit, no dataset and no staging folder.
TEST(PixelDataset, BadInputIsOneLineAndWritesNothing) {
  unsetenv("DISPLAY");
  TempDir tmp;
  const std::string base =
      "rollout --env-id FetchPush-v4 --policy zero --episodes 1 --steps 2 "
      "--minari-root " +
      (tmp.path() / "ds").string();
  const struct {
    std::string args, expect;
  } cases[] = {
      {" --minari tt/x-v0 --obs-camera nosuchcam", "nosuchcam"},
      {" --minari tt/x-v0 --obs-camera external_camera_0 --obs-size 0x10", "--obs-size '0x10'"},
      {" --minari tt/x-v0 --obs-camera external_camera_0 --obs-size 100000x5",
       "--obs-size '100000x5'"},
      {" --minari tt/x-v0 --obs-camera a=external_camera_0 --obs-camera a=track",
       "'a' is given twice"},
      {" --obs-camera external_camera_0", "give --minari"},
      {" --minari tt/x-v0 --obs-size 64x64", "--obs-size applies to the images of --obs-camera"},
      {" --minari tt/x-v0 --obs-camera track", "needs a NAME="},
      {" --minari tt/x-v0 --obs-camera external_camera_0,track", "names 2 cameras"},
      {" --minari tt/x-v0 --obs-camera external_camera_0 --obs-layers rgb,normals",
       "--obs-layers: unknown layer 'normals'"},
      {" --minari tt/x-v0 --no-next-obs", "--no-next-obs applies to the file of --robomimic"},
      {" --robomimic " + (tmp.path() / "r.hdf5").string() + " --valid-fraction 1",
       "--valid-fraction 1"},
      {" --robomimic " + (tmp.path() / "r.txt").string(), "ending in .hdf5 or .h5"},
      {" --minari tt/x-v0 --keep some", "--keep 'some': use all or successful"},
      {" --keep successful", "--keep successful chooses the episodes of a dataset"},
  };
  for (const auto& c : cases) {
    const auto r = RunFetchscope(base + c.args);
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_NE(r.output.find(c.expect), std::string::npos) << c.args << "\n" << r.output;
    EXPECT_EQ(fetchscope::testing::LineCount(r.output), 1) << c.args << "\n" << r.output;
    EXPECT_EQ(r.output.find("terminate"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(tmp.path() / "ds/tt/x-v0")) << c.args;
    EXPECT_FALSE(fs::exists(tmp.path() / "r.hdf5")) << c.args;
  }
  if (fs::exists(tmp.path() / "ds")) {
    for (const auto& entry : fs::recursive_directory_iterator(tmp.path() / "ds")) {
      EXPECT_EQ(entry.path().filename().string().rfind(".fetchscope-pixels", 0), std::string::npos)
          << entry.path();
    }
  }
}

}  // namespace
}  // namespace fetchscope
