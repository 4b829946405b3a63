// The 2D canvas (render/canvas.h) and label placement (render/label_placer.h): the one blend's
// values, clipping at every edge, the pixels of lines and arrows, text through the canvas, and
// placed labels that never overlap.
#include "render/canvas.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "base/errors.h"
#include "render/label_placer.h"

namespace fetchscope {
namespace {

constexpr Rgb kWhite = {255, 255, 255};
constexpr Rgb kRed = {255, 0, 0};

// An RGB24 image filled with one grey level, with a canvas over it.
struct Image {
  int width, height;
  std::vector<uint8_t> rgb;
  Canvas canvas;
  Image(int w, int h, uint8_t fill = 0)
      : width(w), height(h), rgb(static_cast<size_t>(w) * h * 3, fill), canvas(rgb.data(), w, h) {}
  const uint8_t* At(int x, int y) const { return &rgb[(static_cast<size_t>(y) * width + x) * 3]; }
  int Red(int x, int y) const { return At(x, y)[0]; }
  // pixels whose red channel is not `fill`
  int Changed(uint8_t fill) const {
    int n = 0;
    for (size_t i = 0; i < rgb.size(); i += 3) n += rgb[i] != fill;
    return n;
  }
};

TEST(BlendChannel, RoundsToTheNearestLevel) {
  EXPECT_EQ(BlendChannel(100, 200, 0.0), 100);
  EXPECT_EQ(BlendChannel(100, 200, 1.0), 200);
  EXPECT_EQ(BlendChannel(100, 200, 0.25), 125);
  EXPECT_EQ(BlendChannel(0, 255, 0.5), 128);  // 127.5 rounds up
  EXPECT_EQ(BlendChannel(255, 0, 0.6), 102);  // 0.4 * 255 = 102
  EXPECT_EQ(BlendChannel(200, 0, 0.6), 80);   // 0.4 * 200 = 80
  EXPECT_EQ(BlendChannel(10, 20, 0.8), 18);
}

// Text coverage k is blended as alpha k / 255: exactly the integer blend text.cc used before
// the canvas, for every pair of levels and every coverage.
TEST(BlendChannel, CoverageAlphaEqualsTheIntegerBlend) {
  int differ = 0;
  for (unsigned under = 0; under < 256; ++under) {
    for (unsigned over = 0; over < 256; ++over) {
      for (unsigned k = 1; k < 256; ++k) {
        const unsigned integer = (under * (255u - k) + over * k + 127u) / 255u;
        differ += BlendChannel(under, over, k / 255.0) != integer;
      }
    }
  }
  EXPECT_EQ(differ, 0);
}

TEST(Canvas, BlendMixesEachChannelAndIgnoresPixelsOutside) {
  Image img(4, 3, 100);
  img.canvas.Blend(1, 1, {200, 0, 100}, 0.25);
  EXPECT_EQ(img.At(1, 1)[0], 125);
  EXPECT_EQ(img.At(1, 1)[1], 75);
  EXPECT_EQ(img.At(1, 1)[2], 100);
  const std::vector<uint8_t> before = img.rgb;
  for (auto [x, y] : {std::pair{-1, 0}, {0, -1}, {4, 0}, {0, 3}, {-5, 7}}) {
    img.canvas.Blend(x, y, kWhite, 1.0);
  }
  img.canvas.Blend(2, 2, kWhite, 0.0);
  img.canvas.Blend(2, 2, kWhite, -0.5);
  EXPECT_EQ(img.rgb, before);
}

TEST(Canvas, FillRectIsClippedAtEveryEdge) {
  Image img(10, 8);
  img.canvas.FillRect(-3, -2, 5, 4, kRed);  // covers x 0..1, y 0..1
  EXPECT_EQ(img.Changed(0), 4);
  EXPECT_EQ(img.Red(1, 1), 255);
  EXPECT_EQ(img.Red(2, 1), 0);
  img.canvas.FillRect(8, 6, 100, 100, kRed);  // x 8..9, y 6..7
  EXPECT_EQ(img.Changed(0), 8);
  EXPECT_EQ(img.Red(9, 7), 255);
  img.canvas.FillRect(20, 0, 3, 3, kRed);  // wholly outside
  img.canvas.FillRect(0, 0, -4, 3, kRed);  // negative size
  EXPECT_EQ(img.Changed(0), 8);
  // translucent: blended, not painted
  img.canvas.FillRect(4, 4, 2, 2, {200, 200, 200}, 0.5);
  EXPECT_EQ(img.Red(4, 4), 100);
  EXPECT_EQ(img.Red(5, 5), 100);
}

TEST(Canvas, PasteCopiesTheVisiblePart) {
  Image img(6, 5);
  std::vector<uint8_t> block(4 * 4 * 3);
  for (int i = 0; i < 16; ++i) block[3 * i] = static_cast<uint8_t>(10 + i);  // red = 10 + index
  img.canvas.Paste(block.data(), 4, 4, -2, -1);
  // block pixel (2, 1) lands on (0, 0); (3, 3) on (1, 2)
  EXPECT_EQ(img.Red(0, 0), 10 + 1 * 4 + 2);
  EXPECT_EQ(img.Red(1, 2), 10 + 3 * 4 + 3);
  EXPECT_EQ(img.Changed(0), 6);
  img.canvas.Paste(block.data(), 4, 4, 4, 3);  // bottom-right corner: 2 x 2 visible
  EXPECT_EQ(img.Red(5, 4), 10 + 1 * 4 + 1);
  EXPECT_EQ(img.Changed(0), 10);
}

TEST(Canvas, HorizontalLineCoversItsRowsWithAntiAliasedEnds) {
  Image img(20, 10);
  img.canvas.Capsule({2, 5}, {18, 5}, 2, kWhite);
  for (int x = 2; x < 18; ++x) {
    EXPECT_EQ(img.Red(x, 4), 255) << x;  // centres 0.5 from the line: inside
    EXPECT_EQ(img.Red(x, 5), 255) << x;
    EXPECT_EQ(img.Red(x, 3), 0) << x;  // 1.5 away: outside
    EXPECT_EQ(img.Red(x, 6), 0) << x;
  }
  // the round ends: (1.5, 4.5) is 0.707 from (2, 5), coverage 1 + 0.5 - 0.707 = 0.793
  EXPECT_EQ(img.Red(1, 4), 202);
  EXPECT_EQ(img.Red(18, 5), 202);
  EXPECT_EQ(img.Red(0, 5), 0);
  EXPECT_EQ(img.Red(19, 5), 0);
}

TEST(Canvas, ShapesCrossingTheEdgesAreClipped) {
  Image img(16, 12);
  img.canvas.Capsule({-30, -30}, {40, 40}, 3, kWhite);  // the diagonal, through two corners
  img.canvas.Disc({15.5, 0}, 6, kRed);
  img.canvas.Arrow({-10, 11}, {30, 11}, {}, 1, kWhite);
  EXPECT_EQ(img.Red(5, 5), 255);
  EXPECT_EQ(img.Red(15, 0), 255);
  EXPECT_EQ(img.Red(8, 11), 255);
  EXPECT_EQ(img.Red(0, 6), 0);
}

TEST(Canvas, ArrowHasItsShaftAndAHeadAtTheTip) {
  Image img(60, 30);
  ArrowShape shape;
  shape.shaft = 2;
  shape.head_length = 10;
  shape.head_width = 12;
  img.canvas.Arrow({5, 15}, {45, 15}, shape, 0, kWhite);
  EXPECT_EQ(img.Red(10, 14), 255);  // shaft, 2 px: rows 14 and 15
  EXPECT_EQ(img.Red(10, 15), 255);
  EXPECT_EQ(img.Red(10, 12), 0);
  EXPECT_EQ(img.Red(36, 10), 255);  // the head's base, 5 px from the axis
  EXPECT_EQ(img.Red(41, 15), 255);  // near the tip
  EXPECT_EQ(img.Red(47, 15), 0);    // beyond it
  EXPECT_EQ(img.Red(30, 10), 0);    // beside the shaft, before the head
  // a rim grows every part
  Image rimmed(60, 30);
  rimmed.canvas.Arrow({5, 15}, {45, 15}, shape, 2, kWhite);
  EXPECT_EQ(rimmed.Red(10, 12), 255);
  EXPECT_GT(rimmed.Changed(0), img.Changed(0));
  // too short to point anywhere: nothing
  Image dot(10, 10);
  dot.canvas.Arrow({5, 5}, {5, 5}, shape, 0, kWhite);
  EXPECT_EQ(dot.Changed(0), 0);
}

TEST(Canvas, DegenerateTriangleDrawsNothing) {
  Image img(10, 10);
  img.canvas.Triangle({1, 1}, {5, 5}, {9, 9}, 0, kWhite);
  EXPECT_EQ(img.Changed(0), 0);
  img.canvas.Triangle({1, 1}, {9, 1}, {1, 9}, 0, kWhite);
  EXPECT_EQ(img.Red(2, 2), 255);
  EXPECT_EQ(img.Red(8, 8), 0);
}

TEST(Canvas, TextIsTheFontsTextBlendedByCoverage) {
  Image a(120, 40, 30), b(120, 40, 30);
  const TextMetrics m = a.canvas.Text(-3, 5, "Canvas 1.0\nclipped", 14, kRed);
  TextStyle style;
  style.pixel_size = 14;
  style.color = kRed;
  Font::Default().Draw(b.rgb.data(), b.width, b.height, -3, 5, "Canvas 1.0\nclipped", style);
  EXPECT_EQ(a.rgb, b.rgb);
  EXPECT_EQ(m.lines, 2);
  EXPECT_GT(a.Changed(30), 50);
}

// Five labels whose anchors sit close together: every one placed, inside the area, no two
// boxes closer than the gap, no leader through another box.
TEST(LabelPlacer, PlacedLabelsNeverOverlap) {
  LabelStyle style;
  const int w = 400, h = 300;
  std::vector<LabelRequest> requests;
  std::vector<std::vector<Pixel>> anchors;
  const char* texts[] = {"first", "second label", "third\ntwo lines", "4th", "fifth one"};
  for (int i = 0; i < 5; ++i) {
    requests.push_back({texts[i], kWhite, i * 72.0});
    anchors.push_back({{200.0 + 6 * i, 150.0 - 4 * i}});
  }
  const std::vector<LabelObstacle> obstacles = {{{150, 100}, {250, 200}, 3}};
  LabelPlacer placer(requests, anchors, {}, {}, obstacles, {}, style, w, h, "the test area");
  const std::vector<std::optional<PlacedLabel>> placed = placer.Place();
  ASSERT_EQ(placed.size(), 5u);
  for (size_t i = 0; i < placed.size(); ++i) {
    ASSERT_TRUE(placed[i]) << i;
    const RectF& b = placed[i]->box;
    EXPECT_GE(b.x0, style.gap);
    EXPECT_GE(b.y0, style.gap);
    EXPECT_LE(b.x1, w - style.gap);
    EXPECT_LE(b.y1, h - style.gap);
    EXPECT_EQ(placed[i]->text, texts[i]);
    EXPECT_FALSE(SegmentHitsRect(obstacles[0].a, obstacles[0].b, b)) << i;
    for (size_t j = 0; j < placed.size(); ++j) {
      if (j == i) continue;
      EXPECT_FALSE(Intersect(b, Grown(placed[j]->box, style.gap))) << i << " " << j;
      EXPECT_FALSE(SegmentHitsRect(*placed[j]->anchor, placed[j]->attach, b)) << i << " " << j;
    }
  }
  EXPECT_GT(placer.TotalCost(), 0);
}

TEST(LabelPlacer, NoRoomNamesTheLabelAndTheArea) {
  LabelStyle style;
  LabelPlacer placer({{"far too long for this area", kWhite, 0}}, {{{20, 10}}}, {}, {}, {}, {},
                     style, 60, 30, "a tiny area");
  try {
    placer.Place();
    FAIL() << "no error";
  } catch (const RunError& e) {
    EXPECT_NE(std::string(e.what()).find("the label 'far too long for this area'"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("a tiny area"), std::string::npos) << e.what();
  }
}

TEST(LabelPlacer, DrawLabelsDrawsLeaderDotBoxAndText) {
  Image img(200, 100);
  LabelStyle style;
  PlacedLabel label{"hi", kRed, Pixel{20.5, 80.5}, Pixel{100.5, 40.5}, true, {100.5, 20, 140, 45}};
  DrawLabels({label}, style, {20, 20, 28}, 0.8, &img.canvas);
  EXPECT_EQ(img.Red(20, 80), 255);    // the dot
  EXPECT_EQ(img.Red(60, 60), 255);    // on the leader
  EXPECT_EQ(img.Red(60, 58), 20);     // the leader's dark rim
  EXPECT_EQ(img.At(130, 22)[2], 22);  // the box: 0.8 of (20, 20, 28) over black
  EXPECT_EQ(img.At(130, 22)[0], 16);
  EXPECT_EQ(img.Red(5, 5), 0);
}

}  // namespace
}  // namespace fetchscope
