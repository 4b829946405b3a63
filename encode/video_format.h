// The video formats record writes, one row each: adding a format is adding a row here (and
// its muxer and encoder options where VideoWriter opens them, by the row's flags).
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace fetchscope {

/// One --format: what every layer needs to know of it.
struct VideoFormat {
  std::string_view name;       ///< the --format name, the manifest's
  std::string_view extension;  ///< the file extension, without the dot
  std::string_view muxer;      ///< libavformat's muxer, named (never guessed from the file name)
  std::string_view codec;      ///< the encoder; "" for H.264 (--codec: libx264 or h264_nvenc)
  bool bitexact_muxer;         ///< AVFMT_FLAG_BITEXACT (Matroska's random UID and version)
  bool faststart;              ///< mp4's movflags +faststart+use_metadata_tags
  bool palette;                ///< GIF: palette frames at --gif-fps/--gif-width, its own HUD
  int browser_rank;            ///< the report's order of preference (0 first)
};

/// The table, in the order --help names the formats (mp4, webm, gif).
const std::vector<VideoFormat>& VideoFormats();

/// The row named `name`, or nullptr for a name that is not a format.
const VideoFormat* FindVideoFormat(std::string_view name);

/// True when `formats` (names) holds a format of which `has` is true.
template <typename Predicate>
bool AnyVideoFormat(const std::vector<std::string>& formats, Predicate has) {
  for (const std::string& name : formats) {
    const VideoFormat* format = FindVideoFormat(name);
    if (format != nullptr && has(*format)) return true;
  }
  return false;
}

/// True when `formats` encode H.264 (so the node probe decides an encoder for them).
inline bool EncodesH264(const std::vector<std::string>& formats) {
  return AnyVideoFormat(formats, [](const VideoFormat& f) { return f.codec.empty(); });
}

/// True when `formats` include a palette (GIF) format.
inline bool HasPaletteFormat(const std::vector<std::string>& formats) {
  return AnyVideoFormat(formats, [](const VideoFormat& f) { return f.palette; });
}

}  // namespace fetchscope
