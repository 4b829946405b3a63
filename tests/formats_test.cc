// record --format mp4,webm,gif: one file per episode and format, each probed by ffprobe with the
// right frame count and the run's tags, listed in the manifest, and byte-identical whatever
// --jobs.
#include <gtest/gtest.h>

#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "encode/video_writer.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::EpisodeFiles;
using testing::ReadFile;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::TempDir;
namespace fs = std::filesystem;

nlohmann::json Probe(const fs::path& path) {
  const auto r = RunCommand(
      "ffprobe -v error -count_frames -show_entries "
      "stream=codec_name,width,height,nb_read_frames:format_tags -of json '" +
      path.string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return nlohmann::json::parse(r.output, nullptr, false);
}

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
      const nlohmann::json probe = Probe(out / (stem + "." + ext));
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
    const nlohmann::json probe = Probe(out / ("episode_000." + format));
    EXPECT_EQ(probe["streams"][0]["codec_name"], format == "webm" ? "vp9" : "gif");
  }
}

}  // namespace
}  // namespace fetchscope
