// PNG files through libpng. Pixels are row 0 = top; 16-bit samples are uint16 in the host's
// byte order in memory (libpng swaps to PNG's big-endian on the way out and back).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace fetchscope {

/// Writes `pixels` (width*height*channels samples, row 0 = top; bit_depth 16: uint16 in host
/// byte order) as a PNG: channels 1 = gray, 2 = gray+alpha, 3 = RGB, 4 = RGBA; bit_depth 8 or
/// 16. The file appears complete or not at all: it is written to .NAME.tmp-XXXXXX beside it and
/// renamed. Throws UsageError for bad arguments and RunError when the file cannot be written.
/// `fast`: libpng's Sub filter alone and zlib level 3 instead of every filter and level 6, about
/// half the CPU for about 18% more bytes (contact sheets); the pixels are the same.
void WritePng(const std::string& path, int width, int height, int channels, int bit_depth,
              const void* pixels, bool fast = false);

/// The bytes of the PNG file WritePng would write for these arguments, in memory (serve's
/// lossless live frames). Throws as WritePng, with `what` naming the image in messages.
std::string EncodePng(int width, int height, int channels, int bit_depth, const void* pixels,
                      bool fast = false, const std::string& what = "frame");

/// A decoded image.
struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;             ///< 1 gray, 2 gray+alpha, 3 RGB, 4 RGBA
  int bit_depth = 8;            ///< 8 or 16
  std::vector<uint8_t> pixels;  ///< row 0 = top; 16-bit samples as uint16 in host byte order

  /// Bytes per row.
  size_t row_bytes() const { return static_cast<size_t>(width) * channels * (bit_depth / 8); }
};

/// Reads a PNG. Palette images become RGB(A), gray below 8 bits becomes 8-bit, transparency
/// chunks become an alpha channel. Throws RunError for a missing, unreadable or corrupt file.
Image ReadPng(const std::string& path);

/// ReadPng of the bytes of a PNG file in memory; `what` names it in messages.
Image DecodePng(const std::string& bytes, const std::string& what = "PNG data");

}  // namespace fetchscope
