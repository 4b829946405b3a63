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

/// The row of `format`: the row itself, or for a name (a manifest's, read back) the table's row
/// of that name, nullptr for a name that is not a format.
inline const VideoFormat* VideoFormatRow(const VideoFormat* format) { return format; }
inline const VideoFormat* VideoFormatRow(const std::string& name) { return FindVideoFormat(name); }

/// True when `formats` (rows, or names read back from a manifest) hold a format of which `has`
/// is true.
template <typename Format, typename Predicate>
bool AnyVideoFormat(const std::vector<Format>& formats, Predicate has) {
  for (const Format& format : formats) {
    const VideoFormat* row = VideoFormatRow(format);
    if (row != nullptr && has(*row)) return true;
  }
  return false;
}

/// True when `formats` encode H.264 (so the node probe decides an encoder for them).
template <typename Format>
bool EncodesH264(const std::vector<Format>& formats) {
  return AnyVideoFormat(formats, [](const VideoFormat& f) { return f.codec.empty(); });
}

/// True when `formats` include a palette (GIF) format.
template <typename Format>
bool HasPaletteFormat(const std::vector<Format>& formats) {
  return AnyVideoFormat(formats, [](const VideoFormat& f) { return f.palette; });
}

/// The table's names in its order, for messages: "mp4, webm, gif".
std::string VideoFormatList();

/// The names of `formats`, in order (the manifest's "formats").
std::vector<std::string> VideoFormatNames(const std::vector<const VideoFormat*>& formats);

}  // namespace fetchscope
