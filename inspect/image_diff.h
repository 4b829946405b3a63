// Comparing two RGB24 images of the same size, for golden-image tests: how many pixels differ by
// more than a threshold, the largest difference and the RMS error, plus a heat map of the
// differences and a golden | actual | diff strip for people to look at.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace fetchscope {

/// How far apart two images are. A pixel's difference is its largest channel difference
/// (0..255), so a change in any one colour counts in full.
struct ImageDiffStats {
  size_t pixels = 0;         ///< pixels compared (width * height)
  size_t pixels_over = 0;    ///< pixels whose difference exceeds the threshold
  double fraction_over = 0;  ///< pixels_over / pixels
  int max_diff = 0;          ///< largest channel difference anywhere, 0..255
  double rms = 0;            ///< root mean square over every channel of every pixel, in levels
};

/// Compares `golden` and `actual` (each width * height * 3 bytes, same layout) with a per-pixel
/// `threshold` in levels: a pixel counts as different when its largest channel difference is
/// greater than `threshold`.
ImageDiffStats CompareRgb(const uint8_t* golden, const uint8_t* actual, int width, int height,
                          int threshold);

/// A heat map of the per-pixel difference (largest channel difference): black where equal, then
/// dark blue → red → yellow → white as the difference grows, with every non-zero difference
/// visible (at least dark blue). width * height * 3 bytes, row 0 = top.
std::vector<uint8_t> DiffHeatMap(const uint8_t* golden, const uint8_t* actual, int width,
                                 int height);

/// Gap between the panels of SideBySide, pixels.
inline constexpr int kSideBySideGap = 4;

/// Em size of SideBySide's panel labels for panels `height` high: height / 16, 9..24 (15 at
/// 240), as compare's side-by-side videos label theirs.
int SideBySideLabelPixels(int height);

/// Height of SideBySide's label strip above panels `height` high, pixels: one label line and a
/// margin of a quarter em (at least 2 pixels) above and below it.
int SideBySideLabelHeight(int height);

/// golden | actual | diff side by side on a dark background, each panel width x height with
/// kSideBySideGap pixels between them, under a strip (SideBySideLabelHeight) that names each
/// panel, centred ("golden", "actual", "diff"), in the default font:
/// SideBySideWidth(width) x SideBySideHeight(height), RGB24, row 0 = top.
std::vector<uint8_t> SideBySide(const uint8_t* golden, const uint8_t* actual, const uint8_t* diff,
                                int width, int height);

/// The width of SideBySide's image for panels `width` wide.
inline int SideBySideWidth(int width) { return 3 * width + 2 * kSideBySideGap; }

/// The height of SideBySide's image for panels `height` high: the label strip and a panel.
inline int SideBySideHeight(int height) { return SideBySideLabelHeight(height) + height; }

/// The panel names of SideBySide, left to right.
inline constexpr const char* kSideBySideLabels[3] = {"golden", "actual", "diff"};

}  // namespace fetchscope
