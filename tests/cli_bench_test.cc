// `bench`, black box: bench --what node recommends the fastest record row; bench --what look
// prints and stores its plain-beside-randomized CPU account.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::CommandResult;
using testing::LinesWith;
using testing::ReadFile;
using testing::RunFetchscope;
using testing::TempDir;

TEST(RoughEdges, BenchNodeRecommendsTheFastestRecordRow) {
  TempDir tmp;
  const CommandResult r = RunFetchscope(
      "bench --what node --backends egl --seconds 0.4 --width 48 --height 48 --json-out " +
      (tmp.path() / "b.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json node = nlohmann::json::parse(ReadFile(tmp.path() / "b.json"))["node"];
  ASSERT_TRUE(node.contains("recommendation")) << node.dump(1);
  const nlohmann::json& rec = node["recommendation"];
  // the row with the most record frames/s
  const nlohmann::json* best = nullptr;
  for (const auto& row : node["record"]) {
    if (!row.contains("frames_per_s")) continue;
    if (!best || row["frames_per_s"].get<double>() > (*best)["frames_per_s"].get<double>())
      best = &row;
  }
  ASSERT_NE(best, nullptr);
  EXPECT_EQ(rec["jobs"], (*best)["jobs"]);
  EXPECT_EQ(rec["worker_mode"], (*best)["worker_mode"]);
  EXPECT_EQ(rec["frames_per_s"], (*best)["frames_per_s"]);
  const std::string flags = rec["flags"];
  EXPECT_EQ(flags.rfind("--jobs " + std::to_string((*best)["jobs"].get<int>()) + " --worker-mode " +
                            (*best)["worker_mode"].get<std::string>(),
                        0),
            0u)
      << flags;
  const std::vector<std::string> lines = LinesWith(r.output, "recommended:");
  ASSERT_EQ(lines.size(), 1u) << r.output;
  EXPECT_NE(lines[0].find(flags), std::string::npos) << lines[0];
}

// bench --what look: one plain and one randomized record run, each stage's CPU per frame side by
// side with the ratio; the look's own stage is counted where a look is drawn (its textures are
// uploaded once per episode) and is absent from the plain run's account.
TEST(BenchLook, PrintsAndStoresThePlainBesideRandomizedAccount) {
  TempDir tmp;
  const CommandResult r = RunFetchscope(
      "bench --what look --backends egl --look-episodes 1 --look-repeats 1 --json-out " +
      (tmp.path() / "b.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json look = nlohmann::json::parse(ReadFile(tmp.path() / "b.json"))["look"];
  ASSERT_FALSE(look.contains("skipped")) << look.dump(1);
  EXPECT_EQ(look["randomize"], "colors,textures,lighting,camera");
  EXPECT_EQ(look["frames"], 51);
  EXPECT_EQ(look["repeats"], 1);
  for (const char* row : {"sim", "scene", "hud", "copy", "look", "renderer_outside_gl", "convert",
                          "encode", "sheet", "outside_gl", "gl"}) {
    ASSERT_TRUE(look["ms_per_frame"].contains(row)) << row;
    const nlohmann::json& v = look["ms_per_frame"][row];
    for (const char* side : {"plain", "randomized"}) {
      ASSERT_EQ(v[side]["runs"].size(), 1u) << row << " " << side;
      for (const char* k : {"mean", "min", "max"}) EXPECT_TRUE(v[side][k].is_number()) << row;
    }
    EXPECT_TRUE(v.contains("ratio")) << row;
    EXPECT_EQ(LinesWith(r.output, row).empty(), false) << row << "\n" << r.output;
  }
  EXPECT_GT(look["ms_per_frame"]["look"]["randomized"]["mean"].get<double>(), 0.0);
  EXPECT_TRUE(look["ms_per_frame"]["look"]["ratio"].is_null());  // the plain run draws none
  EXPECT_TRUE(look["ms_per_frame"]["outside_gl"]["ratio"].is_number());
  EXPECT_TRUE(look["renderer_extra_share_of_outside_gl"].is_number());
  EXPECT_EQ(LinesWith(r.output, "look: outside GL x").size(), 1u) << r.output;
}

}  // namespace
}  // namespace fetchscope
