// The HUD (render/overlay.h): zero rewards without a sign, text with no box outlined, and the HUD
// left out where a GIF shows the views too small for it.
#include "render/overlay.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::ReachSuccessStep;

TEST(PictureNumber, HudShowsZeroRewardWithoutSign) {
  const HudText hud = FormatHud(ReachSuccessStep(), OverlaySet{});
  EXPECT_EQ(hud.values.find("-0.0000"), std::string::npos) << hud.values;
  EXPECT_NE(hud.values.find("\n0.0000\n"), std::string::npos) << hud.values;
  EXPECT_NE(hud.values.find("+0.00 +0.50 -0.25 +0.00"), std::string::npos) << hud.values;
}

// Pixels of the HUD box drawn at `opacity` over a uniform `grey` image.
std::vector<uint8_t> HudOver(uint8_t grey, double opacity, PixelRect* box) {
  const int w = 480, h = 480;
  std::vector<uint8_t> rgb(w * h * 3, grey);
  const HudText hud = FormatHud(ReachSuccessStep(), OverlaySet{});
  const PixelRect tile{0, 0, w, h};
  *box = *PlaceHud(hud, tile, HudPosition::kTopLeft);
  EXPECT_TRUE(DrawHud(rgb.data(), w, h, tile, hud, HudPosition::kTopLeft, opacity));
  return rgb;
}

TEST(HudOutline, TextWithoutBoxIsOutlinedInBlackOverWhite) {
  PixelRect box;
  const std::vector<uint8_t> rgb = HudOver(255, 0.0, &box);
  int dark = 0;
  for (int y = box.y; y < box.y + box.height; ++y) {
    for (int x = box.x; x < box.x + box.width; ++x) {
      const uint8_t* p = &rgb[(y * 480 + x) * 3];
      if (std::max({p[0], p[1], p[2]}) < 60) ++dark;
    }
  }
  // white text on a white table would be invisible: its outline is what shows
  EXPECT_GT(dark, 300) << "no dark outline around the HUD text at --hud-opacity 0";
}

TEST(HudOutline, EveryBrightTextPixelHasADarkNeighbour) {
  PixelRect box;
  const uint8_t grey = 128;  // text (200..255) and outline (< 60) both differ from it
  const std::vector<uint8_t> rgb = HudOver(grey, 0.0, &box);
  auto at = [&](int x, int y) { return rgb[(y * 480 + x) * 3]; };
  int bright = 0, outlined = 0;
  for (int y = box.y + 1; y < box.y + box.height - 1; ++y) {
    for (int x = box.x + 1; x < box.x + box.width - 1; ++x) {
      if (at(x, y) < 230) continue;
      ++bright;
      bool near_dark = false;
      for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx) near_dark = near_dark || at(x + dx, y + dy) < 60;
      }
      outlined += near_dark;
    }
  }
  ASSERT_GT(bright, 100);
  EXPECT_EQ(outlined, bright);
}

TEST(HudOutline, TheDefaultBoxHasNoOutline) {
  // at the default opacity the box alone darkens the scene: nothing in it is darker than the box
  PixelRect box;
  const std::vector<uint8_t> rgb = HudOver(255, 0.6, &box);
  const uint8_t boxed = rgb[((box.y + 1) * 480 + box.x + 1) * 3];  // 255 * 0.4, rounded
  EXPECT_EQ(boxed, 102);
  for (int y = box.y; y < box.y + box.height; ++y) {
    for (int x = box.x; x < box.x + box.width; ++x) ASSERT_GE(rgb[(y * 480 + x) * 3], boxed);
  }
}

TEST(GifHud, LeftOutWhereTheGifShowsViewsTooSmallForIt) {
  // two 480-pixel views side by side in a 320-pixel GIF: each shows at 160 x 160
  EXPECT_EQ(HudTextPixels(480, 480, ShownScale{320, 960}), 0);
  EXPECT_EQ(HudTextPixels(480, 480, ShownScale{1, 1}), HudTextPixels(480, 480));
  EXPECT_EQ(FrameTextPixels(480, 480, ShownScale{1, 1}), FrameTextPixels(480, 480));
}

}  // namespace
}  // namespace fetchscope
