// The episode viewer's per-step signals (inspect/viewer.h): what each plot holds for Reach and for
// an object task, the hindsight relabelling as record samples it, where the contact sheet's first
// and last tiles lie, and a real run's page carrying one lazily parsed block per episode that
// agrees with its trajectory file.
#include "inspect/viewer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "encode/contact_sheet.h"
#include "encode/png_io.h"
#include "src/env_spec.h"
#include "src/fetch_env.h"
#include "src/hindsight.h"
#include "src/trajectory.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::PageBlock;
using testing::ReadFile;
using testing::RunFetchscope;
using testing::TempDir;

TrajectoryStep Step(std::vector<double> obs, std::array<double, 3> achieved,
                    std::array<double, 3> desired, std::optional<std::array<double, 4>> action,
                    std::optional<double> reward) {
  TrajectoryStep step;
  step.obs = {std::move(obs), achieved, desired};
  if (action) step.action = Action{*action, false};
  step.reward = reward;
  return step;
}

TEST(ViewerSignalsTest, ReachPlotsCommandAgainstAchievedAndItsFingers) {
  const EnvSpec& spec = FindEnvSpec("FetchReach-v4");
  std::vector<double> o0(10, 0.0), o1(10, 0.0), o2(10, 0.0);
  o0[0] = 1.0;  // grip x
  o1[0] = 1.03;
  o2[0] = 1.05;
  o2[1] = -0.01;
  o1[3] = 0.02;  // fingers
  o1[4] = 0.025;
  const std::vector<TrajectoryStep> steps = {
      Step(o0, {1, 0, 0}, {1, 0.3, 0.4}, std::nullopt, std::nullopt),
      Step(o1, {1.03, 0, 0}, {1, 0.3, 0.4}, std::array<double, 4>{2.0, -0.5, NAN, 1}, -1.0),
      Step(o2, {1.05, -0.01, 0}, {1, 0.3, 0.4}, std::array<double, 4>{0.4, -3, 0, -1}, -0.0)};
  const json s = EpisodeSignals(spec, steps);
  EXPECT_EQ(s["frames"], 3);
  EXPECT_NEAR(s["distance"][0].get<double>(), 0.5, 1e-9);
  EXPECT_TRUE(s["reward"][0].is_null());
  EXPECT_EQ(s["reward"][1], -1.0);
  EXPECT_TRUE(s["action"][0][0].is_null());  // the reset: no action
  EXPECT_EQ(s["action"][0][1], 2.0);         // as given
  EXPECT_TRUE(s["action"][2][1].is_null());  // not finite: no value to plot
  EXPECT_EQ(s["commanded"][0][1], 0.05);     // clipped to 1, times 0.05 m
  EXPECT_EQ(s["commanded"][1][1], -0.025);   // -0.5 x 0.05
  EXPECT_EQ(s["commanded"][1][2], -0.05);    // -3 clipped to -1
  EXPECT_NEAR(s["commanded"][0][2].get<double>(), 0.02, 1e-12);
  EXPECT_TRUE(s["achieved"][0][0].is_null());  // no step before the reset
  EXPECT_NEAR(s["achieved"][0][1].get<double>(), 0.03, 1e-9);
  EXPECT_NEAR(s["achieved"][0][2].get<double>(), 0.02, 1e-9);
  EXPECT_NEAR(s["achieved"][1][2].get<double>(), -0.01, 1e-9);
  EXPECT_NEAR(s["finger_width"][1].get<double>(), 0.045, 1e-9);  // obs[3] + obs[4]
  // Reach blocks its gripper and has no object: no such plots
  EXPECT_FALSE(s.contains("gripper_command"));
  EXPECT_FALSE(s.contains("object_height"));
  EXPECT_FALSE(s.contains("her"));
}

TEST(ViewerSignalsTest, PickAndPlacePlotsGripperCommandAndObject) {
  const EnvSpec& spec = FindEnvSpec("FetchPickAndPlace-v4");
  std::vector<double> o0(25, 0.0), o1(25, 0.0);
  o1[3] = 1.3;  // object x, y, z
  o1[4] = 0.7;
  o1[5] = 0.45;
  o1[9] = 0.03;  // fingers
  o1[10] = 0.01;
  const std::vector<TrajectoryStep> steps = {
      Step(o0, {0, 0, 0}, {1.3, 0.7, 0.55}, std::nullopt, std::nullopt),
      Step(o1, {1.3, 0.7, 0.45}, {1.3, 0.7, 0.55}, std::array<double, 4>{0, 0, 0, -4}, -1.0)};
  const json s = EpisodeSignals(spec, steps);
  EXPECT_NEAR(s["finger_width"][1].get<double>(), 0.04, 1e-9);  // obs[9] + obs[10]
  EXPECT_TRUE(s["gripper_command"][0].is_null());
  EXPECT_EQ(s["gripper_command"][1], -1.0);  // clipped
  EXPECT_EQ(s["object_height"][1], 0.45);
  EXPECT_NEAR(s["object_goal_distance"][1].get<double>(), 0.1, 1e-9);
  EXPECT_NEAR(s["distance"][1].get<double>(), 0.1, 1e-9);
  // Push blocks its gripper: no command plotted there
  EXPECT_FALSE(EpisodeSignals(FindEnvSpec("FetchPush-v4"), steps).contains("gripper_command"));
}

TEST(ViewerSignalsTest, HindsightRewardsAreRecordsRelabelling) {
  const EnvSpec& spec = FindEnvSpec("FetchPush-v4");
  std::vector<TrajectoryStep> steps;
  std::vector<std::array<double, 3>> achieved;
  for (int t = 0; t <= 6; ++t) {
    const std::array<double, 3> a = {1.2 + 0.02 * t, 0.7, 0.42};
    achieved.push_back(a);
    steps.push_back(Step(std::vector<double>(25, 0.0), a, {1.4, 0.7, 0.42},
                         t ? std::optional<std::array<double, 4>>({1, 0, 0, 0}) : std::nullopt,
                         t ? std::optional<double>(-1.0) : std::nullopt));
  }
  const uint64_t seed = HindsightSeed(7, 2);
  const json s = EpisodeSignals(spec, steps, seed);
  ASSERT_TRUE(s.contains("her"));
  const HindsightEpisode h = SampleHindsight(
      achieved, {1.4, 0.7, 0.42}, seed, kHindsightK,
      [](const auto& a, const auto& g) { return GoalDistance(a, g) > 0.05 ? -1.0 : -0.0; },
      [](const auto& a, const auto& g) { return GoalDistance(a, g) < 0.05; });
  ASSERT_EQ(s["her"]["rewards"].size(), static_cast<size_t>(kHindsightK));
  int successes = 0;
  for (size_t t = 1; t < steps.size(); ++t) {
    int n = 0;
    for (int i = 0; i < kHindsightK; ++i) {
      EXPECT_EQ(s["her"]["rewards"][i][t].get<double>(), h.transitions[t - 1][i].reward);
      n += h.transitions[t - 1][i].success;
    }
    EXPECT_EQ(s["her"]["successes"][t], n);
    successes += n;
  }
  EXPECT_TRUE(s["her"]["successes"][0].is_null());
  EXPECT_EQ(successes, h.relabelled_successes);
  EXPECT_EQ(s["her"]["relabelled_successes"], h.relabelled_successes);
  EXPECT_GT(successes, 0) << "the goals sampled from the future should include reached ones";
}

TEST(ViewerSheetTest, LocatesTheFirstAndLastTilesOfARealSheet) {
  for (const auto& [tiles, tile_width] : {std::pair{11, 240}, {12, 64}, {5, 100}, {1, 48}}) {
    std::vector<SheetTile> frames;
    for (int i = 0; i < tiles; ++i) {  // 40 x 30 frames, each one flat colour
      SheetTile tile;
      tile.width = 40;
      tile.height = 30;
      tile.rgb.assign(40 * 30 * 3, static_cast<uint8_t>(10 + 20 * i));
      tile.label = "t=" + std::to_string(i);
      frames.push_back(std::move(tile));
    }
    const SheetImage sheet = MakeContactSheet("title", frames, tile_width);
    const auto thumbs = LocateSheetThumbs(sheet.width, sheet.height, tiles);
    ASSERT_TRUE(thumbs) << tiles << " tiles";
    EXPECT_EQ(thumbs->tile_width, tile_width);
    EXPECT_EQ(thumbs->tile_height, static_cast<int>(std::lround(30.0 * tile_width / 40)));
    auto pixel = [&](int x, int y) {
      return sheet.rgb[(static_cast<size_t>(y) * sheet.width + x) * 3];
    };
    for (const auto& [corner, colour] :
         {std::pair{thumbs->first, 10}, {thumbs->last, 10 + 20 * (tiles - 1)}}) {
      // the tile's corners and centre are the frame's colour
      for (const auto& [dx, dy] : {std::pair{0, 0},
                                   {thumbs->tile_width - 1, thumbs->tile_height - 1},
                                   {thumbs->tile_width / 2, thumbs->tile_height / 2}}) {
        EXPECT_EQ(pixel(corner[0] + dx, corner[1] + dy), colour) << tiles << " tiles";
      }
    }
    if (tiles > 1) {  // a sheet one pixel wider holds no whole number of columns
      EXPECT_FALSE(LocateSheetThumbs(sheet.width + 1, sheet.height, tiles));
    }
    EXPECT_FALSE(LocateSheetThumbs(sheet.width, sheet.height, 0));
  }
}

TEST(ViewerSheetTest, CountsTheTilesRecordPutOnASheet) {
  EXPECT_EQ(SheetTileCount(21, 20, 0), 11);  // 0, 2, ..., 18 and the last frame, 20
  EXPECT_EQ(SheetTileCount(51, 50, 0), 11);  // 0, 5, ..., 45 and 50
  EXPECT_EQ(SheetTileCount(8, 20, 0), 5);    // interrupted after 7 steps: 0, 2, 4, 6 and 7
  EXPECT_EQ(SheetTileCount(21, 20, 1), 21);  // every frame
  EXPECT_EQ(SheetTileCount(0, 20, 0), 0);
}

TEST(ViewerSheetTest, ReadsAPngsSizeFromItsHeader) {
  TempDir tmp;
  const std::vector<uint8_t> pixels(7 * 5 * 3, 0);
  WritePng((tmp.path() / "a.png").string(), 7, 5, 3, 8, pixels.data());
  EXPECT_EQ(PngSize(tmp.path() / "a.png"), (std::pair<int, int>{7, 5}));
  EXPECT_FALSE(PngSize(tmp.path() / "missing.png"));
}

// The JSON of block `id` in a page, or null.
TEST(ViewerPageTest, ARunsPageCarriesEachEpisodesSignals) {
  TempDir tmp;
  const fs::path run = tmp.path() / "run";
  const auto r = RunFetchscope(
      "record --env-id FetchPickAndPlace-v4 --policy scripted --steps 12 --width 64 --height 64 "
      "--episodes 2 --quiet --out " +
      run.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string html = ReadFile(run / "index.html");
  const json data = PageBlock(html, "fetchscope-data");
  ASSERT_TRUE(data.is_object());
  EXPECT_EQ(data["viewer"]["has_object"], true);
  EXPECT_EQ(data["viewer"]["gripper_command"], true);
  EXPECT_EQ(data["viewer"]["hindsight"], false);
  // where the plotted values are, for viewer.js's titles (src/observation_layout.h)
  EXPECT_EQ(data["viewer"]["layout"],
            json({{"finger_width", "obs[9] + obs[10]"}, {"object_height", "obs[5]"}}));
  for (int k = 0; k < 2; ++k) {
    const json& e = data["episodes"][k];
    EXPECT_EQ(e["viewer"], true);
    ASSERT_TRUE(e["thumbs"].is_object()) << e.dump();
    EXPECT_EQ(e["thumbs"]["tile"], (json{240, 240}));
    EXPECT_EQ(e["thumbs"]["first"], (json{8, e["thumbs"]["first"][1]}));
    const json block = PageBlock(html, "fetchscope-episode-" + std::to_string(k));
    ASSERT_TRUE(block.is_object()) << k;
    EXPECT_EQ(block["index"], k);
    EXPECT_EQ(block["frames"], 13);
    const json trajectory = json::parse(ReadFile(run / e["trajectory"].get<std::string>()));
    const json& steps = trajectory["episodes"][0]["steps"];
    for (size_t t = 1; t < steps.size(); ++t) {
      for (int i = 0; i < 3; ++i) {
        const double moved =
            steps[t]["observation"][i].get<double>() - steps[t - 1]["observation"][i].get<double>();
        EXPECT_NEAR(block["achieved"][i][t].get<double>(), moved, 1e-6) << "t=" << t;
        const double a = std::clamp(steps[t]["action"][i].get<double>(), -1.0, 1.0);
        EXPECT_NEAR(block["commanded"][i][t].get<double>(), 0.05 * a, 1e-6) << "t=" << t;
      }
      EXPECT_EQ(block["reward"][t], steps[t]["reward"]);
    }
  }
}

// With the hindsight overlay, each episode's relabelled rewards are the ones record sampled: their
// successes add up to the manifest's count.
TEST(ViewerPageTest, HindsightRewardsMatchTheManifestsCounts) {
  TempDir tmp;
  const fs::path run = tmp.path() / "run";
  const auto r = RunFetchscope(
      "record --env-id FetchPush-v4 --policy scripted --steps 20 --width 48 --height 48 "
      "--episodes 2 --overlay hindsight --quiet --out " +
      run.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string html = ReadFile(run / "index.html");
  const json data = PageBlock(html, "fetchscope-data");
  ASSERT_TRUE(data.is_object());
  EXPECT_EQ(data["viewer"]["hindsight"], true);
  const json manifest = json::parse(ReadFile(run / "manifest.json"));
  for (const json& e : manifest["episodes"]) {
    const int k = e["index"].get<int>();
    const json block = PageBlock(html, "fetchscope-episode-" + std::to_string(k));
    ASSERT_TRUE(block.contains("her")) << k;
    int successes = 0;
    for (const json& n : block["her"]["successes"]) successes += n.is_null() ? 0 : n.get<int>();
    EXPECT_EQ(successes, e["hindsight"]["relabelled_successes"].get<int>()) << k;
    EXPECT_EQ(block["her"]["rewards"].size(), 4u);
    EXPECT_EQ(block["her"]["rewards"][0].size(), 21u);
  }
}

}  // namespace
}  // namespace fetchscope
