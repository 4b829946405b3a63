// record --format mp4,webm,gif: one file per episode and format, each probed by ffprobe with the
// right frame count and the run's tags, listed in the manifest, and byte-identical whatever
// --jobs; the GIF's HUD sized for the GIF.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "base/number_format.h"
#include "base/text_table.h"
#include "encode/contact_sheet.h"
#include "encode/png_io.h"
#include "encode/video_reader.h"
#include "encode/video_writer.h"
#include "inspect/image_diff.h"
#include "render/overlay.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::EpisodeFiles;
using testing::FfprobeJson;
using testing::ReadFile;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::TempDir;
namespace fs = std::filesystem;
using testing::CommandResult;

// What the tests read back with ffprobe.
const char kProbeEntries[] = "stream=codec_name,width,height,nb_read_frames:format_tags";

class FormatsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    unsetenv("DISPLAY");
    for (const char* name : {"SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"}) unsetenv(name);
  }
};

TEST_F(FormatsTest, EveryFormatPerEpisodeProbedTaggedAndTheSameWithJobs) {
  TempDir tmp;
  const int steps = 10, frames = steps + 1;
  const std::string run =
      "record --quiet --env-id FetchPush-v4 --policy scripted --seed 11 --episodes 3 --steps " +
      std::to_string(steps) + " --width 96 --height 64 --format webm,gif,mp4 --gif-width 48";
  std::map<int, std::map<std::string, std::string>> files;
  for (int jobs : {1, 2}) {
    const fs::path out = tmp.path() / ("j" + std::to_string(jobs));
    const auto r =
        RunFetchscope(run + " --jobs " + std::to_string(jobs) + " --out " + out.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    files[jobs] = EpisodeFiles(out);
  }
  ASSERT_EQ(files[1].size(), 3u * 5);  // 3 videos, sheet and trajectory per episode
  for (const auto& [name, bytes] : files[1]) {
    EXPECT_TRUE(files[2][name] == bytes) << name << " differs between --jobs 1 and --jobs 2";
  }

  const fs::path out = tmp.path() / "j1";
  const nlohmann::json manifest = nlohmann::json::parse(ReadFile(out / "manifest.json"));
  EXPECT_EQ(manifest["video"]["formats"], nlohmann::json({"webm", "gif", "mp4"}));
  EXPECT_EQ(manifest["video"]["codecs"]["webm"], "libvpx-vp9");
  EXPECT_EQ(manifest["video"]["codecs"]["gif"], "gif");
  const std::string h264 = manifest["video"]["codecs"]["mp4"];
  EXPECT_TRUE(h264 == "libx264" || h264 == "h264_nvenc") << h264;
  EXPECT_EQ(manifest["video"]["codec"], "libvpx-vp9, gif, " + h264);
  const int gif_frames = GifFrameCount(frames, 25, 10);
  EXPECT_EQ(gif_frames, 5);  // ticks 0, 0.1, 0.2, 0.3, 0.4 s of a 0.44 s clip
  for (int k = 0; k < 3; ++k) {
    const std::string stem = "episode_00" + std::to_string(k);
    const nlohmann::json& entry = manifest["episodes"][k];
    EXPECT_EQ(entry["video"], stem + ".webm");  // the first format named
    EXPECT_EQ(entry["videos"]["mp4"]["file"], stem + ".mp4");
    EXPECT_EQ(entry["videos"]["webm"]["file"], stem + ".webm");
    EXPECT_EQ(entry["videos"]["gif"]["file"], stem + ".gif");
    EXPECT_EQ(entry["videos"]["mp4"]["frames"], frames);
    EXPECT_EQ(entry["videos"]["webm"]["frames"], frames);
    EXPECT_EQ(entry["videos"]["gif"]["frames"], gif_frames);

    const std::map<std::string, std::pair<std::string, int>> expected = {
        {"mp4", {"h264", frames}}, {"webm", {"vp9", frames}}, {"gif", {"gif", gif_frames}}};
    for (const auto& [ext, codec_frames] : expected) {
      const nlohmann::json probe = FfprobeJson(out / (stem + "." + ext), kProbeEntries);
      ASSERT_FALSE(probe.is_discarded()) << stem << "." << ext;
      const nlohmann::json& stream = probe["streams"][0];
      EXPECT_EQ(stream["codec_name"], codec_frames.first) << ext;
      EXPECT_EQ(stream["nb_read_frames"], std::to_string(codec_frames.second)) << ext;
      EXPECT_EQ(stream["width"], ext == "gif" ? 48 : 96) << ext;
      EXPECT_EQ(stream["height"], ext == "gif" ? 32 : 64) << ext;
      // names lowercased: Matroska (WebM) stores tag names in capitals
      nlohmann::json tags = nlohmann::json::object();
      for (const auto& [key, value] : probe["format"]["tags"].items()) {
        std::string name = key;
        for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        tags[name] = value;
      }
      if (ext == "gif") {
        EXPECT_EQ(tags.value("comment", ""),
                  "title=FetchPush-v4 seed 11 episode " + std::to_string(k) +
                      " (scripted); env_id=FetchPush-v4; seed=11; policy=scripted; episode=" +
                      std::to_string(k) + "; fetchscope_version=" + FETCHSCOPE_VERSION);
      } else {
        EXPECT_EQ(tags.value("env_id", ""), "FetchPush-v4") << ext;
        EXPECT_EQ(tags.value("seed", ""), "11") << ext;
        EXPECT_EQ(tags.value("policy", ""), "scripted") << ext;
        EXPECT_EQ(tags.value("episode", ""), std::to_string(k)) << ext;
        EXPECT_EQ(tags.value("fetchscope_version", ""), FETCHSCOPE_VERSION) << ext;
      }
    }
  }
  for (const auto& e : fs::directory_iterator(out)) {
    EXPECT_NE(e.path().filename().string()[0], '.') << "leftover temporary " << e.path();
  }
}

// A run without mp4 encodes no H.264: the manifest and the summary line name the encoders that
// made its files, format by format.
TEST_F(FormatsTest, ManifestAndSummaryNameTheEncodersActuallyUsed) {
  TempDir tmp;
  const std::map<std::string, std::string> runs = {{"webm", "libvpx-vp9"}, {"gif", "gif"}};
  for (const auto& [format, codec] : runs) {
    SCOPED_TRACE(format);
    const fs::path out = tmp.path() / format;
    const auto r = RunFetchscope(
        "record --no-report --env-id FetchReach-v4 --episodes 1 --steps 3 --width 48 --height 48 "
        "--format " +
        format + " --out " + out.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json video = nlohmann::json::parse(ReadFile(out / "manifest.json"))["video"];
    EXPECT_EQ(video["codec"], codec);
    EXPECT_EQ(video["codecs"], nlohmann::json({{format, codec}}));
    EXPECT_EQ(video["codec_reason"].get<std::string>().find("h264"), std::string::npos)
        << video["codec_reason"];
    EXPECT_NE(r.output.find(", " + codec + " -> " + out.string()), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("libx264"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("nvenc"), std::string::npos) << r.output;
    const nlohmann::json probe = FfprobeJson(out / ("episode_000." + format), kProbeEntries);
    EXPECT_EQ(probe["streams"][0]["codec_name"], format == "webm" ? "vp9" : "gif");
  }
}

// The longest run of near-black pixels in column `x` of an RGB24 image `w` wide.
int BlackRun(const std::vector<uint8_t>& rgb, int w, int h, int x) {
  int best = 0, run = 0;
  for (int y = 0; y < h; ++y) {
    const uint8_t* p = &rgb[(y * w + x) * 3];
    run = std::max({p[0], p[1], p[2]}) < 48 ? run + 1 : 0;
    best = std::max(best, run);
  }
  return best;
}

TEST(GifHud, SizedForTheGifWidthWhileTheMp4KeepsItsOwn) {
  TempDir tmp;
  const fs::path out = tmp.path() / "run";
  // an opaque box (--hud-opacity 1) is easy to find in the decoded frames
  const CommandResult r = RunFetchscope(
      "record --quiet --no-report --env-id FetchReach-v4 --episodes 1 --steps 1 --width 480 "
      "--height 480 --format mp4,gif --hud-opacity 1 --out " +
      out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  FrameInfo info;
  info.title = "FetchReach-v4";
  const HudText hud = FormatHud(info, OverlaySet{});
  const PixelRect tile{0, 0, 480, 480};
  const ShownScale gif_scale{320, 480};
  EXPECT_EQ(HudTextPixels(480, 480, gif_scale), 15);  // 10 px once scaled to 320
  const PixelRect mp4_box = *PlaceHud(hud, tile, HudPosition::kTopLeft);
  const PixelRect gif_box = *PlaceHud(hud, tile, HudPosition::kTopLeft, gif_scale);
  // the same HUD as a 320-pixel frame's, in drawn pixels
  const PixelRect native = *PlaceHud(hud, PixelRect{0, 0, 320, 320}, HudPosition::kTopLeft);
  EXPECT_NEAR(gif_box.height * 2.0 / 3, native.height, 2);

  int w = 0, h = 0;
  const auto gif = ReadAllFrames((out / "episode_000.gif").string(), &w, &h);
  ASSERT_FALSE(gif.empty());
  ASSERT_EQ(w, 320);
  const int gif_x = (gif_box.x + 2) * 2 / 3;  // in the box's left padding: no text
  EXPECT_NEAR(BlackRun(gif[0], w, h, gif_x), gif_box.height * 2.0 / 3, 3)
      << "the GIF's HUD box should be " << native.height << " px high, as a 320-pixel video's";

  const auto mp4 = ReadAllFrames((out / "episode_000.mp4").string(), &w, &h);
  ASSERT_FALSE(mp4.empty());
  ASSERT_EQ(w, 480);
  EXPECT_NEAR(BlackRun(mp4[0], w, h, mp4_box.x + 2), mp4_box.height, 3);
}

TEST(GifHud, LeftOutOfAGifTooNarrowForItAndSaidOnce) {
  TempDir tmp;
  const fs::path out = tmp.path() / "run";
  // two 480-pixel views side by side in a 320-pixel GIF: each shows at 160 x 160
  const CommandResult r = RunFetchscope(
      "record --no-report --env-id FetchReach-v4 --episodes 2 --steps 1 --camera "
      "default,head_camera_rgb --format mp4,gif --hud-opacity 1 --out " +
      out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string note = "the GIF (320 px wide) shows each view at 160x160";
  const size_t at = r.output.find(note);
  ASSERT_NE(at, std::string::npos) << r.output;
  EXPECT_EQ(r.output.find(note, at + 1), std::string::npos) << "said more than once";
  int w = 0, h = 0;
  const auto gif = ReadAllFrames((out / "episode_000.gif").string(), &w, &h);
  ASSERT_EQ(w, 320);
  // the HUD's corner, left of the tile label: the shrunken HUD box made it mostly black
  int dark = 0;
  for (int y = 0; y < 40; ++y) {
    for (int x = 0; x < 40; ++x) {
      const uint8_t* p = &gif[0][(y * w + x) * 3];
      dark += std::max({p[0], p[1], p[2]}) < 48;
    }
  }
  EXPECT_LT(dark, 50) << "the GIF still has a HUD box";
  const auto mp4 = ReadAllFrames((out / "episode_000.mp4").string(), &w, &h);
  ASSERT_EQ(w, 960);
  EXPECT_GT(BlackRun(mp4[0], w, h, 8), 60) << "the MP4 keeps its HUD";
}

}  // namespace
}  // namespace fetchscope
