// Contact sheet layout, tile scaling and labels, and the bitmap font under them.
#include "render/contact_sheet.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "render/bitmap_font.h"
#include "src/errors.h"

namespace fetchscope {
namespace {

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

// Top-left corner of tile i, from the layout documented in the header.
struct Origin {
  int x, y;
};
Origin TileOrigin(int i, int columns, int tile_width, int cell_height) {
  return {kSheetMargin + (i % columns) * (tile_width + kSheetMargin),
          kSheetTitleBarHeight + kSheetMargin +
              (i / columns) * (kSheetMargin + cell_height + kSheetLabelBarHeight)};
}

const Rgb kPalette[] = {{255, 0, 0},   {0, 255, 0},   {0, 0, 255},     {255, 255, 0},
                        {0, 255, 255}, {255, 0, 255}, {128, 64, 32},   {10, 200, 90},
                        {200, 10, 90}, {90, 10, 200}, {250, 250, 250}, {5, 5, 5}};

TEST(MakeContactSheetTest, SizeFollowsTheLayout) {
  // 5 tiles of 100x50 at width 40 -> 40x20 cells; ceil(sqrt(5)) = 3 columns, 2 rows.
  std::vector<SheetTile> tiles;
  for (int i = 0; i < 5; ++i) tiles.push_back(SolidTile(100, 50, kPalette[i]));
  SheetImage sheet = MakeContactSheet("title", tiles, 40);
  EXPECT_EQ(sheet.width, kSheetMargin + 3 * (40 + kSheetMargin));
  EXPECT_EQ(sheet.height,
            kSheetTitleBarHeight + 2 * (kSheetMargin + 20 + kSheetLabelBarHeight) + kSheetMargin);
  EXPECT_EQ(sheet.rgb.size(), static_cast<size_t>(sheet.width) * sheet.height * 3);

  sheet = MakeContactSheet("title", tiles, 40, /*columns=*/1);
  EXPECT_EQ(sheet.width, kSheetMargin + 40 + kSheetMargin);
  EXPECT_EQ(sheet.height,
            kSheetTitleBarHeight + 5 * (kSheetMargin + 20 + kSheetLabelBarHeight) + kSheetMargin);

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
  const SheetImage sheet = MakeContactSheet("FetchReach-v4 seed 1", tiles, tile_width, columns);

  const int title_text = CountColor(sheet, 0, 0, sheet.width, kSheetTitleBarHeight, kSheetText);
  EXPECT_GT(title_text, 100);

  auto bar_text = [&](int i, int first_row, int rows) {
    const Origin o = TileOrigin(i, columns, tile_width, cell_height);
    return CountColor(sheet, o.x, o.y + cell_height + first_row, tile_width, rows, kSheetText);
  };
  auto bar_fill = [&](int i) {
    const Origin o = TileOrigin(i, columns, tile_width, cell_height);
    return CountColor(sheet, o.x, o.y + cell_height, tile_width, kSheetLabelBarHeight,
                      kSheetLabelBar);
  };
  // two lines on tile 0, one on tile 1, none on tile 2; the bar is filled around the text
  EXPECT_GT(bar_text(0, 0, kLineHeight), 20);
  EXPECT_GT(bar_text(0, kLineHeight, kSheetLabelBarHeight - kLineHeight), 20);
  EXPECT_GT(bar_text(1, 0, kLineHeight), 10);
  EXPECT_EQ(bar_text(1, kLineHeight, kSheetLabelBarHeight - kLineHeight), 0);
  EXPECT_EQ(bar_text(2, 0, kSheetLabelBarHeight), 0);
  EXPECT_EQ(bar_fill(2), tile_width * kSheetLabelBarHeight);
  EXPECT_GT(bar_fill(0), tile_width * kSheetLabelBarHeight / 2);

  // An empty title leaves the title bar plain.
  const SheetImage untitled = MakeContactSheet("", tiles, tile_width, columns);
  EXPECT_EQ(CountColor(untitled, 0, 0, untitled.width, kSheetTitleBarHeight, kSheetText), 0);
}

TEST(MakeContactSheetTest, LongLabelsStayInsideTheirBar) {
  const std::string long_line(200, 'W');
  const SheetImage sheet =
      MakeContactSheet(std::string(300, 'M'),
                       {SolidTile(32, 32, kPalette[0], long_line + "\n" + long_line),
                        SolidTile(32, 32, kPalette[1], long_line)},
                       64, 2);
  const Origin first = TileOrigin(0, 2, 64, 64);
  const Origin second = TileOrigin(1, 2, 64, 64);
  // no text in the margin between the two label bars, nor right of the sheet's last bar
  EXPECT_EQ(
      CountColor(sheet, first.x + 64, first.y + 64, kSheetMargin, kSheetLabelBarHeight, kSheetText),
      0);
  EXPECT_EQ(CountColor(sheet, second.x + 64, second.y + 64, kSheetMargin, kSheetLabelBarHeight,
                       kSheetText),
            0);
  // the title is cut before the right margin
  EXPECT_EQ(CountColor(sheet, sheet.width - kSheetMargin, 0, kSheetMargin, kSheetTitleBarHeight,
                       kSheetText),
            0);
  EXPECT_GT(CountColor(sheet, 0, 0, sheet.width, kSheetTitleBarHeight, kSheetText), 0);
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
  EXPECT_EQ(sheet.height, kSheetTitleBarHeight + kSheetMargin);
}

TEST(BitmapFontTest, TextWidthAndHeight) {
  EXPECT_EQ(TextWidth("", 1), 0);
  EXPECT_EQ(TextWidth("A", 1), kGlyphWidth);
  EXPECT_EQ(TextWidth("AB", 1), kGlyphAdvance + kGlyphWidth);
  EXPECT_EQ(TextWidth("AB", 3), 3 * (kGlyphAdvance + kGlyphWidth));
  EXPECT_EQ(TextWidth("A\nABC\nAB", 1), 2 * kGlyphAdvance + kGlyphWidth);
  EXPECT_EQ(TextHeight("", 2), 0);
  EXPECT_EQ(TextHeight("x", 2), 2 * kGlyphHeight);
  EXPECT_EQ(TextHeight("x\ny", 1), kLineHeight + kGlyphHeight);
}

// The lit pixels of `text` drawn alone, as a string of '#' and '.'.
std::string Render(const std::string& text, int scale) {
  const int w = TextWidth(text, scale), h = kGlyphHeight * scale;
  std::vector<uint8_t> rgb(static_cast<size_t>(w) * h * 3, 0);
  DrawText(rgb.data(), w, h, 0, 0, text, scale, {255, 255, 255});
  std::string bits;
  for (size_t i = 0; i < rgb.size(); i += 3) bits += rgb[i] ? '#' : '.';
  return bits;
}

TEST(BitmapFontTest, EveryPrintableGlyphIsDistinctAndOnlySpaceIsBlank) {
  std::set<std::string> seen;
  for (int code = 33; code <= 126; ++code) {
    const std::string bits = Render(std::string(1, static_cast<char>(code)), 1);
    EXPECT_NE(bits.find('#'), std::string::npos) << "glyph " << code << " is blank";
    EXPECT_TRUE(seen.insert(bits).second) << "glyph " << static_cast<char>(code) << " repeats";
  }
  EXPECT_EQ(Render(" ", 1).find('#'), std::string::npos);
  // non-ASCII bytes draw as '?'
  EXPECT_EQ(Render("\xe9", 1), Render("?", 1));
}

TEST(BitmapFontTest, ScaleMakesBlocks) {
  const std::string one = Render("A", 1), two = Render("A", 2);
  for (int y = 0; y < 2 * kGlyphHeight; ++y) {
    for (int x = 0; x < 2 * kGlyphWidth; ++x) {
      ASSERT_EQ(two[y * 2 * kGlyphWidth + x], one[(y / 2) * kGlyphWidth + x / 2]) << x << "," << y;
    }
  }
}

TEST(BitmapFontTest, ClipsAtEveryEdge) {
  // A 20x12 image inside a guard band: text hanging over every edge must not
  // touch the guard bytes.
  const int w = 20, h = 12, guard = 64;
  std::vector<uint8_t> memory(guard + w * h * 3 + guard, 7);
  uint8_t* image = memory.data() + guard;
  std::fill(image, image + w * h * 3, 0);
  for (int x : {-30, -3, 0, 15, 19, 40}) {
    for (int y : {-20, -4, 0, 8, 11, 30}) {
      DrawText(image, w, h, x, y, "WM#@\nWM#@", 2, {255, 255, 255});
    }
  }
  for (int i = 0; i < guard; ++i) {
    ASSERT_EQ(memory[i], 7);
    ASSERT_EQ(memory[guard + w * h * 3 + i], 7);
  }
  EXPECT_GT(std::count(image, image + w * h * 3, 255), 0);
}

}  // namespace
}  // namespace fetchscope
