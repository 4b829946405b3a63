// The video format table (encode/video_format.h): one row per format, asked by every layer
// instead of comparing names.
#include "encode/video_format.h"

#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

#include "encode/episode_sink.h"
#include "render/layers.h"

namespace fetchscope {
namespace {

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
  EXPECT_EQ(VideoFormatList(), "mp4, webm, gif");  // what the errors list, in the table's order
}

TEST(VideoFormatTest, FileNamesAndCodecsFollowTheRow) {
  for (const VideoFormat& row : VideoFormats()) {
    EXPECT_EQ(LayerVideoName(7, Layer::kDepth, row),
              "episode_007_depth." + std::string(row.extension));
    const std::string codec = FormatCodec(row, "h264_nvenc");
    EXPECT_EQ(codec, row.codec.empty() ? "h264_nvenc" : std::string(row.codec)) << row.name;
    EpisodeSinkOptions sink;
    EXPECT_EQ(EpisodeVideoOptions(sink, 0, row).format, &row);
  }
}

}  // namespace
}  // namespace fetchscope
