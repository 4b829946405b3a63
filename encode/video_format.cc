#include "encode/video_format.h"

namespace fetchscope {

const std::vector<VideoFormat>& VideoFormats() {
  // name, extension, muxer, codec, bitexact_muxer, faststart, palette, browser_rank
  static const std::vector<VideoFormat> kTable = {
      {"mp4", "mp4", "mp4", "", false, true, false, 0},
      {"webm", "webm", "webm", "libvpx-vp9", true, false, false, 1},
      {"gif", "gif", "gif", "gif", false, false, true, 2},
  };
  return kTable;
}

const VideoFormat* FindVideoFormat(std::string_view name) {
  for (const VideoFormat& format : VideoFormats()) {
    if (format.name == name) return &format;
  }
  return nullptr;
}

std::string VideoFormatList() {
  std::string list;
  for (const VideoFormat& format : VideoFormats()) {
    list += (list.empty() ? "" : ", ") + std::string(format.name);
  }
  return list;
}

std::vector<std::string> VideoFormatNames(const std::vector<const VideoFormat*>& formats) {
  std::vector<std::string> names;
  for (const VideoFormat* format : formats) names.emplace_back(format->name);
  return names;
}

}  // namespace fetchscope
