// Small vector maths shared by the drawings and the measurements: world points (Vec3, metres)
// and image points (Pixel, row 0 at the top), rectangles and segments in the image plane.
// Header-only; every function is exact double arithmetic in the order written, so moving a
// caller onto it changes no result.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <utility>

namespace fetchscope {

/// A world point or direction, metres (MuJoCo's frame: z up).
using Vec3 = std::array<double, 3>;

/// a + scale * b.
inline Vec3 Add(const Vec3& a, const Vec3& b, double scale = 1.0) {
  return {a[0] + scale * b[0], a[1] + scale * b[1], a[2] + scale * b[2]};
}

/// The point halfway between a and b.
inline Vec3 Mid(const Vec3& a, const Vec3& b) { return Add(a, Add(b, a, -1.0), 0.5); }

/// |v|.
inline double Norm(const Vec3& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

/// v scaled to length 1 (a zero vector stays near zero).
inline Vec3 Unit(const Vec3& v) {
  const double n = std::max(1e-12, std::hypot(v[0], v[1], v[2]));
  return {v[0] / n, v[1] / n, v[2] / n};
}

/// A pixel position in a frame: x to the right, y down from the top row (row 0 = top, as the
/// images fetchscope writes), in pixels; may lie outside the frame. Pixel (i, j) covers
/// [i, i + 1) x [j, j + 1), so its centre is (i + 0.5, j + 0.5).
struct Pixel {
  double x;  ///< column, 0 = left edge of the frame
  double y;  ///< row, 0 = top edge of the frame
};

/// An axis-aligned rectangle in pixels (x0 <= x1, y0 <= y1), row 0 at the top.
struct RectF {
  double x0, y0, x1, y1;
};

/// `r` grown by `d` pixels on every side (shrunk for d < 0).
inline RectF Grown(const RectF& r, double d) { return {r.x0 - d, r.y0 - d, r.x1 + d, r.y1 + d}; }

/// Whether the insides of a and b overlap (touching edges do not count).
inline bool Intersect(const RectF& a, const RectF& b) {
  return a.x0 < b.x1 && b.x0 < a.x1 && a.y0 < b.y1 && b.y0 < a.y1;
}

/// The area a and b share, square pixels.
inline double OverlapArea(const RectF& a, const RectF& b) {
  const double w = std::min(a.x1, b.x1) - std::max(a.x0, b.x0);
  const double h = std::min(a.y1, b.y1) - std::max(a.y0, b.y0);
  return w > 0 && h > 0 ? w * h : 0;
}

/// The point of `box` nearest to `p`.
inline Pixel Nearest(const RectF& box, Pixel p) {
  return {std::clamp(p.x, box.x0, box.x1), std::clamp(p.y, box.y0, box.y1)};
}

/// Segment a-b cut to rectangle r (Liang-Barsky); none when it misses r.
inline std::optional<std::pair<Pixel, Pixel>> ClipSegment(Pixel a, Pixel b, const RectF& r) {
  double t0 = 0, t1 = 1;
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double p[4] = {-dx, dx, -dy, dy};
  const double q[4] = {a.x - r.x0, r.x1 - a.x, a.y - r.y0, r.y1 - a.y};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0) {
      if (q[i] < 0) return std::nullopt;
    } else {
      const double t = q[i] / p[i];
      if (p[i] < 0)
        t0 = std::max(t0, t);
      else
        t1 = std::min(t1, t);
      if (t0 > t1) return std::nullopt;
    }
  }
  return std::make_pair(Pixel{a.x + t0 * dx, a.y + t0 * dy}, Pixel{a.x + t1 * dx, a.y + t1 * dy});
}

/// Whether segment a-b meets rectangle r.
inline bool SegmentHitsRect(Pixel a, Pixel b, const RectF& r) {
  return ClipSegment(a, b, r).has_value();
}

/// Whether segments a-b and c-d cross (touching ends do not count).
inline bool SegmentsCross(Pixel a, Pixel b, Pixel c, Pixel d) {
  auto side = [](Pixel p, Pixel q, Pixel r) {
    return (q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x);
  };
  const double d1 = side(c, d, a), d2 = side(c, d, b), d3 = side(a, b, c), d4 = side(a, b, d);
  return d1 * d2 < 0 && d3 * d4 < 0;
}

/// |b - a|, pixels.
inline double Distance(Pixel a, Pixel b) { return std::hypot(b.x - a.x, b.y - a.y); }

/// How far p is from segment a-b, pixels.
inline double DistanceToSegment(Pixel p, Pixel a, Pixel b) {
  const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
  const double t =
      len2 > 0 ? std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / len2, 0.0, 1.0) : 0;
  return Distance(p, {a.x + t * dx, a.y + t * dy});
}

}  // namespace fetchscope
