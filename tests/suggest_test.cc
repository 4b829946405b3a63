// "did you mean": edit distance, the nearest name, and comma lists with spaces.
#include "base/suggest.h"

#include <gtest/gtest.h>

#include "base/errors.h"
#include "render/camera.h"
#include "render/overlay.h"
#include "src/env_spec.h"

namespace fetchscope {
namespace {

TEST(SuggestTest, EditDistanceCountsInsertionsDeletionsSubstitutionsAndSwaps) {
  EXPECT_EQ(EditDistance("", ""), 0);
  EXPECT_EQ(EditDistance("hud", ""), 3);
  EXPECT_EQ(EditDistance("goal", "goal"), 0);
  EXPECT_EQ(EditDistance("Goal", "goal"), 0);  // case is not an edit
  EXPECT_EQ(EditDistance("gaol", "goal"), 1);  // a swap of neighbours
  EXPECT_EQ(EditDistance("trial", "trail"), 1);
  EXPECT_EQ(EditDistance("track", "trac"), 1);
  EXPECT_EQ(EditDistance("kitten", "sitting"), 3);
}

TEST(SuggestTest, ClosestNameOnlyWhenNearEnough) {
  const std::vector<std::string> overlays = {"goal", "achieved", "hud", "action", "trail"};
  EXPECT_EQ(ClosestName("hdu", overlays), "hud");
  EXPECT_EQ(ClosestName("acheived", overlays), "achieved");
  EXPECT_EQ(ClosestName("sparkles", overlays), "");
  EXPECT_EQ(ClosestName("", overlays), "");
  EXPECT_EQ(DidYouMean("trial", overlays), " (did you mean 'trail'?)");
  EXPECT_EQ(DidYouMean("zzz", overlays), "");
}

TEST(SuggestTest, CommaListsIgnoreSpacesAroundItems) {
  EXPECT_EQ(SplitCommaList("goal, hud"), (std::vector<std::string>{"goal", "hud"}));
  EXPECT_EQ(SplitCommaList(" a ,\tb,c "), (std::vector<std::string>{"a", "b", "c"}));
  EXPECT_EQ(SplitCommaList("a,,b"), (std::vector<std::string>{"a", "", "b"}));
  EXPECT_EQ(SplitCommaList("a, "), (std::vector<std::string>{"a", ""}));
}

std::string UsageMessage(const std::function<void()>& body) {
  try {
    body();
  } catch (const UsageError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(SuggestTest, ParsersAcceptSpacesAndSuggestNames) {
  const OverlaySet two = ParseOverlays("goal, hud");
  EXPECT_TRUE(two.goal && two.hud && !two.achieved && !two.action && !two.trail);
  const OverlaySet all = ParseOverlays("all");
  EXPECT_TRUE(all.goal && all.achieved && all.hud && all.action && all.trail);
  EXPECT_NE(UsageMessage([] { ParseOverlays("goal,hdu"); }).find("did you mean 'hud'?"),
            std::string::npos);

  const auto cams = ParseCameraList("default, track", nullptr);
  ASSERT_EQ(cams.size(), 2u);
  EXPECT_EQ(cams[1].kind, CameraSpec::kTrack);
  const auto free = ParseCameraList("free:lookat=1, 0.7, 0.5, distance=2, default", nullptr);
  ASSERT_EQ(free.size(), 2u);
  EXPECT_EQ(free[0].free.lookat[1], 0.7);
  EXPECT_EQ(free[0].free.distance, 2.0);
  EXPECT_NE(
      UsageMessage([] { ParseCameraList("defualt", nullptr); }).find("did you mean 'default'?"),
      std::string::npos);

  EXPECT_NE(UsageMessage([] { FindEnvSpec("FetchPsuh-v4"); }).find("did you mean 'FetchPush-v4'?"),
            std::string::npos);
  EXPECT_NE(
      UsageMessage([] { FindEnvSpec("fetchreach-v4"); }).find("did you mean 'FetchReach-v4'?"),
      std::string::npos);
}

}  // namespace
}  // namespace fetchscope
