// Video file reader on libavformat/libavcodec/libswscale: a video file (our H.264 MP4s, or any
// format FFmpeg demuxes) in, RGB24 frames out, one at a time. The counterpart of VideoWriter,
// for `compare` and for tests that check decoded pixels.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace fetchscope {

/// Decodes the first video stream of a file, frame by frame, in presentation order.
/// Not thread-safe; separate readers may run on separate threads.
class VideoReader {
 public:
  /// Opens `path` and its decoder. Throws RunError naming the file when it is missing, not a
  /// video, or has no decodable video stream.
  explicit VideoReader(const std::string& path);
  ~VideoReader();
  VideoReader(const VideoReader&) = delete;
  VideoReader& operator=(const VideoReader&) = delete;
  /// Moves leave `other` empty.
  VideoReader(VideoReader&& other) noexcept;
  /// Moves; the reader replaced is closed first.
  VideoReader& operator=(VideoReader&& other) noexcept;

  /// Decodes the next frame into `rgb` (resized to width() * height() * 3 bytes, rows top to
  /// bottom). Returns false at the end of the stream. Throws RunError on a decoding error.
  bool Next(std::vector<uint8_t>* rgb);

  /// Frame width in pixels (the coded picture as stored, e.g. even for yuv420p).
  int width() const;
  /// Frame height in pixels.
  int height() const;
  /// Frames per second from the stream's average frame rate (0 if the file does not say).
  double fps() const;
  /// The stream's frame count from the container (0 if it does not say).
  int64_t frames_in_container() const;
  /// The path given to the constructor.
  const std::string& path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Decodes every frame of `path` (see VideoReader). For short videos and tests.
std::vector<std::vector<uint8_t>> ReadAllFrames(const std::string& path, int* width, int* height);

}  // namespace fetchscope
