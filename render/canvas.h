// One 2D canvas over a caller's RGB24 pixels (row 0 = top; pixel (i, j)'s centre at
// (i + 0.5, j + 0.5)): every 2D drawing in fetchscope goes through it, the HUD and tile labels,
// contact sheets, golden side-by-sides and the anatomy card. There is one alpha blend
// (BlendChannel); shapes are anti-aliased by their coverage of each pixel's centre, text by
// FreeType's coverage (render/text.h). Everything is clipped to the image, so any position is
// safe.
#pragma once

#include <cstdint>
#include <string>

#include "render/text.h"
#include "render/vec.h"

namespace fetchscope {

/// The one alpha blend: `under` moved toward `over` by `alpha` (0 keeps `under`, 1 gives
/// `over`), rounded to the nearest level. With alpha = k / 255 it equals the integer
/// (under * (255 - k) + over * k + 127) / 255 exactly (tests/canvas_test.cc checks every case).
uint8_t BlendChannel(uint8_t under, uint8_t over, double alpha);

/// An arrow's shape, pixels: a shaft with round ends and a triangular head at the tip.
struct ArrowShape {
  double shaft = 4;         ///< shaft width
  double head_length = 16;  ///< head, along the arrow (at most half the arrow)
  double head_width = 13;   ///< head, across (shrinks with a shortened head)
};

/// A drawing surface over `width` x `height` RGB24 pixels owned by the caller.
class Canvas {
 public:
  /// Draws into `rgb` (width * height * 3 bytes, row 0 = top), which must outlive the canvas.
  Canvas(uint8_t* rgb, int width, int height) : rgb_(rgb), width_(width), height_(height) {}

  int width() const { return width_; }    ///< pixels
  int height() const { return height_; }  ///< pixels
  uint8_t* data() { return rgb_; }        ///< the pixels drawn on

  /// Blends `c` over pixel (x, y) by `alpha` (BlendChannel); nothing outside the image or for
  /// alpha <= 0.
  void Blend(int x, int y, Rgb c, double alpha);

  /// Fills the w x h rectangle at (x, y) (clipped) with `c`, blended by `alpha` (1: opaque).
  void FillRect(int x, int y, int w, int h, Rgb c, double alpha = 1.0);

  /// Copies the w x h RGB24 image `rgb` (row 0 = top) with its top-left corner at (x, y),
  /// clipped to the canvas.
  void Paste(const uint8_t* rgb, int w, int h, int x, int y);

  /// A segment `width` pixels wide with round ends (a disc when a == b).
  void Capsule(Pixel a, Pixel b, double width, Rgb c);

  /// A disc of `radius` pixels around `centre`.
  void Disc(Pixel centre, double radius, Rgb c) { Capsule(centre, centre, 2 * radius, c); }

  /// The triangle p0 p1 p2 grown by `grow` pixels on every side; nothing for a degenerate one.
  void Triangle(Pixel p0, Pixel p1, Pixel p2, double grow, Rgb c);

  /// An arrow from `from` to `to` of `shape`, every part grown by `rim` pixels on each side
  /// (drawn once with a rim in a dark colour and once without, it gets an outline).
  void Arrow(Pixel from, Pixel to, const ArrowShape& shape, double rim, Rgb c);

  /// Draws `utf8` in the default font at an em of `pixel_size` with the top-left corner of its
  /// text box at (x, y) (render/text.h); returns its metrics.
  TextMetrics Text(int x, int y, const std::string& utf8, int pixel_size, Rgb c);

 private:
  // Blends `c` into the pixels around `r` by coverage(centre x, centre y).
  template <typename Coverage>
  void ForEachPixel(const RectF& r, Coverage coverage, Rgb c);

  uint8_t* rgb_;
  int width_, height_;
};

}  // namespace fetchscope
