#include "encode/video_writer.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdarg>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>
#include <optional>
#include <sstream>
#include <system_error>
#include <utility>
#include <vector>

#include "base/cpu_clock.h"
#include "base/errors.h"
#include "base/kill_point.h"
#include "base/suggest.h"
#include "encode/av_handles.h"
#include "encode/av_log.h"
#include "encode/gif_palette.h"
#include "encode/video_files.h"
#include "encode/video_format.h"
#include "encode/video_options.h"

extern "C" {
#include <libavfilter/avfilter.h>
#include <libavfilter/buffersink.h>
#include <libavfilter/buffersrc.h>
#include <libavutil/error.h>
#include <libavutil/imgutils.h>
#include <libavutil/log.h>
}

namespace fetchscope {
namespace {

namespace fs = std::filesystem;

// Removes the file it was given (Adopt) on destruction unless Release()d.
class TemporaryFile {
 public:
  TemporaryFile() = default;
  ~TemporaryFile() {
    if (!path_.empty()) {
      std::error_code ignored;
      fs::remove(path_, ignored);
    }
  }
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  void Adopt(fs::path path) { path_ = std::move(path); }
  const fs::path& path() const { return path_; }
  void Release() { path_.clear(); }

 private:
  fs::path path_;
};

// Every encoder fetchscope opens, each with its own options below (TryOpenEncoder): a format
// row naming an encoder that has no case here is refused, never given another's options.
enum class Encoder { kX264, kNvenc, kVp9, kGif, kApng };

struct KnownEncoder {
  std::string_view name;  // libavcodec's
  Encoder encoder;
};
constexpr std::array<KnownEncoder, 5> kEncoders = {{{"libx264", Encoder::kX264},
                                                    {"h264_nvenc", Encoder::kNvenc},
                                                    {"libvpx-vp9", Encoder::kVp9},
                                                    {"gif", Encoder::kGif},
                                                    {"apng", Encoder::kApng}}};

const KnownEncoder* EncoderOf(std::string_view name) {
  for (const KnownEncoder& known : kEncoders) {
    if (known.name == name) return &known;
  }
  return nullptr;
}

std::string KnownEncoderList() {
  std::string list;
  for (const KnownEncoder& known : kEncoders) {
    list += (list.empty() ? "" : ", ") + std::string(known.name);
  }
  return list;
}

// The even size an encoder of 4:2:0 frames needs (the last column/row repeated), else `size`
// (also for no format at all, which ValidateVideoOptions then refuses).
int EncodedSize(int size, const VideoFormat* format) {
  return format != nullptr && format->even_size ? (size + 1) & ~1 : size;
}

}  // namespace

struct VideoWriter::Impl {
  // options.format's row of the format table (ValidateVideoOptions has checked there is one)
  const VideoFormat& Format() const { return *options.format; }
  Impl(const std::string& path, const VideoOptions& options);
  // Options and sizes only, no file: for ProbeEncoder.
  explicit Impl(const VideoOptions& opts)
      : options(opts),
        encoded_width(EncodedSize(opts.width, opts.format)),
        encoded_height(EncodedSize(opts.height, opts.format)) {
    if (options.preset.empty()) options.preset = kDefaultVideoPreset;
  }
  // Opens options.codec for options' size and closes it again; throws RunError with FFmpeg's
  // reason when it cannot open.
  static void ProbeEncoder(const VideoOptions& options);
  void OpenEncoder();
  bool TryOpenEncoder(const std::string& name, std::string* failure);
  void OpenOutput();
  void ConvertFrame(const uint8_t* rgb);
  void SendFrame(const AVFrame* frame);
  void Finish();
  // GIF: the palette filter graph, and frames through it.
  // the palette filter's frames into the encoder
  void DrainGifFilter() {
    gif_filter->Drain([this](const AVFrame* f) { SendFrame(f); });
  }
  bool GifKeeps(int index) const;

  std::string final_path;
  VideoOptions options;
  int encoded_width;
  int encoded_height;
  // Declared before the FFmpeg objects so it is destroyed after them: the file
  // is closed before it is removed.
  TemporaryFile temporary;
  std::string codec_name;
  CodecContextPtr encoder;
  OutputFormatContextPtr muxer;
  AVStream* stream = nullptr;   // owned by muxer
  FramePtr frame;               // one frame (the row's pixels) reused for every AddFrame
  PacketPtr packet;             // one packet reused for every encoded output
  SwsContextPtr converter;      // RGB24 -> yuv420p, BT.709 limited range
  std::vector<uint8_t> padded;  // swscale's input: the frame (odd row/column repeated) + slack
  int frames_written = 0;
  int frames_encoded = 0;
  double convert_cpu_s = 0, encode_cpu_s = 0;  // thread CPU (convert_cpu_s())
  bool finished = false;
  bool gif = false;
  int gif_fps = 0;                             // options.gif_fps, at most options.fps
  std::optional<GifPaletteFilter> gif_filter;  // GIF: frames in at options' size, PAL8 out
};

VideoWriter::Impl::Impl(const std::string& path, const VideoOptions& opts)
    : final_path(path),
      options(opts),
      encoded_width(EncodedSize(opts.width, opts.format)),
      encoded_height(EncodedSize(opts.height, opts.format)) {
  ValidateVideoOptions(options);
  if (options.preset.empty()) options.preset = kDefaultVideoPreset;
  if (path.empty()) {
    throw UsageError("video path is empty: give a file name ending in ." +
                     std::string(options.format->extension));
  }
  CheckOutputFolder(path);
  InstallAvLogCapture();
  gif = Format().pixels == VideoPixels::kPal8;
  if (gif) {
    gif_fps = std::min(options.gif_fps, options.fps);
    encoded_width = std::min(options.gif_width, options.width);
    encoded_height = std::max(
        1,
        static_cast<int>((static_cast<long>(options.height) * encoded_width * 2 + options.width) /
                         (2L * options.width)));
    OpenEncoder();
    OpenOutput();
    gif_filter.emplace(options.width, options.height, options.fps, encoded_width, encoded_height);
    packet.reset(av_packet_alloc());
    if (!packet) throw RunError("out of memory allocating a video packet");
    return;
  }
  OpenEncoder();
  OpenOutput();

  frame.reset(av_frame_alloc());
  packet.reset(av_packet_alloc());
  if (!frame || !packet) throw RunError("out of memory allocating video frame buffers");
  frame->format = encoder->pix_fmt;
  frame->width = encoded_width;
  frame->height = encoded_height;
  if (Format().bt709_tags) {
    frame->color_range = AVCOL_RANGE_MPEG;
    frame->colorspace = AVCOL_SPC_BT709;
  }
  if (int rc = av_frame_get_buffer(frame.get(), 0); rc < 0) {
    throw RunError("cannot allocate a " + std::to_string(encoded_width) + "x" +
                   std::to_string(encoded_height) + " video frame: " + DescribeAvError(rc));
  }
  if (Format().pixels == VideoPixels::kRgb24) return;  // AddFrame copies the rows as they are

  converter.reset(sws_getContext(encoded_width, encoded_height, AV_PIX_FMT_RGB24, encoded_width,
                                 encoded_height, AV_PIX_FMT_YUV420P,
                                 SWS_BILINEAR | SWS_ACCURATE_RND, nullptr, nullptr, nullptr));
  if (!converter)
    throw RunError("cannot create the RGB to yuv420p converter: " + DescribeAvError(0));
  // sRGB content gets BT.709 coefficients and limited range, matching the tags
  // set on the stream, so players show the colours that were rendered.
  const int* bt709 = sws_getCoefficients(SWS_CS_ITU709);
  sws_setColorspaceDetails(converter.get(), bt709, /*srcRange=*/1, bt709, /*dstRange=*/0,
                           /*brightness=*/0, /*contrast=*/1 << 16, /*saturation=*/1 << 16);

  // swscale's SIMD loads read up to 16 bytes past the last input pixel (valgrind: "Invalid read
  // of size 16" at the end of the caller's frame; a crash when that frame ends at a page
  // boundary). Converting from our own copy with slack keeps those reads inside our memory.
  constexpr std::size_t kSwscaleReadSlack = 64;
  padded.resize(static_cast<std::size_t>(encoded_width) * encoded_height * 3 + kSwscaleReadSlack);
}

void VideoWriter::Impl::ProbeEncoder(const VideoOptions& options) {
  InstallAvLogCapture();
  Impl probe(options);
  std::string failure;
  if (!probe.TryOpenEncoder(options.codec, &failure)) throw RunError(failure);
}

void VideoWriter::Impl::OpenEncoder() {
  if (Format().codec != kH264) {  // a format of one encoder; H.264 follows --codec
    const std::string name(Format().codec);
    if (EncoderOf(name) == nullptr) {
      throw RunError("video format " + std::string(Format().name) +
                     ": fetchscope has no settings for the encoder " + name + " (it knows " +
                     KnownEncoderList() + ")");
    }
    std::string failure;
    if (!TryOpenEncoder(name, &failure)) {
      throw RunError("video codec " + name + " cannot open (" + failure +
                     "); install Debian's libavcodec59, which has it");
    }
    return;
  }
  const bool automatic = options.codec == "auto";
  std::string failure;
  if (automatic || options.codec == "h264_nvenc") {
    if (TryOpenEncoder("h264_nvenc", &failure)) return;
    if (!automatic) {
      throw RunError("video codec h264_nvenc: NVENC is unavailable (" + failure +
                     "); use --codec libx264");
    }
  }
  if (!TryOpenEncoder("libx264", &failure)) {
    throw RunError("video codec libx264 cannot open (" + failure +
                   "); install a libavcodec built with libx264 (Debian's libavcodec59 is)");
  }
}

bool VideoWriter::Impl::TryOpenEncoder(const std::string& name, std::string* failure) {
  ClearLastAvError();
  const KnownEncoder* known = EncoderOf(name);
  if (known == nullptr) {
    *failure = "fetchscope has no settings for the encoder " + name + " (it knows " +
               KnownEncoderList() + ")";
    return false;
  }
  const AVCodec* codec = avcodec_find_encoder_by_name(name.c_str());
  if (codec == nullptr) {
    *failure = "this libavcodec has no " + name + " encoder";
    return false;
  }
  CodecContextPtr context(avcodec_alloc_context3(codec));
  if (!context) {
    *failure = "out of memory";
    return false;
  }
  context->width = encoded_width;
  context->height = encoded_height;
  switch (Format().pixels) {
    case VideoPixels::kYuv420p:
      context->pix_fmt = AV_PIX_FMT_YUV420P;
      break;
    case VideoPixels::kPal8:
      context->pix_fmt = AV_PIX_FMT_PAL8;
      break;
    case VideoPixels::kRgb24:
      context->pix_fmt = AV_PIX_FMT_RGB24;
      break;
  }
  // GIF frames keep their input index as pts (frames between gif_fps ticks are dropped)
  context->time_base = AVRational{1, options.fps};
  context->framerate = AVRational{gif ? gif_fps : options.fps, 1};
  context->sample_aspect_ratio = AVRational{1, 1};
  // A keyframe every 2 s keeps scrubbing through an episode quick.
  context->gop_size = 2 * options.fps;
  if (Format().bt709_tags) {  // what the conversion does (ConvertFrame), said on the stream
    context->color_range = AVCOL_RANGE_MPEG;
    context->colorspace = AVCOL_SPC_BT709;
    context->color_primaries = AVCOL_PRI_BT709;
    context->color_trc = AVCOL_TRC_BT709;
  }
  // MP4 and WebM keep the codec's headers (H.264's SPS/PPS) in the container, not the stream.
  const std::string muxer_name(Format().muxer);
  const AVOutputFormat* container = av_guess_format(muxer_name.c_str(), nullptr, nullptr);
  if (container != nullptr && (container->flags & AVFMT_GLOBALHEADER) != 0) {
    context->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
  }

  const int preset_index = PresetIndex(options.preset);
  AvDictionary codec_options;
  switch (known->encoder) {
    case Encoder::kNvenc:
      // Constant-quality VBR is NVENC's nearest match to x264's crf (cq 0 means
      // "automatic" there, so crf 0 asks for the best fixed quality instead).
      codec_options.Set("preset", NvencPresetFor(preset_index));
      codec_options.Set("rc", "vbr");
      codec_options.Set("cq", std::to_string(std::max(options.crf, 1)));
      context->bit_rate = 0;
      break;
    case Encoder::kVp9: {
      // Constant quality (crf with no bitrate cap). x264's crf 23 looks about like VP9's 31, so the
      // scale is shifted by 8. One thread, no row or tile parallelism: libvpx's output then never
      // depends on the machine or the number of workers (record runs one encoder per episode).
      codec_options.Set("crf", std::to_string(std::min(63, options.crf + 8)));
      codec_options.Set("b", "0");
      const Vp9Speed vp9 = Vp9SpeedFor(options.preset);
      codec_options.Set("deadline", vp9.deadline);
      codec_options.Set("cpu-used", std::to_string(vp9.cpu_used));
      codec_options.Set("threads", "1");
      codec_options.Set("row-mt", "0");
      codec_options.Set("tile-columns", "0");
      codec_options.Set("frame-parallel", "0");
      context->bit_rate = 0;
      break;
    }
    case Encoder::kGif:
      // nothing to set: one palette per clip comes from the filter graph
      break;
    case Encoder::kApng:
      // lossless: --crf and --preset do not apply. Each frame is filtered per row as PNG's
      // best guess ("mixed" prediction) and compressed at zlib's default level; one thread.
      codec_options.Set("pred", "mixed");
      codec_options.Set("threads", "1");
      break;
    case Encoder::kX264:
      codec_options.Set("preset", options.preset);
      codec_options.Set("crf", std::to_string(options.crf));
      codec_options.Set("threads", options.threads == 0 ? "auto" : std::to_string(options.threads));
      const std::string params = X264ParamsFor(options.preset);
      if (!params.empty()) codec_options.Set("x264-params", params);
      break;
  }
  if (int rc = avcodec_open2(context.get(), codec, codec_options.address()); rc < 0) {
    *failure = DescribeAvError(rc);
    return false;
  }
  encoder = std::move(context);
  codec_name = name;
  return true;
}

void VideoWriter::Impl::OpenOutput() {
  const fs::path temp_path = TemporaryPathFor(final_path, Format().extension);
  AVFormatContext* raw = nullptr;
  ClearLastAvError();
  // The format is named: the muxer must not guess it from the temporary name.
  const std::string muxer_name(Format().muxer);
  if (int rc = avformat_alloc_output_context2(&raw, nullptr, muxer_name.c_str(), temp_path.c_str());
      rc < 0) {
    throw RunError(std::string("cannot create a ") + muxer_name + " muxer: " + DescribeAvError(rc));
  }
  muxer.reset(raw);
  // Matroska writes a random segment UID and the library version unless asked to be bitexact.
  if (Format().bitexact_muxer) muxer->flags |= AVFMT_FLAG_BITEXACT;
  if (Format().tags == VideoTags::kContainer) {  // the others are inserted by Finish()
    for (const auto& [key, value] : options.metadata) {
      av_dict_set(&muxer->metadata, key.c_str(), value.c_str(), 0);
    }
  }
  stream = avformat_new_stream(muxer.get(), nullptr);
  if (stream == nullptr) throw RunError("cannot add a video stream to the video muxer");
  if (int rc = avcodec_parameters_from_context(stream->codecpar, encoder.get()); rc < 0) {
    throw RunError("cannot copy encoder parameters to the video stream: " + DescribeAvError(rc));
  }
  stream->time_base = encoder->time_base;
  stream->avg_frame_rate = encoder->framerate;
  stream->r_frame_rate = encoder->framerate;

  if (int rc = avio_open(&muxer->pb, temp_path.c_str(), AVIO_FLAG_WRITE); rc < 0) {
    throw RunError("cannot write video " + Quoted(final_path) + ": cannot create a file in " +
                   Quoted(FolderOf(temp_path).string()) + " (" + DescribeAvError(rc) + ")");
  }
  temporary.Adopt(temp_path);

  AvDictionary muxer_options;
  if (!Format().muxer_options.empty()) {
    const std::string pairs(Format().muxer_options);
    if (int rc = av_dict_parse_string(muxer_options.address(), pairs.c_str(), "=", ":", 0);
        rc < 0) {
      throw RunError("the " + std::string(Format().name) + " row's muxer options '" + pairs +
                     "' do not parse: " + DescribeAvError(rc));
    }
  }
  if (int rc = avformat_write_header(muxer.get(), muxer_options.address()); rc < 0) {
    throw RunError("cannot write the " + std::string(Format().name) + " header of " +
                   Quoted(final_path) + ": " + DescribeAvError(rc));
  }
}

void VideoWriter::Impl::ConvertFrame(const uint8_t* rgb) {
  // The encoder released its reference when it consumed the previous frame,
  // so this normally keeps the same buffers (no per-frame allocation).
  if (int rc = av_frame_make_writable(frame.get()); rc < 0) {
    throw RunError("cannot reuse the video frame buffer: " + DescribeAvError(rc));
  }
  switch (Format().pixels) {
    case VideoPixels::kRgb24: {
      const std::size_t row = static_cast<std::size_t>(options.width) * 3;
      for (int y = 0; y < options.height; ++y) {
        std::memcpy(frame->data[0] + static_cast<std::size_t>(y) * frame->linesize[0],
                    rgb + y * row, row);
      }
      return;
    }
    case VideoPixels::kYuv420p:
      break;
    case VideoPixels::kPal8:  // frames go through the palette filter (GifPaletteFilter) instead
      throw RunError("internal: palette frames are not converted one by one");
  }
  if (encoded_width == options.width && encoded_height == options.height) {
    std::memcpy(padded.data(), rgb, static_cast<std::size_t>(options.width) * options.height * 3);
  } else {
    // yuv420p needs even sizes: repeat the last column and/or row.
    const std::size_t in_row = static_cast<std::size_t>(options.width) * 3;
    const std::size_t out_row = static_cast<std::size_t>(encoded_width) * 3;
    for (int y = 0; y < encoded_height; ++y) {
      const uint8_t* in = rgb + std::min(y, options.height - 1) * in_row;
      uint8_t* out = padded.data() + y * out_row;
      std::memcpy(out, in, in_row);
      if (encoded_width != options.width) std::memcpy(out + in_row, in + in_row - 3, 3);
    }
  }
  const uint8_t* const planes[1] = {padded.data()};
  const int strides[1] = {encoded_width * 3};
  sws_scale(converter.get(), planes, strides, 0, encoded_height, frame->data, frame->linesize);
}

// Sends `input` (nullptr: flush) and writes every packet the encoder has ready.
void VideoWriter::Impl::SendFrame(const AVFrame* input) {
  ClearLastAvError();
  if (int rc = avcodec_send_frame(encoder.get(), input); rc < 0) {
    throw RunError("video encoder " + codec_name + " rejected frame " +
                   std::to_string(frames_written) + ": " + DescribeAvError(rc));
  }
  while (true) {
    const int rc = avcodec_receive_packet(encoder.get(), packet.get());
    if (rc == AVERROR(EAGAIN) || rc == AVERROR_EOF) return;
    if (rc < 0) {
      throw RunError("video encoder " + codec_name + " failed: " + DescribeAvError(rc));
    }
    if (gif && packet->duration <= 0) packet->duration = options.fps / gif_fps;
    av_packet_rescale_ts(packet.get(), encoder->time_base, stream->time_base);
    packet->stream_index = stream->index;
    ++frames_encoded;
    // Takes the packet's reference and leaves it blank for the next one.
    if (int write_rc = av_interleaved_write_frame(muxer.get(), packet.get()); write_rc < 0) {
      throw RunError("cannot write video " + Quoted(final_path) + ": " + DescribeAvError(write_rc));
    }
  }
}

void VideoWriter::Impl::Finish() {
  if (finished) return;
  if (frames_written == 0) {
    throw RunError("video " + Quoted(final_path) + " has no frames: nothing written");
  }
  if (gif) {
    gif_filter->Push(nullptr, 0);  // palettegen sees the whole clip; paletteuse lets frames out
    DrainGifFilter();
  }
  KillPoint("video flush");
  SendFrame(nullptr);
  ClearLastAvError();
  if (int rc = av_write_trailer(muxer.get()); rc < 0) {
    throw RunError("cannot finish video " + Quoted(final_path) + ": " + DescribeAvError(rc));
  }
  if (int rc = avio_closep(&muxer->pb); rc < 0) {
    throw RunError("cannot close video " + Quoted(final_path) + ": " + DescribeAvError(rc));
  }
  if (!options.metadata.empty()) {
    switch (Format().tags) {
      case VideoTags::kContainer:  // written by the muxer (OpenOutput)
        break;
      case VideoTags::kGifComment:
        InsertGifComment(temporary.path(), GifComment(options.metadata));
        break;
      case VideoTags::kPngText:
        InsertPngText(temporary.path(), options.metadata);
        break;
    }
  }
  KillPoint("video written, not renamed");
  std::error_code error;
  fs::rename(temporary.path(), final_path, error);
  if (error) {
    throw RunError("cannot rename " + Quoted(temporary.path().string()) + " to " +
                   Quoted(final_path) + ": " + error.message());
  }
  KillPoint("video renamed");
  temporary.Release();
  finished = true;
  // The encoder's and scaler's memory is no longer needed.
  converter.reset();
  frame.reset();
  packet.reset();
  encoder.reset();
  muxer.reset();
  gif_filter.reset();
}

bool VideoWriter::Impl::GifKeeps(int index) const {
  return GifKeepsFrame(index, options.fps, gif_fps);  // the first frame at or after each tick
}

VideoWriter::VideoWriter(const std::string& path, const VideoOptions& options)
    : impl_(std::make_unique<Impl>(path, options)) {}

VideoWriter::~VideoWriter() = default;
VideoWriter::VideoWriter(VideoWriter&& other) noexcept = default;
VideoWriter& VideoWriter::operator=(VideoWriter&& other) noexcept = default;

void VideoWriter::AddFrame(const uint8_t* rgb) {
  if (impl_->finished) {
    throw RunError("video " + Quoted(impl_->final_path) +
                   " is already finished: cannot add frames");
  }
  CpuLap lap;
  if (impl_->gif) {
    if (impl_->GifKeeps(impl_->frames_written)) {
      impl_->gif_filter->Push(rgb, impl_->frames_written);
      impl_->DrainGifFilter();
    }
    ++impl_->frames_written;
    lap.Into(&impl_->encode_cpu_s);
    return;
  }
  impl_->ConvertFrame(rgb);
  lap.Into(&impl_->convert_cpu_s);
  impl_->frame->pts = impl_->frames_written;
  impl_->SendFrame(impl_->frame.get());
  ++impl_->frames_written;
  lap.Into(&impl_->encode_cpu_s);
}

void VideoWriter::Finish() {
  CpuLap lap;
  impl_->Finish();
  lap.Into(&impl_->encode_cpu_s);
}
double VideoWriter::convert_cpu_s() const { return impl_->convert_cpu_s; }
double VideoWriter::encode_cpu_s() const { return impl_->encode_cpu_s; }
int VideoWriter::frames_written() const { return impl_->frames_written; }
int VideoWriter::frames_encoded() const { return impl_->frames_encoded; }
const std::string& VideoWriter::codec_name() const { return impl_->codec_name; }
int VideoWriter::encoded_width() const { return impl_->encoded_width; }
int VideoWriter::encoded_height() const { return impl_->encoded_height; }
const std::string& VideoWriter::path() const { return impl_->final_path; }

VideoCodecDecision DecideVideoCodec(const VideoOptions& options) {
  ValidateVideoOptions(options);
  if (options.codec == "libx264") return {"libx264", "requested"};
  if (options.codec == "auto" && !NvidiaDevicePresent()) {
    return {"libx264", "auto: no NVIDIA GPU here (no /dev/nvidiactl), so no NVENC"};
  }
  // Opening the real encoder is the only reliable test: A100, H100 and H200 have CUDA but no
  // NVENC, and the driver says so only when a session is opened.
  VideoOptions probe = options;
  probe.codec = "h264_nvenc";
  std::string failure = "no NVIDIA driver node (/dev/nvidiactl)";
  if (NvidiaDevicePresent()) {
    try {
      VideoWriter::Impl::ProbeEncoder(probe);
      return {"h264_nvenc", options.codec == "auto" ? "auto: h264_nvenc opened" : "requested"};
    } catch (const RunError& e) {
      failure = e.what();
    }
  }
  if (options.codec == "h264_nvenc") {
    throw RunError("video codec h264_nvenc: NVENC is unavailable (" + failure +
                   "); use --codec libx264");
  }
  return {"libx264", "auto: h264_nvenc unavailable (" + failure + ")"};
}

}  // namespace fetchscope
