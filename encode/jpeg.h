// JPEG through libjpeg-turbo's TurboJPEG API: serve's live frames while the view moves (about
// 0.6 ms and 24 KB for a 640x480 frame at quality 75 on the development machine; PNG takes
// about 7 ms, so it is kept for the frame at rest).
#pragma once

#include <cstdint>
#include <string>

namespace fetchscope {

/// The JPEG qualities EncodeJpeg accepts.
inline constexpr int kMinJpegQuality = 1;
inline constexpr int kMaxJpegQuality = 100;

/// One compressor, reused frame to frame (one per thread).
class JpegEncoder {
 public:
  JpegEncoder();
  ~JpegEncoder();
  JpegEncoder(const JpegEncoder&) = delete;
  JpegEncoder& operator=(const JpegEncoder&) = delete;

  /// The JPEG file of `rgb` (width x height x 3 bytes, row 0 = top) at `quality`
  /// (kMinJpegQuality..kMaxJpegQuality; 4:2:0 chroma below 90, 4:4:4 from 90 up). Throws
  /// UsageError for a size or quality out of range and RunError when libjpeg-turbo fails.
  std::string Encode(const uint8_t* rgb, int width, int height, int quality);

 private:
  void* handle_ = nullptr;  // tjhandle
};

}  // namespace fetchscope
