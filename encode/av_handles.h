// RAII owners for the FFmpeg (libavformat/libavcodec/libavutil/libswscale)
// objects used by the video writer and its tests: one std::unique_ptr alias
// per C handle, so each is non-copyable with noexcept moves and freed by the
// library's own free function.
#pragma once

#include <memory>
#include <string>
#include <utility>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/dict.h>
#include <libavutil/frame.h>
#include <libswscale/swscale.h>
}

namespace fetchscope {

/// Frees a muxing context: closes its output file first if it was opened by
/// avio_open (AVFMT_NOFILE formats own no file).
struct OutputFormatContextDeleter {
  void operator()(AVFormatContext* context) const noexcept {
    if (context->oformat != nullptr && !(context->oformat->flags & AVFMT_NOFILE)) {
      avio_closep(&context->pb);
    }
    avformat_free_context(context);
  }
};
/// An AVFormatContext from avformat_alloc_output_context2.
using OutputFormatContextPtr = std::unique_ptr<AVFormatContext, OutputFormatContextDeleter>;

/// Closes a demuxing context opened by avformat_open_input.
struct InputFormatContextDeleter {
  void operator()(AVFormatContext* context) const noexcept { avformat_close_input(&context); }
};
/// An AVFormatContext from avformat_open_input.
using InputFormatContextPtr = std::unique_ptr<AVFormatContext, InputFormatContextDeleter>;

/// Frees an encoder or decoder context.
struct CodecContextDeleter {
  void operator()(AVCodecContext* context) const noexcept { avcodec_free_context(&context); }
};
/// An AVCodecContext from avcodec_alloc_context3.
using CodecContextPtr = std::unique_ptr<AVCodecContext, CodecContextDeleter>;

/// Frees a frame and drops its buffer references.
struct FrameDeleter {
  void operator()(AVFrame* frame) const noexcept { av_frame_free(&frame); }
};
/// An AVFrame from av_frame_alloc.
using FramePtr = std::unique_ptr<AVFrame, FrameDeleter>;

/// Frees a packet and drops its buffer reference.
struct PacketDeleter {
  void operator()(AVPacket* packet) const noexcept { av_packet_free(&packet); }
};
/// An AVPacket from av_packet_alloc.
using PacketPtr = std::unique_ptr<AVPacket, PacketDeleter>;

/// Frees a software scaler / pixel-format converter.
struct SwsContextDeleter {
  void operator()(SwsContext* context) const noexcept { sws_freeContext(context); }
};
/// A SwsContext from sws_getContext.
using SwsContextPtr = std::unique_ptr<SwsContext, SwsContextDeleter>;

/// Owns an AVDictionary of options. FFmpeg's open functions take the
/// address and leave behind the entries they did not consume.
class AvDictionary {
 public:
  AvDictionary() = default;
  ~AvDictionary() { av_dict_free(&dict_); }
  AvDictionary(const AvDictionary&) = delete;
  AvDictionary& operator=(const AvDictionary&) = delete;
  AvDictionary(AvDictionary&& other) noexcept : dict_(std::exchange(other.dict_, nullptr)) {}
  AvDictionary& operator=(AvDictionary&& other) noexcept {
    std::swap(dict_, other.dict_);
    return *this;
  }

  /// Sets `key` to `value`, replacing an earlier value.
  void Set(const std::string& key, const std::string& value) {
    av_dict_set(&dict_, key.c_str(), value.c_str(), 0);
  }
  /// The address to hand to avcodec_open2 / avformat_write_header.
  AVDictionary** address() { return &dict_; }
  /// Number of entries (after an open call: the options nobody recognised).
  int size() const { return av_dict_count(dict_); }

 private:
  AVDictionary* dict_ = nullptr;
};

}  // namespace fetchscope
