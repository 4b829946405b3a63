#include "inspect/image_diff.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>

#include "render/canvas.h"

namespace fetchscope {
namespace {

constexpr Rgb kSideBySideBackground = {40, 40, 40};
constexpr Rgb kSideBySideText = {235, 235, 235};

int PixelDiff(const uint8_t* a, const uint8_t* b) {
  int d = 0;
  for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(int{a[c]} - int{b[c]}));
  return d;
}

// 0 -> black; 1 -> dark blue; then through red and yellow to white at 255. The first visible
// level is bright enough that a single-level difference shows on a screen.
void HeatColour(int d, uint8_t* out) {
  if (d == 0) {
    out[0] = out[1] = out[2] = 0;
    return;
  }
  // a square-root scale so small differences (llvmpipe noise) are not lost next to big ones
  const double t = std::sqrt(d / 255.0);
  double r, g, b;
  if (t < 1.0 / 3) {
    const double u = t * 3;  // blue -> red
    r = u;
    g = 0;
    b = 0.5 * (1 - u) + 0.2;
  } else if (t < 2.0 / 3) {
    const double u = t * 3 - 1;  // red -> yellow
    r = 1;
    g = u;
    b = 0.2 * (1 - u);
  } else {
    const double u = t * 3 - 2;  // yellow -> white
    r = 1;
    g = 1;
    b = u;
  }
  out[0] = static_cast<uint8_t>(std::lround(std::clamp(r, 0.0, 1.0) * 255));
  out[1] = static_cast<uint8_t>(std::lround(std::clamp(g, 0.0, 1.0) * 255));
  out[2] = static_cast<uint8_t>(std::lround(std::clamp(b, 0.0, 1.0) * 255));
}

}  // namespace

ImageDiffStats CompareRgb(const uint8_t* golden, const uint8_t* actual, int width, int height,
                          int threshold) {
  ImageDiffStats stats;
  stats.pixels = static_cast<size_t>(width) * height;
  double sum_sq = 0;
  for (size_t i = 0; i < stats.pixels; ++i) {
    const uint8_t* a = golden + 3 * i;
    const uint8_t* b = actual + 3 * i;
    for (int c = 0; c < 3; ++c) {
      const double d = int{a[c]} - int{b[c]};
      sum_sq += d * d;
    }
    const int d = PixelDiff(a, b);
    stats.max_diff = std::max(stats.max_diff, d);
    if (d > threshold) ++stats.pixels_over;
  }
  if (stats.pixels > 0) {
    stats.fraction_over = static_cast<double>(stats.pixels_over) / stats.pixels;
    stats.rms = std::sqrt(sum_sq / (3.0 * stats.pixels));
  }
  return stats;
}

std::vector<uint8_t> DiffHeatMap(const uint8_t* golden, const uint8_t* actual, int width,
                                 int height) {
  const size_t pixels = static_cast<size_t>(width) * height;
  std::vector<uint8_t> heat(pixels * 3);
  for (size_t i = 0; i < pixels; ++i)
    HeatColour(PixelDiff(golden + 3 * i, actual + 3 * i), &heat[3 * i]);
  return heat;
}

int SideBySideLabelPixels(int height) { return std::clamp(height / 16, 9, 24); }

int SideBySideLabelHeight(int height) {
  const int pixels = SideBySideLabelPixels(height);
  const TextMetrics m = Font::Default().Measure("Ag", pixels);
  return m.ascent + m.descent + 2 * std::max(2, pixels / 4);
}

std::vector<uint8_t> SideBySide(const uint8_t* golden, const uint8_t* actual, const uint8_t* diff,
                                int width, int height) {
  const int out_width = SideBySideWidth(width), strip = SideBySideLabelHeight(height);
  const int pixels = SideBySideLabelPixels(height), pad = std::max(2, pixels / 4);
  std::vector<uint8_t> out(static_cast<size_t>(out_width) * (strip + height) * 3);
  Canvas canvas(out.data(), out_width, strip + height);
  canvas.FillRect(0, 0, out_width, strip + height, kSideBySideBackground);
  const Font& font = Font::Default();
  const uint8_t* panels[3] = {golden, actual, diff};
  for (int p = 0; p < 3; ++p) {
    const int x = p * (width + kSideBySideGap);
    canvas.Paste(panels[p], width, height, x, strip);
    // centred over the panel (as compare's strip names its panels), cut to fit it
    const std::string label = font.Fit(kSideBySideLabels[p], pixels, width - 2 * pad);
    const int label_x = x + std::max(pad, (width - font.Measure(label, pixels).width) / 2);
    canvas.Text(label_x, pad, label, pixels, kSideBySideText);
  }
  return out;
}

}  // namespace fetchscope
