#include "render/projection.h"

#include <cmath>

namespace fetchscope {
namespace {

double Dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

void Cross(const double a[3], const double b[3], double out[3]) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

void Normalize(double v[3]) {
  const double n = std::sqrt(Dot(v, v));
  if (n > 0) {
    for (int i = 0; i < 3; ++i) v[i] /= n;
  }
}

}  // namespace

std::optional<Pixel> ProjectToPixel(const mjvScene& scene, const mjrRect& tile, int frame_height,
                                    const std::array<double, 3>& point) {
  const mjvGLCamera cam = mjv_averageCamera(&scene.camera[0], &scene.camera[1]);
  // the view basis of mjr_lookAt: side = forward x up, true up = side x forward
  double forward[3] = {cam.forward[0], cam.forward[1], cam.forward[2]};
  double up[3] = {cam.up[0], cam.up[1], cam.up[2]};
  Normalize(forward);
  double side[3], true_up[3];
  Cross(forward, up, side);
  Normalize(side);
  Cross(side, forward, true_up);
  const double v[3] = {point[0] - cam.pos[0], point[1] - cam.pos[1], point[2] - cam.pos[2]};
  const double depth = Dot(v, forward);
  if (depth <= 1e-9) return std::nullopt;
  // glFrustum(center -+ halfwidth, bottom, top, near): halfwidth matches the viewport's aspect
  const double near = cam.frustum_near;
  const double halfheight = 0.5 * (cam.frustum_top - cam.frustum_bottom);
  const double halfwidth = halfheight * tile.width / static_cast<double>(tile.height);
  const double centre_y = 0.5 * (cam.frustum_top + cam.frustum_bottom);
  const double ndc_x = (near * Dot(v, side) / depth - cam.frustum_center) / halfwidth;
  const double ndc_y = (near * Dot(v, true_up) / depth - centre_y) / halfheight;
  const double gl_x = tile.left + 0.5 * (ndc_x + 1.0) * tile.width;
  const double gl_y = tile.bottom + 0.5 * (ndc_y + 1.0) * tile.height;  // from the bottom
  return Pixel{gl_x, frame_height - gl_y};
}

}  // namespace fetchscope
