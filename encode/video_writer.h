// Video writer on libavcodec/libavformat/libswscale/libavfilter: RGB frames in, a file that
// browsers and players open out, in one of three formats:
//   mp4  H.264 (libx264 or h264_nvenc), yuv420p, BT.709 tags, moov atom in front
//   webm VP9 (libvpx-vp9), yuv420p, BT.709 tags, single-threaded so the bytes never depend on
//        the machine
//   gif  one palette per clip (libavfilter palettegen + paletteuse), scaled down to
//        gif_width and gif_fps so that files stay small
// Every format carries VideoOptions::metadata as container tags (GIF: one comment,
// "key=value; key=value"). The file appears under its final name only when complete.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "encode/video_format.h"

namespace fetchscope {

/// Encoder settings for VideoWriter.
struct VideoOptions {
  int width = 480;   ///< frame width given to AddFrame, pixels (1..8192)
  int height = 480;  ///< frame height given to AddFrame, pixels (1..8192)
  int fps = 25;      ///< frames per second (1..1000); frame i is shown at i / fps s
  /// auto | libx264 | h264_nvenc; auto: h264_nvenc if it opens, else libx264.
  std::string codec = "auto";
  int crf = 23;  ///< quality 0..51, lower is better: libx264 crf, h264_nvenc cq (vbr)
  /// libx264 preset name (ultrafast superfast veryfast faster fast medium slow
  /// slower veryslow placebo); empty = kDefaultVideoPreset. h264_nvenc gets the
  /// nearest of its p1..p7 (veryfast -> p2, medium -> p4, veryslow -> p7).
  std::string preset = "";
  /// Encoder threads (libx264 `threads`). 1 by default: x264's bitstream depends on its thread
  /// count (and names it in the stream), so a fixed count keeps videos byte-identical whatever
  /// the machine or the number of workers; record runs several single-threaded encoders at
  /// once instead (one per episode). 0 = libx264's own choice (about 1.5 x cores).
  int threads = 1;
  /// Container and codec: a row of VideoFormats() (encode/video_format.h), by default its first
  /// (mp4: H.264 per `codec`); a row with its own encoder (webm's VP9, gif) ignores `codec`.
  const VideoFormat* format = &VideoFormats().front();
  int gif_fps = 10;     ///< GIF frame rate (1..50), at most `fps` (never duplicates frames)
  int gif_width = 320;  ///< GIF width in pixels (16..4096), at most `width`; height keeps aspect
  /// Container tags, in order (e.g. env_id, seed, policy, episode, fetchscope_version): MP4 and
  /// WebM tags that `ffprobe -show_format` lists; GIF: one comment extension holding them all.
  std::vector<std::pair<std::string, std::string>> metadata;
};

/// Frames a GIF made from `frames` frames at `fps` holds at options' gif_fps: every frame when
/// gif_fps >= fps, else libavfilter's fps filter picks the frame nearest each 1/gif_fps tick.
int GifFrameCount(int frames, int fps, int gif_fps);

/// Whether frame `index` (0 = the first) of a clip at `fps` is one of the GifFrameCount frames
/// a GIF at `gif_fps` keeps: every frame when gif_fps >= fps, else frame 0 and the first at or
/// after each later 1/gif_fps tick.
bool GifKeepsFrame(int index, int fps, int gif_fps);

/// The preset used when VideoOptions::preset is empty. "veryfast" encodes
/// several times faster than x264's "medium" at a modest size cost, which
/// suits rendered scenes (flat colours, little noise) and keeps encoding
/// from dominating a record run.
inline constexpr const char* kDefaultVideoPreset = "veryfast";

/// The x264 options libx264 gets on top of `preset`: for veryfast (the default) a cheaper motion
/// search, "me=dia:subme=1", which cuts x264's CPU per 480x480 Fetch frame by about 30% for
/// about 8% more bytes and 0.05 dB less PSNR (BENCHMARKS.md, "CPU per recorded frame"); "" for
/// the other presets (x264's own).
std::string X264ParamsFor(const std::string& preset);

/// Checks codec, crf, fps, preset and size without opening anything (UsageError on a bad one),
/// so a command can reject bad options before it creates any output.
void ValidateVideoOptions(const VideoOptions& options);

/// The encoder a run uses and why, decided once per run (record decides in the parent and
/// hands the result to its workers).
struct VideoCodecDecision {
  std::string codec;   ///< "libx264" or "h264_nvenc"
  std::string reason;  ///< e.g. "auto: h264_nvenc unavailable (No capable devices found)"
};

/// True when this machine has an NVIDIA driver node (/dev/nvidiactl), the precondition for
/// NVENC; without it `--codec auto` needs no probe.
bool NvidiaDevicePresent();

/// Decides options.codec: libx264 as asked; h264_nvenc (or auto) by opening a test encoder of
/// options' size, which loads CUDA into this process (run it in a child process where workers
/// will be forked later). auto falls back to libx264 with the reason. Throws RunError when
/// h264_nvenc was asked for and cannot open, or libx264 is missing.
VideoCodecDecision DecideVideoCodec(const VideoOptions& options);

/// Writes one video file (MP4, WebM or GIF), frame by frame.
///
/// The encoder gets yuv420p, which needs even dimensions: an odd width or
/// height is padded by one pixel that repeats the last column or row, so the
/// encoded size is the frame size rounded up to even (encoded_width/height).
/// Frame i gets pts i in time base 1/fps, so N frames last exactly N / fps s.
/// A GIF is scaled to gif_width (even sizes not needed) and thinned to gif_fps; its palette is
/// made from every frame of the clip, so nothing is written to it before Finish().
/// The data goes to a temporary ".<stem>.partial.<ext>" in the same folder and
/// is renamed to `path` by Finish(); a writer destroyed unfinished removes it.
/// Not thread-safe; separate writers may run on separate threads.
class VideoWriter {
 public:
  /// Opens the encoder and the temporary output file. Throws UsageError for
  /// bad options (naming the value and what is accepted) and RunError when the
  /// folder of `path` is missing or unwritable, or when an explicitly named
  /// encoder cannot open (h264_nvenc without an NVIDIA GPU/driver).
  VideoWriter(const std::string& path, const VideoOptions& options);
  /// Removes the temporary file if Finish() did not complete.
  ~VideoWriter();
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;
  /// Moves leave `other` empty: its destructor does nothing.
  VideoWriter(VideoWriter&& other) noexcept;
  /// Moves; the writer replaced is destroyed first (its partial file removed).
  VideoWriter& operator=(VideoWriter&& other) noexcept;

  /// Encodes one RGB24 frame: options.width * options.height * 3 bytes,
  /// rows top to bottom, no padding between rows. Throws RunError if encoding
  /// or writing fails, or if the writer is finished.
  void AddFrame(const uint8_t* rgb);

  /// Flushes the encoder, writes the trailer (moov moved to the front:
  /// faststart) and renames the file into place. Throws RunError on failure,
  /// including a video with no frames (then the destructor still removes the
  /// temporary file). Calling it again after success does nothing.
  void Finish();

  /// Frames passed to AddFrame so far.
  int frames_written() const;
  /// Frames in the file (after Finish(); for a GIF fewer than frames_written() when gif_fps is
  /// below fps).
  int frames_encoded() const;
  /// The encoder actually used: "libx264", "h264_nvenc", "libvpx-vp9" or "gif".
  const std::string& codec_name() const;
  /// Width in the file: options.width rounded up to even (GIF: the scaled width).
  int encoded_width() const;
  /// Height in the file: options.height rounded up to even (GIF: the scaled height).
  int encoded_height() const;
  /// The final path given to the constructor.
  const std::string& path() const;
  /// CPU seconds of the threads that called AddFrame and Finish in RGB to YUV conversion
  /// (swscale and its input copy) and in the encoder and muxer (the GIF's filter graph counts as
  /// encoding). A multi-threaded encoder's own threads are not in it (record runs one thread).
  double convert_cpu_s() const;
  double encode_cpu_s() const;  ///< as convert_cpu_s

 private:
  friend VideoCodecDecision DecideVideoCodec(const VideoOptions& options);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace fetchscope
