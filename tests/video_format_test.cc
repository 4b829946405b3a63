// The video format table (encode/video_format.h): one row per format, asked by every layer
// instead of comparing names. The recipe of docs/architecture.md ("a new format is one row") is
// tested here at unit level: every row round-trips through the writer, ffprobe, record's
// manifest and the report page, each expectation derived from the row's own fields; and a
// scratch row built of existing parts writes a file with no other code knowing it.
#include "encode/video_format.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "base/errors.h"
#include "encode/episode_sink.h"
#include "encode/video_writer.h"
#include "render/layers.h"
#include "test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::TempDir;

TEST(VideoFormatTest, EachRowIsFoundByItsNameAndNamesAreUnique) {
  std::set<std::string> names, extensions;
  for (const VideoFormat& row : VideoFormats()) {
    EXPECT_EQ(FindVideoFormat(row.name), &row);
    EXPECT_TRUE(names.insert(std::string(row.name)).second) << row.name;
    EXPECT_TRUE(extensions.insert(std::string(row.extension)).second) << row.extension;
    EXPECT_FALSE(row.muxer.empty()) << row.name;
  }
  EXPECT_EQ(FindVideoFormat("avi"), nullptr);
  EXPECT_EQ(FindVideoFormat("MP4"), nullptr);
  // --format's default (and the report's unmentioned one) is the first row
  EXPECT_EQ(VideoFormats().front().name, "mp4");
}

TEST(VideoFormatTest, FlagsAnswerForRowsAndForNamesReadBack) {
  const VideoFormat* mp4 = FindVideoFormat("mp4");
  const VideoFormat* webm = FindVideoFormat("webm");
  const VideoFormat* gif = FindVideoFormat("gif");
  ASSERT_TRUE(mp4 && webm && gif);
  EXPECT_TRUE(EncodesH264(std::vector<const VideoFormat*>{webm, mp4}));
  EXPECT_FALSE(EncodesH264(std::vector<const VideoFormat*>{webm, gif}));
  EXPECT_TRUE(HasPaletteFormat(std::vector<const VideoFormat*>{mp4, gif}));
  EXPECT_FALSE(HasPaletteFormat(std::vector<const VideoFormat*>{mp4, webm}));
  // a manifest's names: the same answers, an unknown name counts for nothing
  EXPECT_TRUE(HasPaletteFormat(std::vector<std::string>{"mp4", "gif"}));
  EXPECT_FALSE(HasPaletteFormat(std::vector<std::string>{"mp4", "mkv"}));
  EXPECT_FALSE(EncodesH264(std::vector<std::string>{"webm"}));
  EXPECT_EQ(VideoFormatNames({gif, mp4}), (std::vector<std::string>{"gif", "mp4"}));
  EXPECT_EQ(VideoFormatList(), "mp4, webm, gif, apng");  // what the errors list, in its order
  EXPECT_EQ(VideoFormatOfExtension("apng"), FindVideoFormat("apng"));
  EXPECT_TRUE(IsVideoFileName("episode_000.webm"));
  EXPECT_TRUE(IsVideoFileName("episode_000_depth.apng"));
  EXPECT_FALSE(IsVideoFileName("episode_000.png"));  // a contact sheet
  EXPECT_FALSE(IsVideoFileName(".mp4"));
  EXPECT_FALSE(IsVideoFileName("mp4"));
}

TEST(VideoFormatTest, FileNamesAndCodecsFollowTheRow) {
  for (const VideoFormat& row : VideoFormats()) {
    EXPECT_EQ(LayerVideoName(7, Layer::kDepth, row),
              "episode_007_depth." + std::string(row.extension));
    const std::string codec = FormatCodec(row, "h264_nvenc");
    EXPECT_EQ(codec, row.codec == kH264 ? "h264_nvenc" : std::string(row.codec)) << row.name;
    EpisodeSinkOptions sink;
    EXPECT_EQ(EpisodeVideoOptions(sink, 0, row).format, &row);
  }
}

const std::vector<std::pair<std::string, std::string>> kTags = {
    {"env_id", "FetchPush-v4"}, {"seed", "7"}, {"policy", "exec:python3 my policy.py"}};

// Frame k: a grey level that steps with k, so frames differ.
std::vector<uint8_t> Frame(int k, int width, int height) {
  return std::vector<uint8_t>(static_cast<std::size_t>(width) * height * 3,
                              static_cast<uint8_t>(40 + 30 * k));
}

// Writes `frames` frames of width x height in `format` with kTags; throws what the writer throws.
void Write(const fs::path& path, const VideoFormat& format, int width, int height, int frames) {
  VideoOptions options;
  options.width = width;
  options.height = height;
  options.codec = "libx264";
  options.format = &format;
  options.gif_fps = 25;  // every frame, so that all rows hold `frames` frames
  options.metadata = kTags;
  VideoWriter writer(path.string(), options);
  for (int k = 0; k < frames; ++k) writer.AddFrame(Frame(k, width, height).data());
  writer.Finish();
}

// The text chunks of a PNG file ("keyword" -> text), each one's CRC checked.
std::map<std::string, std::string> PngTextChunks(const std::string& bytes) {
  std::map<std::string, std::string> text;
  std::size_t at = 8;
  while (at + 12 <= bytes.size()) {
    const auto byte = [&](std::size_t i) { return static_cast<uint32_t>(uint8_t(bytes[i])); };
    const uint32_t length = byte(at) << 24 | byte(at + 1) << 16 | byte(at + 2) << 8 | byte(at + 3);
    const std::string type = bytes.substr(at + 4, 4);
    if (at + 12 + length > bytes.size()) break;
    const uint32_t crc = byte(at + 8 + length) << 24 | byte(at + 9 + length) << 16 |
                         byte(at + 10 + length) << 8 | byte(at + 11 + length);
    const uint32_t expected = static_cast<uint32_t>(
        crc32(0, reinterpret_cast<const Bytef*>(bytes.data() + at + 4), length + 4));
    EXPECT_EQ(crc, expected) << "chunk " << type << " at byte " << at;
    if (type == "tEXt") {
      const std::string data = bytes.substr(at + 8, length);
      const std::size_t nul = data.find('\0');
      text[data.substr(0, nul)] = data.substr(nul + 1);
    }
    at += 12 + length;
  }
  return text;
}

// What the row says the file is, checked in the file (ffprobe, or the PNG chunks).
using Tags = std::vector<std::pair<std::string, std::string>>;

void ExpectFileFollowsTheRow(const fs::path& path, const VideoFormat& row, int width, int height,
                             int frames, const Tags& tags = kTags) {
  SCOPED_TRACE(std::string(row.name));
  const json probe = testing::FfprobeJson(
      path, "stream=codec_name,width,height,pix_fmt,color_space,color_range,nb_read_frames");
  ASSERT_FALSE(probe.is_discarded());
  const json& stream = probe["streams"][0];
  const std::string codec(row.codec == kH264          ? "h264"
                          : row.codec == "libvpx-vp9" ? "vp9"
                                                      : row.codec);
  EXPECT_EQ(stream["codec_name"], codec);
  // the even-size rule: the last column and row repeated, or the frame's own size
  EXPECT_EQ(stream["width"], row.even_size ? (width + 1) / 2 * 2 : width);
  EXPECT_EQ(stream["height"], row.even_size ? (height + 1) / 2 * 2 : height);
  EXPECT_EQ(stream["nb_read_frames"], std::to_string(frames));
  switch (row.pixels) {
    case VideoPixels::kYuv420p:
      EXPECT_EQ(stream["pix_fmt"], "yuv420p");
      break;
    case VideoPixels::kRgb24:
      EXPECT_EQ(stream["pix_fmt"], "rgb24");
      break;
    case VideoPixels::kPal8:  // FFmpeg's GIF decoder hands out its palette frames as BGRA
      EXPECT_EQ(stream["pix_fmt"], "bgra");
      break;
  }
  // the colour tags: BT.709 limited range where the conversion made them, nothing otherwise
  EXPECT_EQ(stream.value("color_space", "unknown"), row.bt709_tags ? "bt709" : "unknown");
  EXPECT_EQ(stream.value("color_range", "unknown") == "tv", row.bt709_tags);
  const std::map<std::string, std::string> container = testing::FfprobeFormatTags(path);
  switch (row.tags) {
    case VideoTags::kContainer:
      for (const auto& [key, value] : tags) {
        EXPECT_EQ(container.count(key) ? container.at(key) : "", value) << key;
      }
      break;
    case VideoTags::kGifComment:  // one comment, "key=value; key=value"
      ASSERT_EQ(container.count("comment"), 1u);
      for (const auto& [key, value] : tags) {
        EXPECT_NE(("; " + container.at("comment") + ";").find("; " + key + "=" + value + ";"),
                  std::string::npos)
            << key;
      }
      break;
    case VideoTags::kPngText: {
      const std::map<std::string, std::string> text = PngTextChunks(testing::ReadFile(path));
      for (const auto& [key, value] : tags) {
        EXPECT_EQ(text.count(key) ? text.at(key) : "", value) << key;
      }
      // and FFmpeg reads them back, as the first frame's tags
      const json frames_probe = testing::FfprobeJson(path, "frame_tags");
      EXPECT_EQ(frames_probe["frames"][0]["tags"].value("env_id", ""), text.at("env_id"));
      break;
    }
  }
}

TEST(VideoFormatRoundTrip, EveryRowWritesTheFileItsFieldsDescribe) {
  TempDir dir;
  for (const VideoFormat& row : VideoFormats()) {
    const fs::path path = dir.path() / ("odd." + std::string(row.extension));
    Write(path, row, 33, 17, 4);
    ExpectFileFollowsTheRow(path, row, 33, 17, 4);
  }
  // nothing but the finished files (no temporaries)
  EXPECT_EQ(testing::FilesIn(dir.path()).size(), VideoFormats().size());
}

TEST(VideoFormatRoundTrip, EveryRowsBytesRepeat) {
  TempDir dir;
  for (const VideoFormat& row : VideoFormats()) {
    const fs::path a = dir.path() / ("a." + std::string(row.extension));
    const fs::path b = dir.path() / ("b." + std::string(row.extension));
    Write(a, row, 40, 30, 3);
    Write(b, row, 40, 30, 3);
    EXPECT_EQ(testing::ReadFile(a), testing::ReadFile(b)) << row.name;
  }
}

// record --format ROW: the manifest names the row and lists its file; the page shows it as the
// row says (an image, or a video) and links it.
TEST(VideoFormatRoundTrip, EveryRowThroughRecordsManifestAndPage) {
  TempDir dir;
  for (const VideoFormat& row : VideoFormats()) {
    SCOPED_TRACE(std::string(row.name));
    const fs::path out = dir.path() / std::string(row.name);
    const auto r = testing::RunFetchscope(
        "record --env-id FetchReach-v4 --episodes 1 --steps 4 --width 48 --height 32 --msaa 0 "
        "--gif-fps 25 --quiet --format " +
        std::string(row.name) + " --out " + out.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const json manifest = json::parse(testing::ReadFile(out / "manifest.json"));
    EXPECT_EQ(manifest["video"]["formats"], json::array({std::string(row.name)}));
    const json& video = manifest["episodes"][0]["videos"][std::string(row.name)];
    ASSERT_TRUE(video.is_object()) << manifest["episodes"][0].dump();
    EXPECT_EQ(video["file"], "episode_000." + std::string(row.extension));
    EXPECT_EQ(video["frames"], 5);
    const json data = testing::PageBlock(testing::ReadFile(out / "index.html"), "fetchscope-data");
    ASSERT_TRUE(data.is_object());
    const json& e = data["episodes"][0];
    EXPECT_EQ(e["video"], video["file"]);
    EXPECT_EQ(e["video_format"], std::string(row.name));
    EXPECT_EQ(e["video_image"], row.image);
    ExpectFileFollowsTheRow(out / video["file"].get<std::string>(), row, 48, 32, 5,
                            {{"env_id", "FetchReach-v4"}, {"policy", "random"}, {"episode", "0"}});
  }
}

// The recipe, as a maintainer follows it: a scratch row made of an existing encoder, pixel
// format and tag writer (Matroska holding VP9) writes its file with no other code knowing it.
TEST(VideoFormatRecipe, AScratchRowOfExistingPartsNeedsNothingElse) {
  const VideoFormat scratch{.name = "mkv",
                            .extension = "mkv",
                            .muxer = "matroska",
                            .codec = "libvpx-vp9",
                            .pixels = VideoPixels::kYuv420p,
                            .even_size = true,
                            .bt709_tags = true,
                            .bitexact_muxer = true,
                            .tags = VideoTags::kContainer,
                            .browser_rank = 4};
  TempDir dir;
  const fs::path path = dir.path() / "scratch.mkv";
  Write(path, scratch, 33, 17, 4);
  ExpectFileFollowsTheRow(path, scratch, 33, 17, 4);
  const json probe = testing::FfprobeJson(path, "format=format_name");
  EXPECT_EQ(probe["format"]["format_name"], "matroska,webm");
}

// A row naming an encoder that has no settings of its own is refused, never given x264's.
TEST(VideoFormatRecipe, AnEncoderWithoutItsOwnSettingsIsRefused) {
  const VideoFormat scratch{.name = "m4v",
                            .extension = "m4v",
                            .muxer = "mp4",
                            .codec = "mpeg4",
                            .pixels = VideoPixels::kYuv420p,
                            .even_size = true,
                            .bt709_tags = true,
                            .tags = VideoTags::kContainer,
                            .browser_rank = 4};
  TempDir dir;
  try {
    Write(dir.path() / "scratch.m4v", scratch, 32, 16, 2);
    FAIL() << "an encoder without settings opened";
  } catch (const RunError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "fetchscope has no settings for the encoder mpeg4 (it knows libx264, "
                  "h264_nvenc, libvpx-vp9, gif, apng)"),
              std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(testing::FilesIn(dir.path()).empty());
}

}  // namespace
}  // namespace fetchscope
