#include "encode/video_format.h"

namespace fetchscope {

const std::vector<VideoFormat>& VideoFormats() {
  static const std::vector<VideoFormat> kTable = {
      {.name = "mp4",
       .summary = "H.264",
       .extension = "mp4",
       .muxer = "mp4",
       // faststart: the index (moov) in front of the data, so that a browser starts playing
       // before the whole file arrives; use_metadata_tags: every tag, not only MP4's few names
       .muxer_options = "movflags=+faststart+use_metadata_tags",
       .codec = kH264,
       .pixels = VideoPixels::kYuv420p,
       .even_size = true,
       .bt709_tags = true,
       .tags = VideoTags::kContainer,
       .browser_rank = 0},
      {.name = "webm",
       .summary = "VP9, plays in every browser and wandb",
       .extension = "webm",
       .muxer = "webm",
       .codec = "libvpx-vp9",
       .pixels = VideoPixels::kYuv420p,
       .even_size = true,
       .bt709_tags = true,
       .bitexact_muxer = true,
       .tags = VideoTags::kContainer,
       .browser_rank = 1},
      {.name = "gif",
       .summary = "one palette per clip, scaled by --gif-fps/--gif-width",
       .extension = "gif",
       .muxer = "gif",
       .codec = "gif",
       .pixels = VideoPixels::kPal8,
       .image = true,
       .tags = VideoTags::kGifComment,
       .browser_rank = 2},
      // lossless frames (the rendered pixels), looping like a GIF, in every browser's <img>
      {.name = "apng",
       .summary = "animated PNG: lossless, every frame, loops like a gif",
       .extension = "apng",
       .muxer = "apng",
       .muxer_options = "plays=0",
       .codec = "apng",
       .pixels = VideoPixels::kRgb24,
       .image = true,
       .tags = VideoTags::kPngText,
       .browser_rank = 3},
  };
  return kTable;
}

const VideoFormat* FindVideoFormat(std::string_view name) {
  for (const VideoFormat& format : VideoFormats()) {
    if (format.name == name) return &format;
  }
  return nullptr;
}

const VideoFormat* VideoFormatOfExtension(std::string_view extension) {
  for (const VideoFormat& format : VideoFormats()) {
    if (format.extension == extension) return &format;
  }
  return nullptr;
}

bool IsVideoFileName(std::string_view file_name) {
  const std::size_t dot = file_name.rfind('.');
  return dot != std::string_view::npos && dot > 0 &&
         VideoFormatOfExtension(file_name.substr(dot + 1)) != nullptr;
}

std::string VideoFormatList() {
  std::string list;
  for (const VideoFormat& format : VideoFormats()) {
    list += (list.empty() ? "" : ", ") + std::string(format.name);
  }
  return list;
}

std::string VideoFormatHelp() {
  std::string help;
  for (const VideoFormat& format : VideoFormats()) {
    help += (help.empty() ? "" : ", ") + std::string(format.name) + " (" +
            std::string(format.summary) + ")";
  }
  return help;
}

std::string OtherVideoExtensions() {
  std::string list;
  for (std::size_t i = 1; i < VideoFormats().size(); ++i) {
    list += (list.empty() ? "." : ", .") + std::string(VideoFormats()[i].extension);
  }
  return list;
}

std::vector<std::string> VideoFormatNames(const std::vector<const VideoFormat*>& formats) {
  std::vector<std::string> names;
  for (const VideoFormat* format : formats) names.emplace_back(format->name);
  return names;
}

}  // namespace fetchscope
