// FreeType text (render/text.h): finding the font, metrics, drawing, fitting, clipping, and a
// rendered label against a golden crop (tests/data/text_label.png).
#include "render/text.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "base/errors.h"
#include "encode/png_io.h"
#include "inspect/image_diff.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

constexpr Rgb kWhite = {255, 255, 255};

// Sets an environment variable for the life of the object and restores it after.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (old_.empty()) {
      unsetenv(name_);
    } else {
      setenv(name_, old_.c_str(), 1);
    }
  }

 private:
  const char* name_;
  std::string old_;
};

struct Raster {
  int width, height;
  std::vector<uint8_t> rgb;
  Raster(int w, int h, uint8_t fill = 0)
      : width(w), height(h), rgb(static_cast<size_t>(w) * h * 3, fill) {}
  const uint8_t* At(int x, int y) const { return &rgb[(static_cast<size_t>(y) * width + x) * 3]; }
};

// Bounding box of the pixels that differ from `fill` (x0, y0, x1, y1 exclusive); x0 = -1 if none.
struct Box {
  int x0 = -1, y0 = -1, x1 = -1, y1 = -1;
};
Box InkBox(const Raster& c, uint8_t fill) {
  Box box;
  for (int y = 0; y < c.height; ++y) {
    for (int x = 0; x < c.width; ++x) {
      const uint8_t* p = c.At(x, y);
      if (p[0] == fill && p[1] == fill && p[2] == fill) continue;
      if (box.x0 < 0) box = {x, y, x + 1, y + 1};
      box.x0 = std::min(box.x0, x);
      box.y0 = std::min(box.y0, y);
      box.x1 = std::max(box.x1, x + 1);
      box.y1 = std::max(box.y1, y + 1);
    }
  }
  return box;
}

std::vector<uint8_t> Render(const std::string& text, int size) {
  Raster c(200, 60);
  TextStyle style;
  style.pixel_size = size;
  style.color = kWhite;
  Font::Default().Draw(c.rgb.data(), c.width, c.height, 4, 4, text, style);
  return c.rgb;
}

TEST(FindFontFileTest, FindsDejaVuSans) {
  const std::filesystem::path font = FindFontFile();
  EXPECT_NE(font.filename().string().find("DejaVuSans"), std::string::npos) << font;
  EXPECT_TRUE(std::filesystem::is_regular_file(font)) << font;
}

TEST(FindFontFileTest, EnvironmentWinsAndAMissingFileIsNamed) {
  const std::string debian = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
  {
    ScopedEnv env("FETCHSCOPE_FONT", debian);
    EXPECT_EQ(FindFontFile(), debian);
  }
  ScopedEnv env("FETCHSCOPE_FONT", "/nonexistent/Font.ttf");
  try {
    FindFontFile();
    FAIL() << "no exception";
  } catch (const RunError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("/nonexistent/Font.ttf"), std::string::npos) << what;
    EXPECT_NE(what.find("fonts-dejavu-core"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
}

TEST(FontTest, ANonFontFileIsARunErrorNamingIt) {
  testing::TempDir dir;
  const auto path = dir.path() / "not-a-font.ttf";
  std::ofstream(path) << "hello";
  try {
    Font font(path);
    FAIL() << "no exception";
  } catch (const RunError& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
}

TEST(FontTest, MetricsAreSane) {
  const Font& font = Font::Default();
  const TextMetrics empty = font.Measure("", 16);
  EXPECT_EQ(empty.width, 0);
  EXPECT_EQ(empty.height, 0);
  EXPECT_EQ(empty.lines, 0);
  // DejaVu Sans: ascender 0.93 em, descender 0.24 em
  EXPECT_GE(empty.ascent, 14);
  EXPECT_LE(empty.ascent, 17);
  EXPECT_GE(empty.descent, 3);
  EXPECT_LE(empty.descent, 5);
  EXPECT_GE(empty.line_height, empty.ascent + empty.descent);

  const TextMetrics a = font.Measure("A", 16), ab = font.Measure("AB", 16);
  EXPECT_GT(a.width, 5);
  EXPECT_GT(ab.width, a.width);
  EXPECT_EQ(a.lines, 1);
  EXPECT_EQ(a.height, a.ascent + a.descent);
  EXPECT_EQ(font.Measure("A\nABC\nAB", 16).width, font.Measure("ABC", 16).width);
  const TextMetrics two = font.Measure("x\ny", 16);
  EXPECT_EQ(two.lines, 2);
  EXPECT_EQ(two.height, two.line_height + two.ascent + two.descent);

  // twice the size, about twice the width (hinting rounds each advance)
  const std::string sample = "FetchPickAndPlace-v4 seed 12";
  const double ratio =
      static_cast<double>(font.Measure(sample, 32).width) / font.Measure(sample, 16).width;
  EXPECT_GT(ratio, 1.8);
  EXPECT_LT(ratio, 2.2);
  // proportional, not fixed-width
  EXPECT_LT(font.Measure("iiii", 16).width, font.Measure("WWWW", 16).width);

  EXPECT_THROW(font.Measure("x", 3), UsageError);
  EXPECT_THROW(font.Measure("x", 513), UsageError);
}

TEST(FontTest, InkStaysInsideTheMeasuredBox) {
  const Font& font = Font::Default();
  for (int size : {9, 12, 18, 40}) {
    for (const std::string text : {"Hg", "FetchSlide-v4  r=-0.25", "two\nlines jq", "W"}) {
      Raster c(400, 200);
      TextStyle style;
      style.pixel_size = size;
      const int x = 10, y = 20;
      const TextMetrics m = font.Draw(c.rgb.data(), c.width, c.height, x, y, text, style);
      const Box ink = InkBox(c, 0);
      ASSERT_GE(ink.x0, 0) << text << " at " << size << " drew nothing";
      EXPECT_GE(ink.x0, x - 1) << text << " " << size;
      EXPECT_LE(ink.x1, x + m.width + 1) << text << " " << size;
      EXPECT_GE(ink.y0, y) << text << " " << size;
      EXPECT_LE(ink.y1, y + m.height) << text << " " << size;
      // anti-aliased: some pixels are neither background nor full colour
      int partial = 0;
      for (size_t i = 0; i < c.rgb.size(); i += 3) partial += c.rgb[i] > 0 && c.rgb[i] < 255;
      EXPECT_GT(partial, 0) << text << " " << size;
    }
  }
}

TEST(FontTest, BackgroundBoxCoversTextBoxAndPadding) {
  Raster c(120, 60, 7);
  TextStyle style;
  style.pixel_size = 14;
  style.color = {250, 250, 250};
  style.background = Rgb{40, 80, 120};
  style.padding = 3;
  const TextMetrics m = Font::Default().Draw(c.rgb.data(), c.width, c.height, 10, 10, "ok", style);
  const Box box = InkBox(c, 7);
  EXPECT_EQ(box.x0, 7);
  EXPECT_EQ(box.y0, 7);
  EXPECT_EQ(box.x1, 10 + m.width + 3);
  EXPECT_EQ(box.y1, 10 + m.height + 3);
  const uint8_t* corner = c.At(7, 7);
  EXPECT_EQ(corner[0], 40);
  EXPECT_EQ(corner[1], 80);
  EXPECT_EQ(corner[2], 120);
  EXPECT_THROW(
      {
        style.padding = -1;
        Font::Default().Draw(c.rgb.data(), c.width, c.height, 0, 0, "x", style);
      },
      UsageError);
}

TEST(FontTest, Utf8IsDecoded) {
  // é is its own glyph, not e and not a replacement box
  EXPECT_NE(Render("\xc3\xa9", 20), Render("e", 20));
  EXPECT_NE(Render("\xc3\xa9", 20), Render("\xef\xbf\xbd", 20));
  // malformed bytes draw as U+FFFD
  EXPECT_EQ(Render("\xff", 20), Render("\xef\xbf\xbd", 20));
  EXPECT_EQ(Render("\xc3", 20), Render("\xef\xbf\xbd", 20));
}

TEST(FontTest, FitCutsAtCharactersWithAnEllipsis) {
  const Font& font = Font::Default();
  EXPECT_EQ(font.Fit("short", 12, 200), "short");
  const std::string long_text = "FetchPickAndPlace-v4 seed 123456789 policy scripted";
  const std::string cut = font.Fit(long_text, 12, 100);
  EXPECT_LE(font.Measure(cut, 12).width, 100);
  ASSERT_GE(cut.size(), 4u);
  EXPECT_EQ(cut.substr(cut.size() - 3), "...");
  EXPECT_EQ(long_text.compare(0, cut.size() - 3, cut, 0, cut.size() - 3), 0);
  // never splits a UTF-8 sequence
  const std::string accents = "\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9\xc3\xa9";
  const std::string cut_accents = font.Fit(accents, 12, 30);
  EXPECT_EQ((cut_accents.size() - 3) % 2, 0u) << cut_accents;
  EXPECT_EQ(font.Fit(long_text, 12, 2), "");
}

TEST(FontTest, ClipsAtEveryEdge) {
  // A 20x12 image inside a guard band: text hanging over every edge must not touch the guard.
  const int w = 20, h = 12, guard = 64;
  std::vector<uint8_t> memory(guard + w * h * 3 + guard, 7);
  uint8_t* image = memory.data() + guard;
  std::fill(image, image + w * h * 3, 0);
  TextStyle style;
  style.pixel_size = 16;
  for (int with_box : {1, 0}) {  // boxes first, so the glyphs drawn after them stay visible
    style.background = with_box ? std::optional<Rgb>(Rgb{1, 2, 3}) : std::nullopt;
    style.padding = with_box ? 5 : 0;
    for (int x : {-30, -3, 0, 15, 19, 40}) {
      for (int y : {-20, -4, 0, 8, 11, 30}) {
        Font::Default().Draw(image, w, h, x, y, "WM#@\nWM#@", style);
      }
    }
  }
  for (int i = 0; i < guard; ++i) {
    ASSERT_EQ(memory[i], 7);
    ASSERT_EQ(memory[guard + w * h * 3 + i], 7);
  }
  EXPECT_GT(std::count(image, image + w * h * 3, 255), 0);
}

// A tile label as the tool draws one, against tests/data/text_label.png (made by this test with
// FETCHSCOPE_UPDATE_TEXT_GOLDEN=1 and checked by eye). Debian's FreeType renders the same bytes
// on every machine; a small tolerance absorbs a FreeType point release.
TEST(FontTest, LabelMatchesGoldenCrop) {
  Raster c(240, 40, 30);
  TextStyle style;
  style.pixel_size = 15;
  style.color = {235, 235, 235};
  style.background = Rgb{44, 44, 50};
  style.padding = 4;
  Font::Default().Draw(c.rgb.data(), c.width, c.height, 8, 8,
                       "FetchPush-v4 \xc2\xb7 seed 7 \xe2\x9c\x93", style);
  const std::string golden = (testing::SourceDir() / "tests/data/text_label.png").string();
  if (std::getenv("FETCHSCOPE_UPDATE_TEXT_GOLDEN")) {
    WritePng(golden, c.width, c.height, 3, 8, c.rgb.data());
    GTEST_SKIP() << "wrote " << golden;
  }
  const Image expected = ReadPng(golden);
  ASSERT_EQ(expected.width, c.width);
  ASSERT_EQ(expected.height, c.height);
  ASSERT_EQ(expected.channels, 3);
  const ImageDiffStats diff =
      CompareRgb(expected.pixels.data(), c.rgb.data(), c.width, c.height, 24);
  EXPECT_LE(diff.fraction_over, 0.002) << "max diff " << diff.max_diff << ", rms " << diff.rms;
  EXPECT_LT(diff.rms, 3.0);
  // and the label is really there: the golden is not a blank box
  int light = 0;
  for (size_t i = 0; i < c.rgb.size(); i += 3) light += c.rgb[i] > 140;
  EXPECT_GT(light, 100);
}

}  // namespace
}  // namespace fetchscope
