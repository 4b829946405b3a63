// record --from DATASET (docs/guide/datasets.md): a Minari dataset re-rendered. The round trip
// rollout --minari -> record --from gives back the rollout's trajectories bit for bit; datasets
// written in Minari 0.5's own layout by python3-h5py (create_dataset_from_buffers with per-episode
// 64-bit seeds, DataCollector without seeds) replay with zero divergence, the seedless one from
// each episode's first observation; a perturbed dataset reports its first divergence and still
// renders; a bad dataset is one line naming the file, with nothing written.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "render/overlay.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/fetch_env.h"
#include "src/trajectory.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::PythonWithH5py;
using testing::ReadFile;
using testing::ReplaceMinariActions;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::SourceDir;
using testing::TempDir;
using testing::WriteEdited;

std::string Script() { return (SourceDir() / "tests/data/minari/minari_in_h5py.py").string(); }

const char* kSmall = " --width 40 --height 40 --no-report --quiet ";

// every step of `a` equals `b`'s, bit for bit: observation, goals, action and its dtype,
// reward, success
void ExpectSameSteps(const TrajectoryEpisode& a, const TrajectoryEpisode& b) {
  ASSERT_EQ(a.steps.size(), b.steps.size());
  for (size_t t = 0; t < a.steps.size(); ++t) {
    SCOPED_TRACE("step " + std::to_string(t));
    const TrajectoryStep& x = a.steps[t];
    const TrajectoryStep& y = b.steps[t];
    EXPECT_EQ(x.obs.observation, y.obs.observation);
    EXPECT_EQ(x.obs.achieved_goal, y.obs.achieved_goal);
    EXPECT_EQ(x.obs.desired_goal, y.obs.desired_goal);
    ASSERT_EQ(x.action.has_value(), y.action.has_value());
    if (x.action) {
      EXPECT_EQ(x.action->value, y.action->value);
      EXPECT_EQ(x.action->is_float32, y.action->is_float32);
    }
    EXPECT_EQ(x.reward, y.reward);
    EXPECT_EQ(x.is_success, y.is_success);
  }
}

// the record run's episode k, as its episode_NNN.json holds it
TrajectoryEpisode RecordedEpisode(const fs::path& run, int k) {
  char name[32];
  std::snprintf(name, sizeof name, "episode_%03d.json", k);
  const Trajectory t = ReadTrajectory((run / name).string());
  EXPECT_EQ(t.episodes.size(), 1u);
  return t.episodes.at(0);
}

json Manifest(const fs::path& run) { return json::parse(ReadFile(run / "manifest.json")); }

// each episode's manifest "reset" and its divergence: none, and not even a rounding error
void ExpectNoDivergence(const json& manifest, const std::vector<std::string>& resets) {
  ASSERT_EQ(manifest["episodes"].size(), resets.size()) << manifest.dump();
  for (size_t k = 0; k < resets.size(); ++k) {
    const json& e = manifest["episodes"][k];
    EXPECT_EQ(e["reset"], resets[k]) << k;
    EXPECT_TRUE(e["divergence"]["first_step"].is_null()) << e.dump();
    EXPECT_EQ(e["divergence"]["max_difference"], 0.0) << e.dump();
    EXPECT_EQ(e["divergence"]["tolerance"], 1e-6);
  }
}

// A reset rebuilt from the first observation is the seeded reset, bit for bit, and so are the
// steps after it (one mj_forward from the same state: the same warm start).
TEST(ResetTo, RebuildsASeededResetExactly) {
  for (const char* id :
       {"FetchReach-v4", "FetchPush-v4", "FetchPickAndPlace-v4", "FetchSlide-v4"}) {
    SCOPED_TRACE(id);
    const EnvSpec& spec = FindEnvSpec(id);
    FetchEnv a(spec, ResolveAssets("bundled")), b(spec, ResolveAssets("bundled"));
    for (uint64_t seed : {1u, 77u}) {
      const Observation want = a.Reset(seed);
      std::optional<ObjectPose> pose;
      if (spec.has_object) {
        pose = ObjectPose{{want.observation[3], want.observation[4], want.observation[5]},
                          {want.observation[11], want.observation[12], want.observation[13]}};
      }
      b.Reset(seed + 1);  // another episode's state and warm start before
      const Observation got = b.ResetTo(want.desired_goal, pose);
      EXPECT_EQ(got.observation, want.observation);
      EXPECT_EQ(got.desired_goal, want.desired_goal);
      for (int t = 0; t < 5; ++t) {
        Action action;
        action.is_float32 = true;
        action.value = {0.5, -0.25, t * 0.125, 1.0};
        EXPECT_EQ(b.Step(action).obs.observation, a.Step(action).obs.observation) << t;
      }
    }
  }
  // a rotated object: the Euler angles turn back into a quaternion
  const std::array<double, 3> euler = {0.1, -0.2, 0.3};
  const std::array<double, 4> q = Euler2Quat(euler);
  double mat[9];
  mju_quat2Mat(mat, q.data());
  const std::array<double, 3> back = Mat2Euler(mat);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(back[i], euler[i], 1e-15);
}

// The ghost overlay: on by default, off with "none", drawn only where the frame has a ghost.
TEST(GhostOverlay, DrawsTheDatasetsAchievedGoal) {
  EXPECT_TRUE(ParseOverlays("default").ghost);
  EXPECT_FALSE(ParseOverlays("none").ghost);
  EXPECT_FALSE(ParseOverlays("goal,hud").ghost);
  EXPECT_TRUE(ParseOverlays("goal,achieved,hud,labels").ghost);  // record's --overlay default
  EXPECT_TRUE(ParseOverlays("goal,ghost").ghost);
  EXPECT_TRUE(ParseOverlays("all").ghost);
  const EnvSpec& spec = FindEnvSpec("FetchPush-v4");
  FetchEnv env(spec, ResolveAssets("bundled"));
  mjvScene scene;
  mjv_defaultScene(&scene);
  mjv_makeScene(env.model(), &scene, 100);
  FrameInfo info;
  info.achieved = {1.3, 0.7, 0.42};
  info.goal = {1.2, 0.8, 0.42};
  const Trail trail;
  AddOverlayGeoms(OverlaySet{}, info, info.achieved, trail, false, &scene);
  const int without = scene.ngeom;
  std::vector<std::array<float, 3>> others;  // the colours of every other overlay geom
  for (int i = 0; i < without; ++i) {
    const float* c = scene.geoms[i].rgba;
    others.push_back({c[0], c[1], c[2]});
  }
  EXPECT_EQ(FormatHud(info, OverlaySet{}).labels.find("ghost"), std::string::npos);
  scene.ngeom = 0;
  info.ghost = std::array<double, 3>{1.3, 0.7, 0.45};
  AddOverlayGeoms(OverlaySet{}, info, info.achieved, trail, false, &scene);
  EXPECT_EQ(scene.ngeom, without + 4);  // the cross's three bars and its line
  // the ghost's geoms: opaque, in a colour no other overlay geom has; bars 6 cm long (many
  // pixels at 480x480)
  int ghost = 0;
  for (int i = 0; i < scene.ngeom; ++i) {
    const float* c = scene.geoms[i].rgba;
    if (std::find(others.begin(), others.end(), std::array<float, 3>{c[0], c[1], c[2]}) !=
        others.end()) {
      continue;
    }
    ++ghost;
    EXPECT_EQ(c[3], 1.0f);
    if (scene.geoms[i].type == mjGEOM_CAPSULE) {
      EXPECT_GE(2 * scene.geoms[i].size[2], 0.05f);
    }
  }
  EXPECT_EQ(ghost, 4);
  const HudText hud = FormatHud(info, OverlaySet{});
  EXPECT_NE(hud.labels.find("ghost"), std::string::npos);
  EXPECT_NE(hud.values.find("30.0 mm off (blue +)"), std::string::npos) << hud.values;
  scene.ngeom = 0;
  AddOverlayGeoms(ParseOverlays("goal,hud"), info, info.achieved, trail, false, &scene);
  EXPECT_EQ(scene.ngeom, without - 3);  // neither the achieved marker (2 geoms, halo) nor the ghost
  mjv_freeScene(&scene);
}

// rollout --minari, then record --from the id: the rollout's trajectories, bit for bit
// (random policy: float32 actions, as the dataset stores them). Episode 0 resets with its seed,
// the others, which continued the generator, by continuing it (their first rows match).
TEST(RecordFromDataset, RoundTripIsBitForBit) {
  unsetenv("DISPLAY");
  TempDir tmp;
  const fs::path root = tmp.path() / "datasets", run = tmp.path() / "run";
  auto r = RunFetchscope(
      "rollout --env-id FetchPush-v4 --policy random --episodes 3 --steps 12 "
      "--seed 4 --minari rt/push-v0 --minari-root " +
      root.string() + " --json-out " + (tmp.path() / "t.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunFetchscope("record --from rt/push-v0 --minari-root " + root.string() +
                    " --width 40 --height 40 --no-report --out " + run.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("Minari dataset rt/push-v0 (" +
                          (root / "rt/push-v0/data/main_data.hdf5").string() +
                          "): env FetchPush-v4 (env_spec), 3 of 3 episode(s), 36 steps, seeds 1 "
                          "of 3, minari_version 0.5.0"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("episode 0: reset from its seed; replays within 1e-06"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("episode 2: reset by continuing the generator of episode 0's seed; "
                          "replays within 1e-06"),
            std::string::npos)
      << r.output;
  const Trajectory t = ReadTrajectory((tmp.path() / "t.json").string());
  for (const TrajectoryEpisode& e : t.episodes) {
    SCOPED_TRACE(e.index);
    ExpectSameSteps(RecordedEpisode(run, e.index), e);
  }
  const json m = Manifest(run);
  ExpectNoDivergence(m, {"seed", "continued generator", "continued generator"});
  EXPECT_EQ(m["env_id"], "FetchPush-v4");
  EXPECT_EQ(m["from"], "rt/push-v0");
  EXPECT_NE(m["dataset"]["found"].get<std::string>().find("rt/push-v0"), std::string::npos);
  // --jobs 2: the same episode files, byte for byte
  const fs::path run2 = tmp.path() / "run2";
  r = RunFetchscope("record --from rt/push-v0 --minari-root " + root.string() + " --jobs 2" +
                    kSmall + "--out " + run2.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* file : {"episode_000.json", "episode_002.json", "episode_002.mp4"}) {
    EXPECT_TRUE(ReadFile(run / file) == ReadFile(run2 / file)) << file;
  }
  // --episodes picks the first ones; a conflicting --env-id is refused naming both
  r = RunFetchscope("record --from rt/push-v0 --minari-root " + root.string() +
                    " --episodes 1 --overwrite" + kSmall + "--out " + run.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(Manifest(run)["episodes"].size(), 1u);
  r = RunFetchscope("record --from rt/push-v0 --minari-root " + root.string() +
                    " --env-id FetchReach-v4" + kSmall + "--out " + (tmp.path() / "x").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--env-id FetchReach-v4 conflicts with the dataset's env_spec id "
                          "FetchPush-v4"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(tmp.path() / "x"));
}

// Datasets in Minari 0.5's own layout, of the genuine env's episodes: create_dataset_from_buffers
// with a 64-bit seed per episode (dense: float64 rewards), and DataCollector without seeds
// (sparse: float32 rewards; episodes after the first continued the generator, so only their
// first observation says how they start). Both replay with zero divergence.
TEST(RecordFromDataset, MinarisOwnLayoutWithAndWithoutSeeds) {
  const std::string py = PythonWithH5py();
  if (py.empty()) GTEST_SKIP() << "python3-h5py is not installed";
  unsetenv("DISPLAY");
  TempDir tmp;
  const fs::path root = tmp.path() / "datasets";
  // buffers: one rollout per seed, each episode reset with its own seed
  std::string files;
  int i = 0;
  for (const char* seed : {"18446744073709551611", "9007199254740993", "7"}) {
    const fs::path file = tmp.path() / ("seed" + std::to_string(i++) + ".json");
    const auto r = RunFetchscope(
        "rollout --env-id FetchPushDense-v4 --policy random --episodes 1 "
        "--steps 15 --seed " +
        std::string(seed) + " --json-out " + file.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    files += " " + file.string();
  }
  auto r = RunCommand(py + " " + Script() + " " + root.string() + " mine/buffers-v0 buffers" +
                      files + " 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fs::path run = tmp.path() / "run";
  r = RunFetchscope("record --from " + (root / "mine/buffers-v0").string() + kSmall + "--out " +
                    run.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ExpectNoDivergence(Manifest(run), {"seed", "seed", "seed"});
  for (int k = 0; k < 3; ++k) {
    const Trajectory t =
        ReadTrajectory((tmp.path() / ("seed" + std::to_string(k) + ".json")).string());
    ExpectSameSteps(RecordedEpisode(run, k), t.episodes.at(0));
  }
  // collector: one rollout, no seeds stored; given as its main_data.hdf5
  const fs::path rollout = tmp.path() / "collector.json";
  r = RunFetchscope(
      "rollout --env-id FetchPickAndPlace-v4 --policy random --episodes 3 "
      "--steps 20 --seed 11 --json-out " +
      rollout.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunCommand(py + " " + Script() + " " + root.string() + " mine/collector-v0 collector " +
                 rollout.string() + " 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fs::path run2 = tmp.path() / "run2";
  r = RunFetchscope("record --from " + (root / "mine/collector-v0/data/main_data.hdf5").string() +
                    " --width 40 --height 40 --no-report --out " + run2.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("seeds none (each reset rebuilt from its first observation)"),
            std::string::npos)
      << r.output;
  ExpectNoDivergence(Manifest(run2),
                     {"first observation", "first observation", "first observation"});
  const Trajectory t = ReadTrajectory(rollout.string());
  for (const TrajectoryEpisode& e : t.episodes) ExpectSameSteps(RecordedEpisode(run2, e.index), e);
}

// A dataset whose observation was edited: its first step over the tolerance, the value and the
// difference, in the console, the manifest and the report; every frame is still rendered.
TEST(RecordFromDataset, PerturbedObservationsReportTheirFirstDivergence) {
  const std::string py = PythonWithH5py();
  if (py.empty()) GTEST_SKIP() << "python3-h5py is not installed";
  unsetenv("DISPLAY");
  TempDir tmp;
  const fs::path root = tmp.path() / "datasets", rollout = tmp.path() / "r.json";
  auto r = RunFetchscope(
      "rollout --env-id FetchPush-v4 --policy random --episodes 2 --steps 12 "
      "--seed 5 --json-out " +
      rollout.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  json j = json::parse(ReadFile(rollout));
  j["episodes"][1]["steps"][7]["observation"][3] =
      j["episodes"][1]["steps"][7]["observation"][3].get<double>() + 1e-3;
  j["episodes"][1]["steps"][9]["observation"][5] =
      j["episodes"][1]["steps"][9]["observation"][5].get<double>() + 1.0;
  { std::ofstream(rollout) << j.dump(); }
  r = RunCommand(py + " " + Script() + " " + root.string() + " edited/push-v0 collector " +
                 rollout.string() + " 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fs::path run = tmp.path() / "run";
  r = RunFetchscope("record --from edited/push-v0 --minari-root " + root.string() +
                    " --width 40 --height 40 --out " + run.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // the component as describe names it, positions in mm, and where the largest difference is
  EXPECT_NE(r.output.find("episode 1: reset from its first observation; diverges at step 7 in "
                          "object_pos.x (observation[3]) by -1 mm (tolerance 1e-06); largest "
                          "difference -1000 mm in object_pos.z (observation[5]) at step 9"),
            std::string::npos)
      << r.output;
  const json m = Manifest(run);
  EXPECT_TRUE(m["episodes"][0]["divergence"]["first_step"].is_null());
  const json& d = m["episodes"][1]["divergence"];
  EXPECT_EQ(d["first_step"], 7);
  EXPECT_EQ(d["where"], "observation[3]");
  EXPECT_EQ(d["component"], "object_pos.x");
  EXPECT_EQ(d["unit"], "m");
  EXPECT_EQ(d["max_step"], 9);
  EXPECT_EQ(d["max_component"], "object_pos.z");
  EXPECT_NEAR(d["difference"].get<double>(), -1e-3, 1e-12);
  EXPECT_NEAR(d["max_difference"].get<double>(), 1.0, 1e-12);
  EXPECT_EQ(m["episodes"][1]["frames"], 13);  // still rendered, every frame
  EXPECT_TRUE(fs::is_regular_file(run / "episode_001.mp4"));
  // --tolerance above the edit: no divergence at step 7, the 1.0 one stays
  r = RunFetchscope("record --from edited/push-v0 --minari-root " + root.string() +
                    " --tolerance 0.01 --overwrite --width 40 --height 40 --quiet --out " +
                    run.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(Manifest(run)["episodes"][1]["divergence"]["first_step"], 9);
  // the report's data: a "reset" and "divergence" column per episode
  const std::string html = ReadFile(run / "index.html");
  EXPECT_NE(html.find("\"has_replay\":true"), std::string::npos);
  EXPECT_NE(html.find("\"first_step\":9,"), std::string::npos);
  EXPECT_NE(html.find("\"where\":\"observation[5]\""), std::string::npos);
  EXPECT_NE(html.find("\"reset\":\"first observation\""), std::string::npos);
}

// Every bad dataset: one line naming the file and what is wrong, a non-zero exit, no --out.
class RecordFromBadDataset : public ::testing::Test {
 protected:
  void SetUp() override {
    unsetenv("DISPLAY");
    root_ = tmp_.path() / "datasets";
    const auto r = RunFetchscope(
        "rollout --env-id FetchPush-v4 --policy random --episodes 2 "
        "--steps 6 --seed 3 --minari bad/push-v0 --minari-root " +
        root_.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    metadata_ = ReadFile(Metadata());
  }
  fs::path Hdf5() const { return root_ / "bad/push-v0/data/main_data.hdf5"; }
  fs::path Metadata() const { return root_ / "bad/push-v0/data/metadata.json"; }
  void EditMetadata(const std::string& from, const std::string& to) {
    WriteEdited(Metadata(), metadata_, from, to);
  }
  void ReplaceActions(size_t rows) { ReplaceMinariActions(Hdf5(), "episode_1", rows); }
  void ExpectOneLine(const fs::path& file, const std::string& what) {
    const fs::path out = tmp_.path() / "out";
    const auto r = RunFetchscope("record --from bad/push-v0 --minari-root " + root_.string() +
                                 " --width 40 --height 40 --out " + out.string());
    EXPECT_NE(r.exit_code, 0) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_NE(r.output.find(file.string() + ": "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(what), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out)) << r.output;
  }

  TempDir tmp_;
  fs::path root_;
  std::string metadata_;
};

TEST_F(RecordFromBadDataset, MissingKey) {
  ReplaceActions(0);
  ExpectOneLine(Hdf5(), "episode_1: missing key 'actions'");
}

TEST_F(RecordFromBadDataset, EpisodeOfTheWrongLength) {
  ReplaceActions(4);
  ExpectOneLine(Hdf5(), "episodes of the wrong length");
}

TEST_F(RecordFromBadDataset, NotAFetchSpace) {
  EditMetadata("[25]", "[17]");
  ExpectOneLine(Metadata(), "observation_space is not a Fetch space");
}

TEST_F(RecordFromBadDataset, NotAFetchEnvId) {
  EditMetadata("{\\\"id\\\": \\\"FetchPush-v4\\\"", "{\\\"id\\\": \\\"HalfCheetah-v5\\\"");
  ExpectOneLine(Metadata(), "env_spec id 'HalfCheetah-v5' is not a Fetch environment");
}

TEST_F(RecordFromBadDataset, UnsupportedMinariVersion) {
  EditMetadata("\"minari_version\": \"0.5.0\"", "\"minari_version\": \"0.6.0\"");
  ExpectOneLine(Metadata(), "unsupported minari_version '0.6.0'");
}

TEST_F(RecordFromBadDataset, TruncatedHdf5) {
  fs::resize_file(Hdf5(), fs::file_size(Hdf5()) / 2);
  ExpectOneLine(Hdf5(), "truncated HDF5 file");
}

// A dataset without env_spec replayed on the wrong --env-id: its reset differs at step 0, so the
// run stops with a line that says why and what to do, before anything is written; a raised
// --tolerance renders it anyway. A misspelt id gets a "did you mean" from the local datasets;
// `fetchscope datasets` lists them.
TEST(RecordFromDataset, WrongEnvIdStopsAndMisspeltIdsAreSuggested) {
  unsetenv("DISPLAY");
  TempDir tmp;
  const fs::path root = tmp.path() / "datasets", run = tmp.path() / "run";
  auto r = RunFetchscope(
      "rollout --env-id FetchPush-v4 --episodes 2 --steps 6 --seed 4 --minari "
      "ns/FetchPush/nospec-v0 --minari-root " +
      root.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // drop env_spec, as a dataset made without an env (DataCollector on a bare env) has none
  const fs::path meta = root / "ns/FetchPush/nospec-v0/data/metadata.json";
  std::string text = ReadFile(meta);
  const size_t from = text.find(", \"env_spec\": "), to = text.find(", \"dataset_id\"");
  ASSERT_TRUE(from != std::string::npos && to != std::string::npos);
  text.erase(from, to - from);
  std::ofstream(meta, std::ios::binary) << text;
  const std::string record =
      "record --from ns/FetchPush/nospec-v0 --minari-root " + root.string() + kSmall;
  r = RunFetchscope(record + "--env-id FetchSlide-v4 --out " + run.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("the reset differs from the dataset's first row"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("its reset is not one of --env-id FetchSlide-v4"), std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(run));
  r = RunFetchscope(record + "--env-id FetchSlide-v4 --tolerance 10 --out " + run.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = RunFetchscope(record + "--env-id FetchPush-v4 --overwrite --out " + run.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // a misspelt id
  r = RunFetchscope("record --from ns/FetchPush/nospek-v0 --minari-root " + root.string() + kSmall +
                    "--out " + (tmp.path() / "run2").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("did you mean 'ns/FetchPush/nospec-v0'?"), std::string::npos) << r.output;
  // the listing: ours, and another writer's (a code_permalink that is not fetchscope's)
  r = RunFetchscope(
      "rollout --env-id FetchReach-v4 --episodes 1 --steps 3 --minari other-v1 "
      "--minari-root " +
      root.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fs::path other = root / "other-v1/data/metadata.json";
  text = ReadFile(other);
  const size_t at = text.find("\"fetchscope ");
  ASSERT_NE(at, std::string::npos);
  text.replace(at + 1, 10, "elsewhere");
  std::ofstream(other, std::ios::binary) << text;
  r = RunFetchscope("datasets --minari-root " + root.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("ns/FetchPush/nospec-v0  (no env_spec)  2         12     "),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("other-v1"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("FetchReach-v4"), std::string::npos) << r.output;
  const json listed =
      json::parse(RunFetchscope("datasets --json --minari-root " + root.string()).output);
  ASSERT_EQ(listed["datasets"].size(), 2u) << listed.dump();
  EXPECT_EQ(listed["datasets"][0]["id"], "ns/FetchPush/nospec-v0");
  EXPECT_EQ(listed["datasets"][0]["seeded_episodes"], 1);
  EXPECT_EQ(listed["datasets"][0]["fetchscope"], true);
  EXPECT_EQ(listed["datasets"][1]["id"], "other-v1");
  EXPECT_EQ(listed["datasets"][1]["fetchscope"], false);
  EXPECT_EQ(listed["datasets"][1]["env"], "FetchReach-v4");
}

// DataCollector-made datasets of the sparse ids: float32 rewards, a 64-bit seed on every episode,
// no infos: replayed exactly. And a dataset whose recorded Euler angles differ from ours in the
// last bits (another atan2: numpy's SIMD one rounds differently) keeps the settled quaternion:
// the episodes rebuilt from their first observation are the rollout's, bit for bit, after the
// reset.
TEST(RecordFromDataset, SparseSeededAndRoundedEulerAnglesReplayExactly) {
  const std::string py = PythonWithH5py();
  if (py.empty()) GTEST_SKIP() << "python3-h5py is not installed";
  unsetenv("DISPLAY");
  TempDir tmp;
  const fs::path root = tmp.path() / "datasets";
  std::string files;
  for (const char* seed : {"18446744073709551557", "3"}) {
    const fs::path file = tmp.path() / ("s" + std::string(seed) + ".json");
    const auto r = RunFetchscope("rollout --env-id FetchPush-v4 --episodes 1 --steps 25 --seed " +
                                 std::string(seed) + " --json-out " + file.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    files += " " + file.string();
  }
  auto r = RunCommand(py + " " + Script() + " " + root.string() + " sparse/buffers-v0 buffers" +
                      files + " 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto dtype = RunCommand(py + " -c 'import h5py; f = h5py.File(\"" +
                                (root / "sparse/buffers-v0/data/main_data.hdf5").string() +
                                "\"); print(f[\"episode_0/rewards\"].dtype, \"infos\" in "
                                "f[\"episode_0\"])'");
  EXPECT_EQ(dtype.output, "float32 False\n");
  r = RunFetchscope("record --from sparse/buffers-v0 --minari-root " + root.string() + kSmall +
                    "--out " + (tmp.path() / "run").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ExpectNoDivergence(Manifest(tmp.path() / "run"), {"seed", "seed"});
  // the Euler angles of every reset one ulp off, no seeds: rebuilt, the settled quaternion kept
  const fs::path rollout = tmp.path() / "rounded.json";
  r = RunFetchscope("rollout --env-id FetchPush-v4 --episodes 2 --steps 40 --seed 21 --json-out " +
                    rollout.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Trajectory played = ReadTrajectory(rollout.string());
  json j = json::parse(ReadFile(rollout));
  for (json& e : j["episodes"]) {
    for (int i = 11; i < 14; ++i) {
      const double v = e["steps"][0]["observation"][i].get<double>();
      e["steps"][0]["observation"][i] = std::nextafter(v, v < 0 ? 1.0 : -1.0);
    }
  }
  std::ofstream(rollout) << j.dump();
  r = RunCommand(py + " " + Script() + " " + root.string() + " rounded/push-v0 collector " +
                 rollout.string() + " 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fs::path run = tmp.path() / "run2";
  r = RunFetchscope("record --from rounded/push-v0 --minari-root " + root.string() + kSmall +
                    "--out " + run.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const TrajectoryEpisode& e : played.episodes) {
    SCOPED_TRACE(e.index);
    TrajectoryEpisode replayed = RecordedEpisode(run, e.index);
    TrajectoryEpisode expected = e;
    replayed.steps.erase(replayed.steps.begin());  // the reset row holds our own angles
    expected.steps.erase(expected.steps.begin());
    ExpectSameSteps(replayed, expected);
  }
  const json m = Manifest(run);
  EXPECT_EQ(m["episodes"][0]["reset"], "first observation");
  EXPECT_LT(m["episodes"][0]["divergence"]["max_difference"].get<double>(), 1e-15);
}

// A dataset the genuine env made (env_spec Gymnasium-Robotics', code_permalink not ours):
// without --assets, record --from replays it on the genuine assets where --assets auto finds
// them, and says so; otherwise it says once that the bundled models drift, and by how much.
TEST(RecordFromDataset, GenuineDatasetsReplayOnTheGenuineAssetsWhereFound) {
  const std::string py = PythonWithH5py();
  if (py.empty()) GTEST_SKIP() << "python3-h5py is not installed";
  const fs::path genuine = testing::GenuineAssetsDir();
  if (genuine.empty()) GTEST_SKIP() << "no genuine assets in ../shared";
  unsetenv("DISPLAY");
  TempDir tmp;
  const fs::path root = tmp.path() / "datasets", file = tmp.path() / "g.json";
  auto r =
      RunFetchscope("rollout --env-id FetchPush-v4 --episodes 1 --steps 50 --seed 0 --assets " +
                    genuine.string() + " --json-out " + file.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunCommand(py + " " + Script() + " " + root.string() + " gen/push-v0 buffers " +
                 file.string() + " 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string record = "record --from gen/push-v0 --minari-root " + root.string() +
                             " --width 40 --height 40 --no-report --out ";
  r = RunCommand("FETCHSCOPE_ASSETS=" + genuine.string() + " " FETCHSCOPE_BIN " " + record +
                 (tmp.path() / "run").string() + " 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("replaying on its assets at " + genuine.string()), std::string::npos)
      << r.output;
  ExpectNoDivergence(Manifest(tmp.path() / "run"), {"seed"});
  r = RunCommand("env -u FETCHSCOPE_ASSETS " FETCHSCOPE_BIN " " + record +
                 (tmp.path() / "run2").string() + " 2>&1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // (a machine with gymnasium_robotics installed replays on its assets instead)
  if (r.output.find("(--assets auto: ") == std::string::npos) {
    EXPECT_NE(r.output.find("replaying on the bundled models"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("positions up to about 0.02 mm off"), std::string::npos) << r.output;
  }
}

}  // namespace
}  // namespace fetchscope
