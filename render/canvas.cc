#include "render/canvas.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace fetchscope {

uint8_t BlendChannel(uint8_t under, uint8_t over, double alpha) {
  return static_cast<uint8_t>(std::lround((1 - alpha) * under + alpha * over));
}

void Canvas::Blend(int x, int y, Rgb c, double alpha) {
  if (x < 0 || y < 0 || x >= width_ || y >= height_ || alpha <= 0) return;
  uint8_t* p = rgb_ + (static_cast<size_t>(y) * width_ + x) * 3;
  p[0] = BlendChannel(p[0], c.r, alpha);
  p[1] = BlendChannel(p[1], c.g, alpha);
  p[2] = BlendChannel(p[2], c.b, alpha);
}

void Canvas::FillRect(int x, int y, int w, int h, Rgb c, double alpha) {
  const int x0 = std::max(0, x), x1 = std::min(width_, x + w);
  const int y0 = std::max(0, y), y1 = std::min(height_, y + h);
  uint8_t lut[3][256];
  bool lut_ready = false;
  for (int row = y0; row < y1; ++row) {
    if (alpha >= 1) {  // opaque: what the blend gives, written straight
      uint8_t* p = rgb_ + (static_cast<size_t>(row) * width_ + x0) * 3;
      for (int col = x0; col < x1; ++col, p += 3) p[0] = c.r, p[1] = c.g, p[2] = c.b;
    } else {
      // one colour at one alpha: BlendChannel of every possible value looked up, not recomputed
      // per pixel (a HUD box is tens of thousands of pixels a frame); the same bytes
      if (alpha <= 0) return;
      if (!lut_ready) {
        for (int v = 0; v < 256; ++v) {
          const auto u = static_cast<uint8_t>(v);
          lut[0][v] = BlendChannel(u, c.r, alpha);
          lut[1][v] = BlendChannel(u, c.g, alpha);
          lut[2][v] = BlendChannel(u, c.b, alpha);
        }
        lut_ready = true;
      }
      uint8_t* p = rgb_ + (static_cast<size_t>(row) * width_ + x0) * 3;
      for (int col = x0; col < x1; ++col, p += 3) {
        p[0] = lut[0][p[0]];
        p[1] = lut[1][p[1]];
        p[2] = lut[2][p[2]];
      }
    }
  }
}

void Canvas::Paste(const uint8_t* rgb, int w, int h, int x, int y) {
  const int x0 = std::max(0, x), x1 = std::min(width_, x + w);
  if (x1 <= x0) return;
  for (int row = std::max(0, y); row < std::min(height_, y + h); ++row) {
    std::memcpy(rgb_ + (static_cast<size_t>(row) * width_ + x0) * 3,
                rgb + (static_cast<size_t>(row - y) * w + (x0 - x)) * 3,
                static_cast<size_t>(x1 - x0) * 3);
  }
}

template <typename Coverage>
void Canvas::ForEachPixel(const RectF& r, Coverage coverage, Rgb c) {
  const int x0 = std::max(0, static_cast<int>(std::floor(r.x0 - 1)));
  const int y0 = std::max(0, static_cast<int>(std::floor(r.y0 - 1)));
  const int x1 = std::min(width_ - 1, static_cast<int>(std::ceil(r.x1 + 1)));
  const int y1 = std::min(height_ - 1, static_cast<int>(std::ceil(r.y1 + 1)));
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) Blend(x, y, c, coverage(x + 0.5, y + 0.5));
  }
}

void Canvas::Capsule(Pixel a, Pixel b, double width, Rgb c) {
  const double r = width / 2;
  const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
  ForEachPixel(
      {std::min(a.x, b.x) - r, std::min(a.y, b.y) - r, std::max(a.x, b.x) + r,
       std::max(a.y, b.y) + r},
      [&](double px, double py) {
        double t = len2 > 0 ? ((px - a.x) * dx + (py - a.y) * dy) / len2 : 0;
        t = std::clamp(t, 0.0, 1.0);
        const double d = std::hypot(px - a.x - t * dx, py - a.y - t * dy);
        return std::clamp(r + 0.5 - d, 0.0, 1.0);
      },
      c);
}

void Canvas::Triangle(Pixel p0, Pixel p1, Pixel p2, double grow, Rgb c) {
  const Pixel p[3] = {p0, p1, p2};
  const double area = (p1.x - p0.x) * (p2.y - p0.y) - (p1.y - p0.y) * (p2.x - p0.x);
  if (std::abs(area) < 1e-9) return;
  const double sign = area > 0 ? 1 : -1;
  const double margin = grow * 3;  // the grown corners reach out further than `grow`
  ForEachPixel(
      {std::min({p0.x, p1.x, p2.x}) - margin, std::min({p0.y, p1.y, p2.y}) - margin,
       std::max({p0.x, p1.x, p2.x}) + margin, std::max({p0.y, p1.y, p2.y}) + margin},
      [&](double px, double py) {
        double inside = 1e300;  // distance to the nearest edge, > 0 inside
        for (int i = 0; i < 3; ++i) {
          const Pixel a = p[i], b = p[(i + 1) % 3];
          const double ex = b.x - a.x, ey = b.y - a.y, len = std::hypot(ex, ey);
          inside = std::min(inside, sign * (ex * (py - a.y) - ey * (px - a.x)) / len);
        }
        return std::clamp(inside + grow + 0.5, 0.0, 1.0);
      },
      c);
}

void Canvas::Arrow(Pixel from, Pixel to, const ArrowShape& shape, double rim, Rgb c) {
  const double len = Distance(from, to);
  if (len < 1e-6) return;
  const double ux = (to.x - from.x) / len, uy = (to.y - from.y) / len;
  const double head = std::min(shape.head_length, 0.5 * len);
  const double half = 0.5 * shape.head_width * head / shape.head_length;
  const Pixel base{to.x - ux * head, to.y - uy * head};
  // the shaft reaches half a pixel under the head, so that no seam shows between them
  Capsule(from, {base.x + ux * 0.5, base.y + uy * 0.5}, shape.shaft + 2 * rim, c);
  Triangle(to, {base.x - uy * half, base.y + ux * half}, {base.x + uy * half, base.y - ux * half},
           rim, c);
}

TextMetrics Canvas::Text(int x, int y, const std::string& utf8, int pixel_size, Rgb c) {
  TextStyle style;
  style.pixel_size = pixel_size;
  style.color = c;
  return Font::Default().Draw(this, x, y, utf8, style);
}

}  // namespace fetchscope
