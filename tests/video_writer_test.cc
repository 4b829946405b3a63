// VideoWriter: real libx264, libvpx-vp9 and GIF encodes, checked with ffprobe and decoded back
// with libavformat/libavcodec; container tags read back by ffprobe; VP9's speed settings and the
// frames a GIF keeps.
#include "encode/video_writer.h"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "base/errors.h"
#include "base/number_format.h"
#include "base/text_table.h"
#include "encode/av_handles.h"
#include "encode/contact_sheet.h"
#include "encode/png_io.h"
#include "encode/video_options.h"
#include "encode/video_reader.h"
#include "inspect/image_diff.h"
#include "render/gl_context.h"
#include "render/overlay.h"
#include "render/renderer.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/fetch_env.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using testing::FfprobeFormatTags;
using testing::FfprobeJson;
using testing::RunCommand;
using testing::TempDir;

// Frame k shows k in binary as 6 horizontal bands (bit 0 on top): orange
// for 1, blue for 0. 6 bits cover the 51 frames; the two colours are far
// apart, so codec error cannot flip a bit, and no two frames look alike.
constexpr int kBits = 6;
constexpr uint8_t kOn[3] = {230, 150, 40};
constexpr uint8_t kOff[3] = {30, 60, 120};

int BandHeight(int height) { return height / kBits; }
int BandOf(int y, int height) { return std::min(y / BandHeight(height), kBits - 1); }

std::vector<uint8_t> BandFrame(int k, int width, int height) {
  std::vector<uint8_t> rgb(static_cast<size_t>(width) * height * 3);
  for (int y = 0; y < height; ++y) {
    const uint8_t* color = ((k >> BandOf(y, height)) & 1) ? kOn : kOff;
    for (int x = 0; x < width; ++x) std::copy(color, color + 3, &rgb[(y * width + x) * 3]);
  }
  return rgb;
}

void EncodeBands(const fs::path& path, int width, int height, int frames) {
  VideoOptions options;
  options.width = width;
  options.height = height;
  options.codec = "libx264";
  VideoWriter writer(path.string(), options);
  for (int k = 0; k < frames; ++k) writer.AddFrame(BandFrame(k, width, height).data());
  EXPECT_EQ(writer.frames_written(), frames);
  writer.Finish();
}

// Every frame of `path`'s video stream, as RGB24 in presentation order.
struct DecodedVideo {
  int width = 0, height = 0;
  std::vector<std::vector<uint8_t>> frames;
  std::vector<int64_t> pts;  // in the stream's time base
  AVRational time_base{0, 1};
  bool tagged_bt709 = true;  // every frame carried BT.709 limited-range tags
};

DecodedVideo Decode(const fs::path& path) {
  DecodedVideo video;
  AVFormatContext* raw = nullptr;
  if (avformat_open_input(&raw, path.c_str(), nullptr, nullptr) < 0) {
    ADD_FAILURE() << "cannot open " << path;
    return video;
  }
  InputFormatContextPtr input(raw);
  EXPECT_GE(avformat_find_stream_info(input.get(), nullptr), 0);
  const int index = av_find_best_stream(input.get(), AVMEDIA_TYPE_VIDEO, -1, -1, nullptr, 0);
  EXPECT_GE(index, 0);
  if (index < 0) return video;
  const AVStream* stream = input->streams[index];
  video.time_base = stream->time_base;
  const AVCodec* codec = avcodec_find_decoder(stream->codecpar->codec_id);
  CodecContextPtr decoder(avcodec_alloc_context3(codec));
  avcodec_parameters_to_context(decoder.get(), stream->codecpar);
  EXPECT_GE(avcodec_open2(decoder.get(), codec, nullptr), 0);
  video.width = decoder->width;
  video.height = decoder->height;

  PacketPtr packet(av_packet_alloc());
  FramePtr frame(av_frame_alloc());
  SwsContextPtr to_rgb;
  auto drain = [&] {
    while (avcodec_receive_frame(decoder.get(), frame.get()) >= 0) {
      video.tagged_bt709 = video.tagged_bt709 && frame->colorspace == AVCOL_SPC_BT709 &&
                           frame->color_range == AVCOL_RANGE_MPEG;
      if (!to_rgb) {
        to_rgb.reset(sws_getContext(
            frame->width, frame->height, static_cast<AVPixelFormat>(frame->format), frame->width,
            frame->height, AV_PIX_FMT_RGB24, SWS_BILINEAR | SWS_ACCURATE_RND | SWS_FULL_CHR_H_INT,
            nullptr, nullptr, nullptr));
        // Decode with the matrix the file says it uses.
        const int* table = sws_getCoefficients(frame->colorspace);
        sws_setColorspaceDetails(to_rgb.get(), table, frame->color_range == AVCOL_RANGE_JPEG, table,
                                 1, 0, 1 << 16, 1 << 16);
      }
      std::vector<uint8_t> rgb(static_cast<size_t>(frame->width) * frame->height * 3);
      uint8_t* planes[1] = {rgb.data()};
      const int strides[1] = {frame->width * 3};
      sws_scale(to_rgb.get(), frame->data, frame->linesize, 0, frame->height, planes, strides);
      video.frames.push_back(std::move(rgb));
      video.pts.push_back(frame->best_effort_timestamp);
      av_frame_unref(frame.get());
    }
  };
  while (av_read_frame(input.get(), packet.get()) >= 0) {
    if (packet->stream_index == index) {
      avcodec_send_packet(decoder.get(), packet.get());
      drain();
    }
    av_packet_unref(packet.get());
  }
  avcodec_send_packet(decoder.get(), nullptr);
  drain();
  return video;
}

// Mean colour of row y, columns [x0, x1).
std::vector<double> RowMean(const std::vector<uint8_t>& rgb, int width, int y, int x0, int x1) {
  std::vector<double> mean(3, 0.0);
  for (int x = x0; x < x1; ++x) {
    for (int c = 0; c < 3; ++c) mean[c] += rgb[(y * width + x) * 3 + c];
  }
  for (double& m : mean) m /= (x1 - x0);
  return mean;
}

// Checks every frame shows its own index: the bands' centre rows are within
// codec tolerance of the colour written.
void ExpectFramesInOrder(const DecodedVideo& video, int width, int height, int frames) {
  ASSERT_EQ(static_cast<int>(video.frames.size()), frames);
  constexpr double kTolerance = 20;  // the two colours differ by 110+ per channel
  for (int k = 0; k < frames; ++k) {
    for (int bit = 0; bit < kBits; ++bit) {
      const int y = bit * BandHeight(height) + BandHeight(height) / 2;
      const std::vector<double> mean = RowMean(video.frames[k], video.width, y, 4, width - 4);
      const uint8_t* expected = ((k >> bit) & 1) ? kOn : kOff;
      for (int c = 0; c < 3; ++c) {
        ASSERT_NEAR(mean[c], expected[c], kTolerance)
            << "frame " << k << " band " << bit << " channel " << c;
      }
    }
  }
}

// What the tests read back with ffprobe.
const char kProbeEntries[] =
    "stream=codec_name,pix_fmt,width,height,nb_read_frames,r_frame_rate,avg_frame_rate:"
    "format=duration";

// Top-level MP4 box types in file order.
std::vector<std::string> TopLevelBoxes(const fs::path& path) {
  const std::string data = testing::ReadFile(path);
  std::vector<std::string> boxes;
  size_t offset = 0;
  while (offset + 8 <= data.size()) {
    uint64_t size = 0;
    for (int i = 0; i < 4; ++i) size = (size << 8) | static_cast<uint8_t>(data[offset + i]);
    boxes.push_back(data.substr(offset + 4, 4));
    if (size == 1 && offset + 16 <= data.size()) {  // 64-bit size follows the type
      size = 0;
      for (int i = 8; i < 16; ++i) size = (size << 8) | static_cast<uint8_t>(data[offset + i]);
    } else if (size == 0) {  // box runs to the end of the file
      size = data.size() - offset;
    }
    if (size < 8) break;
    offset += size;
  }
  return boxes;
}

std::vector<std::string> FolderEntries(const fs::path& folder) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder)) {
    names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

TEST(VideoWriterTest, EncodesEveryFrameInOrderAt25Fps) {
  TempDir dir;
  const fs::path path = dir.path() / "bands.mp4";
  EncodeBands(path, 64, 48, 51);
  EXPECT_EQ(FolderEntries(dir.path()), std::vector<std::string>{"bands.mp4"});

  const nlohmann::json probe = FfprobeJson(path, kProbeEntries);
  ASSERT_FALSE(probe.is_discarded());
  ASSERT_EQ(probe["streams"].size(), 1u);
  const nlohmann::json& stream = probe["streams"][0];
  EXPECT_EQ(stream["codec_name"], "h264");
  EXPECT_EQ(stream["pix_fmt"], "yuv420p");
  EXPECT_EQ(stream["width"], 64);
  EXPECT_EQ(stream["height"], 48);
  EXPECT_EQ(stream["nb_read_frames"], "51");
  EXPECT_EQ(stream["r_frame_rate"], "25/1");
  EXPECT_EQ(stream["avg_frame_rate"], "25/1");
  EXPECT_NEAR(std::stod(probe["format"]["duration"].get<std::string>()), 51 / 25.0, 1e-3);

  const DecodedVideo video = Decode(path);
  EXPECT_TRUE(video.tagged_bt709);
  ExpectFramesInOrder(video, 64, 48, 51);
  // frame i is shown at i / 25 s
  for (size_t i = 0; i < video.pts.size(); ++i) {
    EXPECT_NEAR(video.pts[i] * av_q2d(video.time_base), i / 25.0, 1e-6) << "frame " << i;
  }
}

TEST(VideoWriterTest, OddSizeIsPaddedByRepeatingTheLastRowAndColumn) {
  TempDir dir;
  const fs::path path = dir.path() / "odd.mp4";
  {
    VideoOptions options;
    options.width = 65;
    options.height = 49;
    VideoWriter writer(path.string(), options);
    EXPECT_EQ(writer.encoded_width(), 66);
    EXPECT_EQ(writer.encoded_height(), 50);
  }
  EncodeBands(path, 65, 49, 51);

  const nlohmann::json probe = FfprobeJson(path, kProbeEntries);
  ASSERT_FALSE(probe.is_discarded());
  EXPECT_EQ(probe["streams"][0]["width"], 66);
  EXPECT_EQ(probe["streams"][0]["height"], 50);
  EXPECT_EQ(probe["streams"][0]["nb_read_frames"], "51");

  const DecodedVideo video = Decode(path);
  ExpectFramesInOrder(video, 65, 49, 51);
  // The padding column 65 and row 49 repeat their neighbours: the last band's
  // colour reaches the bottom row, and the right edge matches column 64.
  for (int k : {0, 33, 50}) {
    const std::vector<uint8_t>& rgb = video.frames[k];
    const uint8_t* expected = ((k >> (kBits - 1)) & 1) ? kOn : kOff;
    const std::vector<double> bottom = RowMean(rgb, 66, 49, 4, 62);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(bottom[c], expected[c], 20) << "frame " << k;
    for (int y : {4, 20, 36}) {
      for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(rgb[(y * 66 + 65) * 3 + c], rgb[(y * 66 + 64) * 3 + c], 12)
            << "frame " << k << " row " << y;
      }
    }
  }
}

TEST(VideoWriterTest, MoovPrecedesMdat) {
  TempDir dir;
  const fs::path path = dir.path() / "faststart.mp4";
  EncodeBands(path, 64, 48, 10);
  const std::vector<std::string> boxes = TopLevelBoxes(path);
  const auto moov = std::find(boxes.begin(), boxes.end(), "moov");
  const auto mdat = std::find(boxes.begin(), boxes.end(), "mdat");
  ASSERT_NE(moov, boxes.end());
  ASSERT_NE(mdat, boxes.end());
  EXPECT_LT(moov - boxes.begin(), mdat - boxes.begin());
  EXPECT_EQ(boxes.front(), "ftyp");
}

TEST(VideoWriterTest, UnfinishedWriterLeavesNothingBehind) {
  TempDir dir;
  const fs::path path = dir.path() / "episode_000.mp4";
  {
    VideoOptions options;
    options.width = 64;
    options.height = 48;
    VideoWriter writer(path.string(), options);
    for (int k = 0; k < 5; ++k) writer.AddFrame(BandFrame(k, 64, 48).data());
    // While writing, only the hidden temporary exists.
    EXPECT_FALSE(fs::exists(path));
    // the temporary name holds the writer's PID: two processes never share one
    EXPECT_EQ(
        FolderEntries(dir.path()),
        std::vector<std::string>{".episode_000.partial-" + std::to_string(getpid()) + ".mp4"});
  }
  EXPECT_TRUE(FolderEntries(dir.path()).empty());
}

TEST(VideoWriterTest, FinishWithoutFramesThrowsAndLeavesNothing) {
  TempDir dir;
  const fs::path path = dir.path() / "empty.mp4";
  {
    VideoWriter writer(path.string(), VideoOptions{});
    EXPECT_THROW(writer.Finish(), RunError);
  }
  EXPECT_TRUE(FolderEntries(dir.path()).empty());
}

TEST(VideoWriterTest, FinishIsIdempotentAndClosesTheWriter) {
  TempDir dir;
  const fs::path path = dir.path() / "once.mp4";
  VideoOptions options;
  options.width = 32;
  options.height = 32;
  VideoWriter writer(path.string(), options);
  writer.AddFrame(BandFrame(1, 32, 32).data());
  writer.Finish();
  writer.Finish();
  EXPECT_THROW(writer.AddFrame(BandFrame(2, 32, 32).data()), RunError);
  EXPECT_EQ(FolderEntries(dir.path()), std::vector<std::string>{"once.mp4"});
}

TEST(VideoWriterTest, MovedWriterKeepsWriting) {
  TempDir dir;
  const fs::path path = dir.path() / "moved.mp4";
  VideoOptions options;
  options.width = 32;
  options.height = 32;
  VideoWriter first(path.string(), options);
  first.AddFrame(BandFrame(1, 32, 32).data());
  VideoWriter second(std::move(first));
  second.AddFrame(BandFrame(2, 32, 32).data());
  EXPECT_EQ(second.frames_written(), 2);
  second.Finish();
  EXPECT_EQ(FolderEntries(dir.path()), std::vector<std::string>{"moved.mp4"});
}

TEST(VideoWriterTest, AutoCodecOpensAndSaysWhichEncoder) {
  TempDir dir;
  VideoWriter writer((dir.path() / "auto.mp4").string(), VideoOptions{});
  // NVENC where a GPU and driver exist, else libx264; never an error.
  EXPECT_TRUE(writer.codec_name() == "libx264" || writer.codec_name() == "h264_nvenc")
      << writer.codec_name();
}

TEST(VideoWriterTest, ExplicitNvencWithoutGpuSaysToUseLibx264) {
  TempDir dir;
  VideoOptions options;
  options.codec = "h264_nvenc";
  try {
    VideoWriter writer((dir.path() / "nvenc.mp4").string(), options);
    GTEST_SKIP() << "h264_nvenc opened: this machine has NVENC";
  } catch (const RunError& e) {
    EXPECT_NE(std::string(e.what()).find("NVENC is unavailable"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--codec libx264"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(FolderEntries(dir.path()).empty());
}

struct BadOptionCase {
  std::string name;
  VideoOptions options;
  std::string expected;  // must appear in the message
};

class VideoWriterBadOptionsTest : public ::testing::TestWithParam<BadOptionCase> {};

TEST_P(VideoWriterBadOptionsTest, ThrowsUsageErrorNamingTheValue) {
  TempDir dir;
  try {
    VideoWriter writer((dir.path() / "bad.mp4").string(), GetParam().options);
    FAIL() << "no exception";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find(GetParam().expected), std::string::npos) << e.what();
  }
  EXPECT_TRUE(FolderEntries(dir.path()).empty());
}

VideoOptions With(void (*edit)(VideoOptions*)) {
  VideoOptions options;
  edit(&options);
  return options;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, VideoWriterBadOptionsTest,
    ::testing::Values(
        BadOptionCase{"UnknownCodec", With([](VideoOptions* o) { o->codec = "vp9"; }),
                      "unknown video codec 'vp9': accepted auto, libx264, h264_nvenc"},
        BadOptionCase{"CrfTooHigh", With([](VideoOptions* o) { o->crf = 99; }),
                      "video crf 99 is out of range: accepted 0..51"},
        BadOptionCase{"CrfNegative", With([](VideoOptions* o) { o->crf = -1; }),
                      "video crf -1 is out of range"},
        BadOptionCase{"ZeroFps", With([](VideoOptions* o) { o->fps = 0; }),
                      "video fps 0 is out of range: accepted 1..1000"},
        BadOptionCase{"BadPreset", With([](VideoOptions* o) { o->preset = "quick"; }),
                      "unknown video preset 'quick': accepted ultrafast, superfast, veryfast"},
        BadOptionCase{"ZeroWidth", With([](VideoOptions* o) { o->width = 0; }),
                      "video size 0x480 is out of range"},
        BadOptionCase{"HugeHeight", With([](VideoOptions* o) { o->height = 100000; }),
                      "video size 480x100000 is out of range: width and height must be 1..8192"},
        BadOptionCase{"NoFormat", With([](VideoOptions* o) { o->format = nullptr; }),
                      "no video format: accepted mp4, webm, gif, apng"},
        BadOptionCase{"GifFpsZero", With([](VideoOptions* o) { o->gif_fps = 0; }),
                      "GIF fps 0 is out of range: accepted 1..50"},
        BadOptionCase{"GifFpsTooHigh", With([](VideoOptions* o) { o->gif_fps = 60; }),
                      "GIF fps 60 is out of range: accepted 1..50"},
        BadOptionCase{"GifTooNarrow", With([](VideoOptions* o) { o->gif_width = 8; }),
                      "GIF width 8 is out of range: accepted 16..4096 pixels"},
        BadOptionCase{"GifTooWide", With([](VideoOptions* o) { o->gif_width = 5000; }),
                      "GIF width 5000 is out of range"},
        BadOptionCase{"MetadataKeyWithEquals", With([](VideoOptions* o) {
                        o->metadata = {{"a=b", "c"}};
                      }),
                      "video metadata key 'a=b' is not usable"}),
    [](const ::testing::TestParamInfo<BadOptionCase>& info) { return info.param.name; });

TEST(VideoWriterTest, MissingFolderIsARunErrorNamingIt) {
  TempDir dir;
  const fs::path folder = dir.path() / "missing";
  try {
    VideoWriter writer((folder / "v.mp4").string(), VideoOptions{});
    FAIL() << "no exception";
  } catch (const RunError& e) {
    EXPECT_NE(std::string(e.what()).find("'" + folder.string() + "' does not exist"),
              std::string::npos)
        << e.what();
  }
}

TEST(VideoWriterTest, FileInPlaceOfFolderIsARunError) {
  TempDir dir;
  const fs::path file = dir.path() / "plain.txt";
  std::ofstream(file) << "x";
  EXPECT_THROW(VideoWriter((file / "v.mp4").string(), VideoOptions{}), RunError);
}

TEST(VideoWriterTest, UnwritableFolderIsARunErrorNamingIt) {
  if (geteuid() == 0) GTEST_SKIP() << "root writes into read-only folders";
  TempDir dir;
  const fs::path folder = dir.path() / "readonly";
  fs::create_directory(folder);
  fs::permissions(folder, fs::perms::owner_read | fs::perms::owner_exec);
  try {
    VideoWriter writer((folder / "v.mp4").string(), VideoOptions{});
    FAIL() << "no exception";
  } catch (const RunError& e) {
    EXPECT_NE(std::string(e.what()).find("'" + folder.string() + "'"), std::string::npos)
        << e.what();
  }
  fs::permissions(folder, fs::perms::owner_all);
}

const std::vector<std::pair<std::string, std::string>> kTags = {
    {"env_id", "FetchPush-v4"},
    {"seed", "7"},
    {"policy", "exec:python3 my policy.py"},
    {"episode", "3"},
    {"fetchscope_version", "0.1.0"}};

void EncodeBandsAs(const fs::path& path, const std::string& format, int width, int height,
                   int frames, int gif_fps = 10, int gif_width = 320) {
  VideoOptions options;
  options.width = width;
  options.height = height;
  options.codec = "libx264";
  options.format = FindVideoFormat(format);
  options.gif_fps = gif_fps;
  options.gif_width = gif_width;
  options.metadata = kTags;
  VideoWriter writer(path.string(), options);
  for (int k = 0; k < frames; ++k) writer.AddFrame(BandFrame(k, width, height).data());
  writer.Finish();
  EXPECT_EQ(writer.frames_written(), frames);
}

TEST(VideoWriterTest, Mp4CarriesTheTags) {
  TempDir dir;
  const fs::path path = dir.path() / "tagged.mp4";
  EncodeBandsAs(path, "mp4", 64, 48, 5);
  const auto tags = FfprobeFormatTags(path);
  for (const auto& [key, value] : kTags)
    EXPECT_EQ(tags.count(key) ? tags.at(key) : "", value) << key;
}

TEST(VideoWriterTest, WebmIsVp9WithEveryFrameInOrderAndTags) {
  TempDir dir;
  const fs::path path = dir.path() / "bands.webm";
  EncodeBandsAs(path, "webm", 64, 48, 51);
  EXPECT_EQ(FolderEntries(dir.path()), std::vector<std::string>{"bands.webm"});
  const nlohmann::json probe = FfprobeJson(path, kProbeEntries);
  ASSERT_FALSE(probe.is_discarded());
  ASSERT_EQ(probe["streams"].size(), 1u);
  const nlohmann::json& stream = probe["streams"][0];
  EXPECT_EQ(stream["codec_name"], "vp9");
  EXPECT_EQ(stream["pix_fmt"], "yuv420p");
  EXPECT_EQ(stream["width"], 64);
  EXPECT_EQ(stream["height"], 48);
  EXPECT_EQ(stream["nb_read_frames"], "51");
  EXPECT_EQ(stream["r_frame_rate"], "25/1");
  EXPECT_NEAR(std::stod(probe["format"]["duration"].get<std::string>()), 51 / 25.0, 0.05);
  ExpectFramesInOrder(Decode(path), 64, 48, 51);
  const auto tags = FfprobeFormatTags(path);
  for (const auto& [key, value] : kTags)
    EXPECT_EQ(tags.count(key) ? tags.at(key) : "", value) << key;
  const std::string data = testing::ReadFile(path);
  EXPECT_EQ(data.substr(0, 4), "\x1a\x45\xdf\xa3");  // EBML magic
}

TEST(VideoWriterTest, WebmAndGifBytesRepeat) {
  TempDir dir;
  for (const std::string format : {"webm", "gif"}) {
    const fs::path a = dir.path() / ("a." + format), b = dir.path() / ("b." + format);
    EncodeBandsAs(a, format, 96, 64, 20);
    EncodeBandsAs(b, format, 96, 64, 20);
    EXPECT_EQ(testing::ReadFile(a), testing::ReadFile(b)) << format;
  }
}

TEST(VideoWriterTest, GifIsScaledThinnedAndPalettedWithTheTagsAsAComment) {
  TempDir dir;
  const fs::path path = dir.path() / "bands.gif";
  // 51 frames at 25 fps, 10 fps wanted: frames 0, 3, 5, 8, 10, ... 48, 50 (ticks 0.0 .. 2.0 s)
  EncodeBandsAs(path, "gif", 120, 90, 51, /*gif_fps=*/10, /*gif_width=*/60);
  EXPECT_EQ(GifFrameCount(51, 25, 10), 21);
  EXPECT_EQ(FolderEntries(dir.path()), std::vector<std::string>{"bands.gif"});
  const nlohmann::json probe = FfprobeJson(path, kProbeEntries);
  ASSERT_FALSE(probe.is_discarded());
  ASSERT_EQ(probe["streams"].size(), 1u);
  const nlohmann::json& stream = probe["streams"][0];
  EXPECT_EQ(stream["codec_name"], "gif");
  EXPECT_EQ(stream["width"], 60);
  EXPECT_EQ(stream["height"], 45);
  EXPECT_EQ(stream["nb_read_frames"], "21");
  EXPECT_NEAR(std::stod(probe["format"]["duration"].get<std::string>()), 51 / 25.0, 0.1);

  // each GIF frame shows the input frame picked for its tick (two colours: the palette is exact)
  const DecodedVideo video = Decode(path);
  ASSERT_EQ(video.frames.size(), 21u);
  for (int j = 0; j < 21; ++j) {
    const int k = (j * 25 + 9) / 10;  // first input frame at or after j / 10 s
    for (int bit = 0; bit < kBits; ++bit) {
      // the centre row of the band in the 90-row source, scaled to 45 rows
      const int y = (bit * BandHeight(90) + BandHeight(90) / 2) / 2;
      const std::vector<double> mean = RowMean(video.frames[j], 60, y, 2, 58);
      const uint8_t* expected = ((k >> bit) & 1) ? kOn : kOff;
      for (int c = 0; c < 3; ++c) {
        ASSERT_NEAR(mean[c], expected[c], 12) << "gif frame " << j << " band " << bit;
      }
    }
  }
  const auto tags = FfprobeFormatTags(path);
  ASSERT_TRUE(tags.count("comment"));
  EXPECT_EQ(tags.at("comment"),
            "env_id=FetchPush-v4; seed=7; policy=exec:python3 my policy.py; episode=3; "
            "fetchscope_version=0.1.0");
}

TEST(VideoWriterTest, GifKeepsEveryFrameAtOrAboveTheSourceRateAndNeverUpscales) {
  TempDir dir;
  const fs::path path = dir.path() / "all.gif";
  EncodeBandsAs(path, "gif", 40, 30, 12, /*gif_fps=*/50, /*gif_width=*/320);
  EXPECT_EQ(GifFrameCount(12, 25, 50), 12);
  const nlohmann::json probe = FfprobeJson(path, kProbeEntries);
  ASSERT_FALSE(probe.is_discarded());
  EXPECT_EQ(probe["streams"][0]["nb_read_frames"], "12");
  EXPECT_EQ(probe["streams"][0]["width"], 40);
  EXPECT_EQ(probe["streams"][0]["height"], 30);
}

TEST(VideoWriterTest, UnfinishedWebmAndGifLeaveNothingBehind) {
  TempDir dir;
  for (const std::string format : {"webm", "gif"}) {
    VideoOptions options;
    options.width = 32;
    options.height = 32;
    options.format = FindVideoFormat(format);
    {
      VideoWriter writer((dir.path() / ("x." + format)).string(), options);
      writer.AddFrame(BandFrame(1, 32, 32).data());
      EXPECT_EQ(FolderEntries(dir.path()),
                std::vector<std::string>{".x.partial-" + std::to_string(getpid()) + "." + format})
          << format;
    }
    EXPECT_TRUE(FolderEntries(dir.path()).empty()) << format;
  }
}

// VP9 ran with deadline good (2x MP4's record time, 4-6x its encode time); realtime at the
// default preset costs about what H.264 does (measured in BENCHMARKS.md, not here: no timed
// tests). What is tested is the setting: the default and the fast presets use realtime, the
// slow ones keep good, and every WebM comes out the same whatever --jobs (cli_record_formats_test).
TEST(RoughEdges, WebmUsesLibvpxRealtimeUpToTheDefaultPreset) {
  EXPECT_STREQ(Vp9SpeedFor("").deadline, "realtime");
  EXPECT_EQ(Vp9SpeedFor("").cpu_used, 6);
  EXPECT_STREQ(Vp9SpeedFor("veryfast").deadline, "realtime");
  EXPECT_EQ(Vp9SpeedFor("ultrafast").cpu_used, 8);
  EXPECT_STREQ(Vp9SpeedFor("faster").deadline, "good");
  EXPECT_EQ(Vp9SpeedFor("medium").cpu_used, 2);
  EXPECT_EQ(Vp9SpeedFor("veryslow").cpu_used, 0);
}

TEST(GifHud, CopiesOnlyTheFramesTheGifKeeps) {
  for (int fps : {10, 25, 30}) {
    for (int gif_fps : {1, 7, 10, 25}) {
      int kept = 0;
      for (int i = 0; i < 51; ++i) kept += GifKeepsFrame(i, fps, std::min(gif_fps, fps));
      EXPECT_EQ(kept, GifFrameCount(51, fps, std::min(gif_fps, fps))) << fps << " " << gif_fps;
    }
  }
}

}  // namespace
}  // namespace fetchscope
