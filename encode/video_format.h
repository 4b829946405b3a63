// The video formats record writes, one row each. A row says everything the layers need of a
// format: its container and encoder, the pixels the encoder takes (and so the conversion, the
// even-size rule and the colour tags), whether pages show it as an image, and how its file
// carries the run's tags. Adding a format whose encoder, pixel format and tag writer exist is
// adding one row (docs/architecture.md); a new encoder is one case of EncoderOf, a new pixel
// format or tag writer one case of the switches in encode/video_writer.cc, which the compiler
// makes exhaustive.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace fetchscope {

/// The frames an encoder takes. VideoWriter converts the rendered RGB24 frames to them.
enum class VideoPixels {
  kYuv420p,  ///< 4:2:0 luma/chroma (swscale, BT.709 coefficients, limited range)
  kPal8,     ///< one palette per clip (libavfilter palettegen/paletteuse at --gif-fps/--gif-width)
  kRgb24,    ///< the rendered pixels as they are
};

/// How a format's file carries VideoOptions::metadata.
enum class VideoTags {
  kContainer,   ///< the muxer's own tags (Matroska/WebM; MP4 with use_metadata_tags)
  kGifComment,  ///< one GIF89a comment extension, "key=value; key=value" (the muxer writes none)
  kPngText,     ///< one PNG tEXt chunk per tag (the APNG muxer writes none)
};

/// One --format: what every layer needs to know of it. The table fills rows by field name.
struct VideoFormat {
  std::string_view name = {};       ///< the --format name, the manifest's
  std::string_view summary = {};    ///< what --help says of it: "H.264"
  std::string_view extension = {};  ///< the file extension, without the dot
  std::string_view muxer = {};  ///< libavformat's muxer, named (never guessed from the file name)
  /// The muxer's options, "key=value" pairs joined by ':' ("" for none).
  std::string_view muxer_options = {};
  /// The encoder: kH264 for --codec's choice (libx264 or h264_nvenc), else libavcodec's name.
  /// Every name must have its options in EncoderOf (encode/video_writer.cc).
  std::string_view codec = {};
  VideoPixels pixels = VideoPixels::kYuv420p;
  /// The encoder needs even sizes: an odd frame gets its last column/row repeated (yuv420p).
  bool even_size = false;
  /// BT.709 primaries, transfer and matrix with limited range tagged on the stream (the
  /// conversion's own); false: no colour tags (sRGB pixels as rendered, or a palette).
  bool bt709_tags = false;
  bool bitexact_muxer = false;  ///< AVFMT_FLAG_BITEXACT (Matroska's random UID and version)
  /// Pages show the file as an image (<img>, not seekable), never as a <video>.
  bool image = false;
  VideoTags tags = VideoTags::kContainer;
  int browser_rank = 0;  ///< the report's order of preference among a run's formats (0 first)
};

/// VideoFormat::codec of the formats that follow --codec (libx264 or h264_nvenc).
inline constexpr std::string_view kH264 = "h264";

/// The table, in the order --help names the formats (mp4, webm, gif, apng).
const std::vector<VideoFormat>& VideoFormats();

/// The row named `name`, or nullptr for a name that is not a format.
const VideoFormat* FindVideoFormat(std::string_view name);

/// The row whose files end in ".`extension`" (no dot), or nullptr.
const VideoFormat* VideoFormatOfExtension(std::string_view extension);

/// True when `file_name` ends in the extension of one of the table's rows.
bool IsVideoFileName(std::string_view file_name);

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
  return AnyVideoFormat(formats, [](const VideoFormat& f) { return f.codec == kH264; });
}

/// True when `formats` include a palette (GIF) format, which --gif-fps/--gif-width shape.
template <typename Format>
bool HasPaletteFormat(const std::vector<Format>& formats) {
  return AnyVideoFormat(formats,
                        [](const VideoFormat& f) { return f.pixels == VideoPixels::kPal8; });
}

/// The table's names in its order, for messages: "mp4, webm, gif, apng".
std::string VideoFormatList();

/// --format's help: "mp4 (H.264), webm (VP9, ...), ..." from each row's name and summary.
std::string VideoFormatHelp();

/// The other extensions after the first row's, for record's description: ".webm, .gif, .apng".
std::string OtherVideoExtensions();

/// The names of `formats`, in order (the manifest's "formats").
std::vector<std::string> VideoFormatNames(const std::vector<const VideoFormat*>& formats);

}  // namespace fetchscope
