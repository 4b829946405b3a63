#include "encode/video_reader.h"

#include <utility>

#include "base/errors.h"
#include "encode/av_handles.h"
#include "encode/av_log.h"

extern "C" {
#include <libavutil/error.h>
#include <libavutil/imgutils.h>
}

namespace fetchscope {
namespace {

std::string AvErrorText(int code) {
  char buffer[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(code, buffer, sizeof(buffer));
  return buffer;
}

}  // namespace

struct VideoReader::Impl {
  std::string path;
  InputFormatContextPtr format;
  CodecContextPtr decoder;
  PacketPtr packet;
  FramePtr frame;
  SwsContextPtr converter;  // made for the first frame's size and pixel format
  int stream = -1;
  bool input_done = false;    // demuxer exhausted, decoder flushed
  bool decoder_done = false;  // the decoder returned AVERROR_EOF

  [[noreturn]] void Fail(const std::string& what, int code) const {
    throw RunError("cannot " + what + " '" + path + "': " + AvErrorText(code));
  }

  // Feeds the decoder one packet of our stream, or the flush packet at the end of the file.
  void FeedDecoder() {
    while (true) {
      const int rc = av_read_frame(format.get(), packet.get());
      if (rc == AVERROR_EOF) {
        input_done = true;
        const int flush = avcodec_send_packet(decoder.get(), nullptr);
        if (flush < 0 && flush != AVERROR_EOF) Fail("flush the decoder of", flush);
        return;
      }
      if (rc < 0) Fail("read a packet of", rc);
      const bool ours = packet->stream_index == stream;
      const int sent = ours ? avcodec_send_packet(decoder.get(), packet.get()) : 0;
      av_packet_unref(packet.get());
      if (sent < 0) Fail("decode", sent);
      if (ours) return;
    }
  }

  void Convert(std::vector<uint8_t>* rgb) {
    const int w = frame->width, h = frame->height;
    if (!converter) {
      converter.reset(sws_getContext(w, h, static_cast<AVPixelFormat>(frame->format), w, h,
                                     AV_PIX_FMT_RGB24, SWS_BILINEAR, nullptr, nullptr, nullptr));
      if (!converter) throw RunError("cannot convert the frames of '" + path + "' to RGB");
      // the matrix and range the stream says it uses (our writer: BT.709, limited range);
      // FFmpeg's default would be BT.601 and shift every colour of a BT.709 video
      const int matrix =
          frame->colorspace == AVCOL_SPC_BT709 ? SWS_CS_ITU709
          : frame->colorspace == AVCOL_SPC_BT2020_NCL || frame->colorspace == AVCOL_SPC_BT2020_CL
              ? SWS_CS_BT2020
              : SWS_CS_DEFAULT;
      const int* coefficients = sws_getCoefficients(matrix);
      sws_setColorspaceDetails(converter.get(), coefficients,
                               /*srcRange=*/frame->color_range == AVCOL_RANGE_JPEG ? 1 : 0,
                               coefficients, /*dstRange=*/1, 0, 1 << 16, 1 << 16);
    }
    if (w != decoder->width || h != decoder->height) {
      throw RunError("'" + path + "' changes frame size mid-stream: not supported");
    }
    rgb->resize(static_cast<size_t>(w) * h * 3);
    uint8_t* planes[4] = {rgb->data(), nullptr, nullptr, nullptr};
    int strides[4] = {w * 3, 0, 0, 0};
    sws_scale(converter.get(), frame->data, frame->linesize, 0, h, planes, strides);
  }
};

VideoReader::VideoReader(const std::string& path) : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.path = path;
  InstallAvLogCapture();  // FFmpeg's complaints about a damaged file stay off the terminal
  AVFormatContext* raw = nullptr;
  int rc = avformat_open_input(&raw, path.c_str(), nullptr, nullptr);
  if (rc < 0) s.Fail("open video", rc);
  s.format.reset(raw);
  rc = avformat_find_stream_info(raw, nullptr);
  if (rc < 0) s.Fail("read the streams of", rc);
  const AVCodec* codec = nullptr;
  s.stream = av_find_best_stream(raw, AVMEDIA_TYPE_VIDEO, -1, -1, &codec, 0);
  if (s.stream < 0 || !codec) {
    throw RunError("'" + path + "' has no video stream that this FFmpeg can decode");
  }
  s.decoder.reset(avcodec_alloc_context3(codec));
  if (!s.decoder) throw RunError("cannot allocate a decoder for '" + path + "'");
  rc = avcodec_parameters_to_context(s.decoder.get(), raw->streams[s.stream]->codecpar);
  if (rc < 0) s.Fail("read the codec parameters of", rc);
  s.decoder->thread_count = 1;  // frames come out in order either way; keep it deterministic
  rc = avcodec_open2(s.decoder.get(), codec, nullptr);
  if (rc < 0) s.Fail("open the decoder of", rc);
  s.packet.reset(av_packet_alloc());
  s.frame.reset(av_frame_alloc());
  if (!s.packet || !s.frame) throw RunError("out of memory opening '" + path + "'");
}

VideoReader::~VideoReader() = default;
VideoReader::VideoReader(VideoReader&& other) noexcept = default;
VideoReader& VideoReader::operator=(VideoReader&& other) noexcept = default;

bool VideoReader::Next(std::vector<uint8_t>* rgb) {
  Impl& s = *impl_;
  while (!s.decoder_done) {
    const int rc = avcodec_receive_frame(s.decoder.get(), s.frame.get());
    if (rc == 0) {
      s.Convert(rgb);
      av_frame_unref(s.frame.get());
      return true;
    }
    if (rc == AVERROR_EOF) {
      s.decoder_done = true;
      break;
    }
    if (rc != AVERROR(EAGAIN)) s.Fail("decode", rc);
    if (s.input_done) {
      s.decoder_done = true;  // flushed and still asking for input: nothing more comes
      break;
    }
    s.FeedDecoder();
  }
  return false;
}

int VideoReader::width() const { return impl_->decoder->width; }
int VideoReader::height() const { return impl_->decoder->height; }

double VideoReader::fps() const {
  const AVRational r = impl_->format->streams[impl_->stream]->avg_frame_rate;
  return r.den != 0 ? av_q2d(r) : 0.0;
}

int64_t VideoReader::frames_in_container() const {
  return impl_->format->streams[impl_->stream]->nb_frames;
}

const std::string& VideoReader::path() const { return impl_->path; }

std::vector<std::vector<uint8_t>> ReadAllFrames(const std::string& path, int* width, int* height) {
  VideoReader reader(path);
  std::vector<std::vector<uint8_t>> frames;
  std::vector<uint8_t> rgb;
  while (reader.Next(&rgb)) frames.push_back(rgb);
  if (width) *width = reader.width();
  if (height) *height = reader.height();
  return frames;
}

}  // namespace fetchscope
