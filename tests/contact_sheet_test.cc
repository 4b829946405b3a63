// Contact sheet layout, tile scaling and labels (the text itself: text_test.cc), and captions
// without "-0".
#include "encode/contact_sheet.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "base/errors.h"
#include "base/number_format.h"
#include "base/text_table.h"
#include "encode/png_io.h"
#include "encode/video_reader.h"
#include "encode/video_writer.h"
#include "inspect/image_diff.h"
#include "render/overlay.h"
#include "render/text.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::ReachSuccessStep;

struct IndicesCase {
  std::string name;
  int num_frames;
  int every;
  std::vector<int> expected;
};

class SheetFrameIndicesTest : public ::testing::TestWithParam<IndicesCase> {};

TEST_P(SheetFrameIndicesTest, PicksEveryKthAndTheLast) {
  EXPECT_EQ(SheetFrameIndices(GetParam().num_frames, GetParam().every), GetParam().expected);
}

INSTANTIATE_TEST_SUITE_P(
    Cases, SheetFrameIndicesTest,
    ::testing::Values(
        // 50 steps = 51 frames: about 12 tiles, first and last included
        IndicesCase{"Default50Steps", 51, 0, {0, 5, 10, 15, 20, 25, 30, 35, 40, 45, 50}},
        IndicesCase{"Every10", 51, 10, {0, 10, 20, 30, 40, 50}},
        IndicesCase{"EveryLargerThanEpisode", 51, 100, {0, 50}},
        IndicesCase{"LastNotOnTheGrid", 53, 10, {0, 10, 20, 30, 40, 50, 52}},
        IndicesCase{"ShortEpisodeDefault", 12, 0, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}},
        IndicesCase{"Every1", 4, 1, {0, 1, 2, 3}}, IndicesCase{"ResetFrameOnly", 1, 0, {0}},
        IndicesCase{"NoFrames", 0, 0, {}}),
    [](const ::testing::TestParamInfo<IndicesCase>& info) { return info.param.name; });

TEST(SheetFrameIndicesTest, DefaultGivesAtMost12TilesWithBothEnds) {
  for (int frames = 2; frames <= 1001; ++frames) {
    const std::vector<int> indices = SheetFrameIndices(frames, 0);
    ASSERT_LE(indices.size(), 12u) << frames;
    ASSERT_GE(indices.size(), std::min(frames, 7)) << frames;
    ASSERT_EQ(indices.front(), 0);
    ASSERT_EQ(indices.back(), frames - 1);
    for (size_t i = 1; i < indices.size(); ++i) ASSERT_LT(indices[i - 1], indices[i]);
  }
}

TEST(SheetFrameIndicesTest, NegativeStepIsAUsageError) {
  EXPECT_THROW(SheetFrameIndices(51, -1), UsageError);
}

SheetTile SolidTile(int width, int height, Rgb color, const std::string& label = "") {
  SheetTile tile;
  tile.width = width;
  tile.height = height;
  tile.label = label;
  tile.rgb.resize(static_cast<size_t>(width) * height * 3);
  for (size_t i = 0; i < tile.rgb.size(); i += 3) {
    tile.rgb[i] = color.r;
    tile.rgb[i + 1] = color.g;
    tile.rgb[i + 2] = color.b;
  }
  return tile;
}

Rgb PixelAt(const SheetImage& image, int x, int y) {
  const uint8_t* p = &image.rgb[(static_cast<size_t>(y) * image.width + x) * 3];
  return {p[0], p[1], p[2]};
}

bool Same(Rgb a, Rgb b) { return a.r == b.r && a.g == b.g && a.b == b.b; }

// Pixels of `color` in the rectangle [x0, x0+w) x [y0, y0+h).
int CountColor(const SheetImage& image, int x0, int y0, int w, int h, Rgb color) {
  int count = 0;
  for (int y = y0; y < y0 + h; ++y) {
    for (int x = x0; x < x0 + w; ++x) count += Same(PixelAt(image, x, y), color);
  }
  return count;
}

// Pixels in the rectangle that carry text ink: the text is light (235) and anti-aliased, the
// bars and background under it dark (24..50), so a pixel past half-way is text.
int CountInk(const SheetImage& image, int x0, int y0, int w, int h) {
  int count = 0;
  for (int y = y0; y < y0 + h; ++y) {
    for (int x = x0; x < x0 + w; ++x) count += PixelAt(image, x, y).g > 140;
  }
  return count;
}

// Top-left corner of tile i, from the layout documented in the header.
struct Origin {
  int x, y;
};
Origin TileOrigin(int i, int columns, int tile_width, int cell_height) {
  const SheetLayout layout = ContactSheetLayout(tile_width);
  return {kSheetMargin + (i % columns) * (tile_width + kSheetMargin),
          layout.title_bar_height + kSheetMargin +
              (i / columns) * (kSheetMargin + cell_height + layout.label_bar_height)};
}

TEST(ContactSheetLayoutTest, TextGrowsWithTheTiles) {
  const SheetLayout small = ContactSheetLayout(64), usual = ContactSheetLayout(240),
                    large = ContactSheetLayout(640);
  EXPECT_EQ(small.label_pixel_size, 9);
  EXPECT_EQ(usual.label_pixel_size, 12);
  EXPECT_EQ(large.label_pixel_size, 32);
  EXPECT_EQ(usual.title_pixel_size, 18);
  EXPECT_LT(small.label_bar_height, usual.label_bar_height);
  EXPECT_LT(usual.label_bar_height, large.label_bar_height);
  EXPECT_LT(usual.title_bar_height, large.title_bar_height);
  // two lines of labels fit: at least two line heights plus the padding
  EXPECT_GE(usual.label_bar_height, 2 * usual.label_line_height + 2 * kSheetLabelPadding);
  EXPECT_GE(usual.label_line_height, usual.label_pixel_size);
}

const Rgb kPalette[] = {{255, 0, 0},   {0, 255, 0},   {0, 0, 255},     {255, 255, 0},
                        {0, 255, 255}, {255, 0, 255}, {128, 64, 32},   {10, 200, 90},
                        {200, 10, 90}, {90, 10, 200}, {250, 250, 250}, {5, 5, 5}};

TEST(MakeContactSheetTest, SizeFollowsTheLayout) {
  // 5 tiles of 100x50 at width 40 -> 40x20 cells; ceil(sqrt(5)) = 3 columns, 2 rows.
  std::vector<SheetTile> tiles;
  for (int i = 0; i < 5; ++i) tiles.push_back(SolidTile(100, 50, kPalette[i]));
  const SheetLayout layout = ContactSheetLayout(40);
  SheetImage sheet = MakeContactSheet("title", tiles, 40);
  EXPECT_EQ(sheet.width, kSheetMargin + 3 * (40 + kSheetMargin));
  EXPECT_EQ(sheet.height, layout.title_bar_height +
                              2 * (kSheetMargin + 20 + layout.label_bar_height) + kSheetMargin);
  EXPECT_EQ(sheet.rgb.size(), static_cast<size_t>(sheet.width) * sheet.height * 3);

  sheet = MakeContactSheet("title", tiles, 40, /*columns=*/1);
  EXPECT_EQ(sheet.width, kSheetMargin + 40 + kSheetMargin);
  EXPECT_EQ(sheet.height, layout.title_bar_height +
                              5 * (kSheetMargin + 20 + layout.label_bar_height) + kSheetMargin);

  // more columns than tiles: no empty columns
  sheet = MakeContactSheet("title", tiles, 40, /*columns=*/9);
  EXPECT_EQ(sheet.width, kSheetMargin + 5 * (40 + kSheetMargin));
}

TEST(MakeContactSheetTest, EachTileLandsInItsCell) {
  std::vector<SheetTile> tiles;
  for (int i = 0; i < 7; ++i) tiles.push_back(SolidTile(64, 48, kPalette[i]));
  const int tile_width = 32, cell_height = 24, columns = 3;
  const SheetImage sheet = MakeContactSheet("cells", tiles, tile_width);
  for (int i = 0; i < 7; ++i) {
    const Origin o = TileOrigin(i, columns, tile_width, cell_height);
    EXPECT_EQ(CountColor(sheet, o.x, o.y, tile_width, cell_height, kPalette[i]),
              tile_width * cell_height)
        << "tile " << i;
    // the margin just outside the cell is background
    EXPECT_TRUE(Same(PixelAt(sheet, o.x - 1, o.y), kSheetBackground)) << "tile " << i;
    EXPECT_TRUE(Same(PixelAt(sheet, o.x + tile_width, o.y), kSheetBackground)) << "tile " << i;
  }
  // the unused 9th cell stays background
  const Origin empty = TileOrigin(8, columns, tile_width, cell_height);
  EXPECT_EQ(CountColor(sheet, empty.x, empty.y, tile_width, cell_height, kSheetBackground),
            tile_width * cell_height);
}

TEST(MakeContactSheetTest, KeepsAspectAndShorterTilesLeaveBackground) {
  // 100x100 -> 40x40 sets the cell height; 100x50 -> 40x20 fills its top half.
  const SheetImage sheet = MakeContactSheet(
      "", {SolidTile(100, 100, kPalette[0]), SolidTile(100, 50, kPalette[1])}, 40, 2);
  const Origin second = TileOrigin(1, 2, 40, 40);
  EXPECT_EQ(CountColor(sheet, second.x, second.y, 40, 20, kPalette[1]), 40 * 20);
  EXPECT_EQ(CountColor(sheet, second.x, second.y + 20, 40, 20, kSheetBackground), 40 * 20);
}

TEST(MakeContactSheetTest, BoxFilterAveragesEverySourcePixel) {
  // One-pixel black/white stripes halved: a box filter gives even grey,
  // point sampling would give all black or all white.
  SheetTile stripes = SolidTile(80, 40, {0, 0, 0});
  for (int y = 0; y < 40; ++y) {
    for (int x = 1; x < 80; x += 2) {
      for (int c = 0; c < 3; ++c) stripes.rgb[(y * 80 + x) * 3 + c] = 255;
    }
  }
  const SheetImage sheet = MakeContactSheet("", {stripes}, 40);
  const Origin o = TileOrigin(0, 1, 40, 20);
  for (int y = o.y; y < o.y + 20; ++y) {
    for (int x = o.x; x < o.x + 40; ++x) {
      const Rgb p = PixelAt(sheet, x, y);
      ASSERT_NEAR(p.r, 128, 1) << x << "," << y;
      ASSERT_NEAR(p.g, 128, 1) << x << "," << y;
    }
  }
}

TEST(MakeContactSheetTest, TitleAndLabelsAreDrawn) {
  std::vector<SheetTile> tiles = {SolidTile(64, 64, kPalette[2], "t=0  r=-0.5\nsuccess"),
                                  SolidTile(64, 64, kPalette[3], "t=10"),
                                  SolidTile(64, 64, kPalette[4], "")};
  const int tile_width = 96, cell_height = 96, columns = 3;
  const SheetLayout layout = ContactSheetLayout(tile_width);
  const SheetImage sheet = MakeContactSheet("FetchReach-v4 seed 1", tiles, tile_width, columns);

  EXPECT_GT(CountInk(sheet, 0, 0, sheet.width, layout.title_bar_height), 60);

  // the first line ends where the second line's box starts
  const int first_rows = kSheetLabelPadding + layout.label_line_height;
  auto bar_text = [&](int i, int first_row, int rows) {
    const Origin o = TileOrigin(i, columns, tile_width, cell_height);
    return CountInk(sheet, o.x, o.y + cell_height + first_row, tile_width, rows);
  };
  auto bar_fill = [&](int i) {
    const Origin o = TileOrigin(i, columns, tile_width, cell_height);
    return CountColor(sheet, o.x, o.y + cell_height, tile_width, layout.label_bar_height,
                      kSheetLabelBar);
  };
  // two lines on tile 0, one on tile 1, none on tile 2; the bar is filled around the text
  EXPECT_GT(bar_text(0, 0, first_rows), 20);
  EXPECT_GT(bar_text(0, first_rows, layout.label_bar_height - first_rows), 20);
  EXPECT_GT(bar_text(1, 0, first_rows), 10);
  EXPECT_EQ(bar_text(1, first_rows, layout.label_bar_height - first_rows), 0);
  EXPECT_EQ(bar_text(2, 0, layout.label_bar_height), 0);
  EXPECT_EQ(bar_fill(2), tile_width * layout.label_bar_height);
  EXPECT_GT(bar_fill(0), tile_width * layout.label_bar_height / 2);

  // An empty title leaves the title bar plain.
  const SheetImage untitled = MakeContactSheet("", tiles, tile_width, columns);
  EXPECT_EQ(CountColor(untitled, 0, 0, untitled.width, layout.title_bar_height, kSheetBackground),
            untitled.width * layout.title_bar_height);
}

TEST(MakeContactSheetTest, LongLabelsStayInsideTheirBar) {
  const std::string long_line(200, 'W');
  const SheetLayout layout = ContactSheetLayout(64);
  const SheetImage sheet =
      MakeContactSheet(std::string(300, 'M'),
                       {SolidTile(32, 32, kPalette[0], long_line + "\n" + long_line),
                        SolidTile(32, 32, kPalette[1], long_line)},
                       64, 2);
  const Origin first = TileOrigin(0, 2, 64, 64);
  const Origin second = TileOrigin(1, 2, 64, 64);
  // no ink in the margin between the two label bars, nor right of the sheet's last bar
  EXPECT_EQ(CountColor(sheet, first.x + 64, first.y + 64, kSheetMargin, layout.label_bar_height,
                       kSheetBackground),
            kSheetMargin * layout.label_bar_height);
  EXPECT_EQ(CountColor(sheet, second.x + 64, second.y + 64, kSheetMargin, layout.label_bar_height,
                       kSheetBackground),
            kSheetMargin * layout.label_bar_height);
  EXPECT_GT(CountInk(sheet, first.x, first.y + 64, 64, layout.label_bar_height), 20);
  // the title is cut before the right margin
  EXPECT_EQ(CountColor(sheet, sheet.width - kSheetMargin, 0, kSheetMargin, layout.title_bar_height,
                       kSheetBackground),
            kSheetMargin * layout.title_bar_height);
  EXPECT_GT(CountInk(sheet, 0, 0, sheet.width, layout.title_bar_height), 0);
}

TEST(MakeContactSheetTest, BadArgumentsAreNamed) {
  const std::vector<SheetTile> tiles = {SolidTile(8, 8, kPalette[0])};
  EXPECT_THROW(MakeContactSheet("", tiles, 8), UsageError);
  EXPECT_THROW(MakeContactSheet("", tiles, 5000), UsageError);
  EXPECT_THROW(MakeContactSheet("", tiles, 64, -1), UsageError);
  SheetTile broken = SolidTile(8, 8, kPalette[0], "step 7");
  broken.rgb.pop_back();
  try {
    MakeContactSheet("", {tiles[0], broken}, 64);
    FAIL() << "no exception";
  } catch (const RunError& e) {
    EXPECT_NE(std::string(e.what()).find("tile 1 (step 7)"), std::string::npos) << e.what();
  }
}

TEST(MakeContactSheetTest, NoTilesGivesATitleOnlySheet) {
  const SheetImage sheet = MakeContactSheet("nothing", {}, 64);
  EXPECT_EQ(sheet.width, kSheetMargin + 64 + kSheetMargin);
  EXPECT_EQ(sheet.height, ContactSheetLayout(64).title_bar_height + kSheetMargin);
}

// Tiles scaled when their frame arrives (what record keeps) make the very sheet the full frames
// make: same size, same bytes, whatever the frame size (down, up, odd aspect).
TEST(ScaleSheetTileTest, PreScaledTilesGiveTheSameSheet) {
  SheetScratch scratch;  // one for every size, as an episode's encoder reuses it
  for (const auto& [w, h] : std::vector<std::pair<int, int>>{{480, 480}, {641, 357}, {100, 77}}) {
    std::vector<SheetTile> frames, scaled;
    for (int i = 0; i < 5; ++i) {
      SheetTile frame;
      frame.width = w;
      frame.height = h;
      frame.label = "t=" + std::to_string(i) + "\nd=0.1";
      frame.rgb.resize(static_cast<size_t>(w) * h * 3);
      for (size_t k = 0; k < frame.rgb.size(); ++k) {
        frame.rgb[k] = static_cast<uint8_t>((k * 7 + k / 3 * 13 + i * 29) % 256);
      }
      scaled.push_back(
          ScaleSheetTile(frame.rgb.data(), w, h, frame.label, kSheetTileWidth, &scratch));
      EXPECT_EQ(scaled.back().width, kSheetTileWidth);
      frames.push_back(std::move(frame));
    }
    const SheetImage a = MakeContactSheet("title", frames);
    const SheetImage b = MakeContactSheet("title", scaled);
    ASSERT_EQ(a.width, b.width) << w << "x" << h;
    ASSERT_EQ(a.height, b.height) << w << "x" << h;
    EXPECT_TRUE(a.rgb == b.rgb) << w << "x" << h;
  }
  EXPECT_THROW(ScaleSheetTile(nullptr, 0, 10, "", kSheetTileWidth, &scratch), RunError);
  std::vector<uint8_t> pixel(3);
  EXPECT_THROW(ScaleSheetTile(pixel.data(), 1, 1, "", 8, &scratch), UsageError);
}

TEST(PictureNumber, SheetCaptionShowsRZero) {
  const std::string caption = SheetCaption(ReachSuccessStep());
  EXPECT_EQ(caption, "t=7 r=0\nd=0.012 SUCCESS") << caption;
  FrameInfo miss = ReachSuccessStep();
  miss.reward = -1;
  miss.success = false;
  EXPECT_EQ(SheetCaption(miss), "t=7 r=-1\nd=0.012 ");
  FrameInfo reset;
  EXPECT_EQ(SheetCaption(reset), "t=0 reset\nd=0.000 ");
}

}  // namespace
}  // namespace fetchscope
