// `render`, black box: its layer file names and its PNG-only -o.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <string>

#include "encode/png_io.h"
#include "encode/video_reader.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::CommandResult;
using testing::FilesIn;
using testing::LineCount;
using testing::RunFetchscope;
using testing::TempDir;
namespace fs = std::filesystem;

TEST(RenderNames, SeveralLayersNameEveryNonRgbLayerAfterIt) {
  TempDir tmp;
  const std::string common = "render --env-id FetchPush-v4 --width 64 --height 64 ";
  const fs::path lay = tmp.path() / "lay.png";
  CommandResult r = RunFetchscope(common + "--layers depth,segmentation -o " + lay.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // depth goes to lay_depth.png whether or not rgb is listed; nothing is called lay.png
  EXPECT_EQ(FilesIn(tmp.path()), (std::set<std::string>{"lay_depth.png", "lay_segmentation.png",
                                                        "lay_segmentation_legend.json"}));
  for (const char* name :
       {"lay_depth.png", "lay_segmentation.png", "lay_segmentation_legend.json"}) {
    EXPECT_NE(r.output.find((tmp.path() / name).string()), std::string::npos) << r.output;
  }
  const fs::path both = tmp.path() / "both.png";
  r = RunFetchscope(common + "--layers depth,rgb -o " + both.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(tmp.path() / "both_depth.png"));
  EXPECT_TRUE(fs::exists(both));
  // one layer: -o is that layer's file
  const fs::path alone = tmp.path() / "alone.png";
  r = RunFetchscope(common + "--layers depth -o " + alone.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(alone));
  EXPECT_FALSE(fs::exists(tmp.path() / "alone_depth.png"));
  // and --help states the rule
  const CommandResult help = RunFetchscope("render --help");
  std::string flat;
  for (char c : help.output) {
    if (c == '\n') c = ' ';
    if (c != ' ' || flat.empty() || flat.back() != ' ') flat += c;
  }
  EXPECT_NE(flat.find("with several, NAME.png holds rgb"), std::string::npos) << help.output;
}

TEST(RenderNames, RefusesAnOutputThatIsNotPng) {
  TempDir tmp;
  for (const char* name : {"x.jpg", "x.JPEG", "x"}) {
    SCOPED_TRACE(name);
    const fs::path out = tmp.path() / name;
    const CommandResult r =
        RunFetchscope("render --width 64 --height 64 -o " + out.string() + " 2>&1");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_EQ(LineCount(r.output), 1) << r.output;
    EXPECT_NE(r.output.find(out.string()), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(".png"), std::string::npos) << r.output;
  }
  EXPECT_TRUE(FilesIn(tmp.path()).empty());
  const CommandResult upper =
      RunFetchscope("render --width 64 --height 64 -o " + (tmp.path() / "Y.PNG").string());
  EXPECT_EQ(upper.exit_code, 0) << upper.output;
}

// --overlay trail: render draws the achieved goals of the steps before its frame, as record's
// frame of that step shows them (a lossless APNG frame, compared pixel for pixel).
TEST(RenderTrail, TheTrailIsRecordsFrameOfThatStep) {
  TempDir tmp;
  const std::string common =
      " --env-id FetchReach-v4 --policy scripted --seed 4 --width 96 --height 72 --overlay "
      "goal,achieved,trail";
  CommandResult r = RunFetchscope(
      "record --episodes 1 --steps 12 --format apng --no-sheets --quiet"
      " --no-report --out " +
      (tmp.path() / "run").string() + common);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunFetchscope("render --steps 12 -o " + (tmp.path() / "trail.png").string() + common);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunFetchscope("render --steps 12 -o " + (tmp.path() / "plain.png").string() +
                    " --env-id FetchReach-v4 --policy scripted --seed 4 --width 96 --height 72 "
                    "--overlay goal,achieved");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  int width = 0, height = 0;
  const std::vector<std::vector<uint8_t>> frames =
      ReadAllFrames((tmp.path() / "run/episode_000.apng").string(), &width, &height);
  ASSERT_EQ(frames.size(), 13u);
  const Image trail = ReadPng((tmp.path() / "trail.png").string());
  ASSERT_EQ(trail.width, width);
  EXPECT_TRUE(trail.pixels == frames[12]) << "render's trail is not record's frame of step 12";
  EXPECT_FALSE(ReadPng((tmp.path() / "plain.png").string()).pixels == trail.pixels)
      << "the trail drew nothing";
}

}  // namespace
}  // namespace fetchscope
