// PNG writing and reading through libpng.
#include "encode/png_io.h"

#include <gtest/gtest.h>
#include <png.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "base/errors.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;

// Files in `dir` other than `keep` (to catch leftover temporary files).
std::vector<std::string> OtherFiles(const fs::path& dir, const std::string& keep) {
  std::vector<std::string> others;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().filename() != keep) others.push_back(entry.path().filename().string());
  }
  return others;
}

TEST(PngIo, RoundTripsRgb8) {
  testing::TempDir dir;
  const int w = 37, h = 23;  // odd sizes catch row-stride mistakes
  std::vector<uint8_t> pixels(w * h * 3);
  for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = static_cast<uint8_t>(i * 7 + i / 5);
  const std::string path = (dir.path() / "rgb.png").string();
  WritePng(path, w, h, 3, 8, pixels.data());
  EXPECT_TRUE(OtherFiles(dir.path(), "rgb.png").empty());

  Image image = ReadPng(path);
  EXPECT_EQ(image.width, w);
  EXPECT_EQ(image.height, h);
  EXPECT_EQ(image.channels, 3);
  EXPECT_EQ(image.bit_depth, 8);
  EXPECT_EQ(image.pixels, pixels);
}

TEST(PngIo, RoundTripsGray16InHostOrder) {
  testing::TempDir dir;
  const int w = 5, h = 3;
  std::vector<uint16_t> depth = {0, 1, 255, 256, 1000, 65535, 4242, 0x0102,
                                 7, 8, 9,   10,  11,   12,    60000};
  const std::string path = (dir.path() / "depth.png").string();
  WritePng(path, w, h, 1, 16, depth.data());
  Image image = ReadPng(path);
  ASSERT_EQ(image.width, w);
  ASSERT_EQ(image.height, h);
  EXPECT_EQ(image.channels, 1);
  EXPECT_EQ(image.bit_depth, 16);
  ASSERT_EQ(image.pixels.size(), depth.size() * 2);
  std::vector<uint16_t> back(depth.size());
  std::memcpy(back.data(), image.pixels.data(), image.pixels.size());
  EXPECT_EQ(back, depth);
}

TEST(PngIo, Gray16IsBigEndianInTheFile) {
  // Any other PNG reader must see the same numbers: decode with libpng and no swapping.
  testing::TempDir dir;
  const uint16_t value[2] = {0x0102, 0xA0B0};
  const std::string path = (dir.path() / "two.png").string();
  WritePng(path, 2, 1, 1, 16, value);

  FILE* file = std::fopen(path.c_str(), "rb");
  ASSERT_NE(file, nullptr);
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  uint8_t row[4] = {};
  if (setjmp(png_jmpbuf(png)) == 0) {
    png_init_io(png, file);
    png_read_info(png, info);
    png_read_row(png, row, nullptr);
  }
  png_destroy_read_struct(&png, &info, nullptr);
  std::fclose(file);
  EXPECT_EQ(row[0], 0x01);
  EXPECT_EQ(row[1], 0x02);
  EXPECT_EQ(row[2], 0xA0);
  EXPECT_EQ(row[3], 0xB0);
}

TEST(PngIo, RoundTripsAlphaFormats) {
  testing::TempDir dir;
  for (int channels : {1, 2, 4}) {
    const int w = 4, h = 4;
    std::vector<uint8_t> pixels(w * h * channels);
    for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = static_cast<uint8_t>(255 - i);
    const std::string path = (dir.path() / ("c" + std::to_string(channels) + ".png")).string();
    WritePng(path, w, h, channels, 8, pixels.data());
    Image image = ReadPng(path);
    EXPECT_EQ(image.channels, channels);
    EXPECT_EQ(image.pixels, pixels);
  }
}

TEST(PngIo, OverwritesAtomically) {
  testing::TempDir dir;
  const std::string path = (dir.path() / "frame.png").string();
  const uint8_t black[3] = {0, 0, 0}, white[3] = {255, 255, 255};
  WritePng(path, 1, 1, 3, 8, black);
  WritePng(path, 1, 1, 3, 8, white);
  EXPECT_EQ(ReadPng(path).pixels, std::vector<uint8_t>(white, white + 3));
  EXPECT_TRUE(OtherFiles(dir.path(), "frame.png").empty());
}

TEST(PngIo, GarbageIsARunError) {
  testing::TempDir dir;
  const std::string path = (dir.path() / "garbage.png").string();
  std::ofstream(path) << "this is not a picture, just text pretending";
  try {
    ReadPng(path);
    FAIL() << "expected RunError";
  } catch (const RunError& e) {
    EXPECT_NE(std::string(e.what()).find("is not a PNG file"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(PngIo, TruncatedFileIsARunError) {
  testing::TempDir dir;
  const std::string path = (dir.path() / "cut.png").string();
  std::vector<uint8_t> pixels(64 * 64 * 3);
  for (size_t i = 0; i < pixels.size(); ++i) pixels[i] = static_cast<uint8_t>(i * 31);
  WritePng(path, 64, 64, 3, 8, pixels.data());
  fs::resize_file(path, fs::file_size(path) / 2);
  try {
    ReadPng(path);
    FAIL() << "expected RunError";
  } catch (const RunError& e) {
    EXPECT_NE(std::string(e.what()).find("damaged PNG"), std::string::npos) << e.what();
  }
}

TEST(PngIo, MissingFileIsARunError) {
  EXPECT_THROW(ReadPng("/nonexistent/fetchscope/none.png"), RunError);
}

TEST(PngIo, UnwritableFolderLeavesNothing) {
  testing::TempDir dir;
  // a regular file where a folder should be (tests run as root, where mode bits do not stop us)
  std::ofstream(dir.path() / "f") << "x";
  const std::string folder = (dir.path() / "f" / "sub").string();
  const uint8_t pixel[3] = {1, 2, 3};
  try {
    WritePng(folder + "/x.png", 1, 1, 3, 8, pixel);
    FAIL() << "expected UsageError";
  } catch (const UsageError& e) {  // a path that cannot be: the command line's (exit 2)
    EXPECT_NE(std::string(e.what()).find(folder), std::string::npos) << e.what();
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1);
}

TEST(PngIo, MissingFoldersAreCreated) {
  testing::TempDir dir;
  const fs::path path = dir.path() / "no_such_folder" / "deeper" / "x.png";
  const uint8_t pixel[3] = {1, 2, 3};
  WritePng(path.string(), 1, 1, 3, 8, pixel);
  const Image image = ReadPng(path.string());
  EXPECT_EQ(image.width, 1);
  EXPECT_EQ(image.pixels, std::vector<uint8_t>(pixel, pixel + 3));
}

TEST(PngIo, BadArgumentsAreUsageErrors) {
  testing::TempDir dir;
  const std::string path = (dir.path() / "bad.png").string();
  const uint8_t pixel[8] = {};
  EXPECT_THROW(WritePng(path, 1, 1, 5, 8, pixel), UsageError);
  EXPECT_THROW(WritePng(path, 1, 1, 3, 12, pixel), UsageError);
  EXPECT_THROW(WritePng(path, 0, 1, 3, 8, pixel), UsageError);
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

}  // namespace
}  // namespace fetchscope
