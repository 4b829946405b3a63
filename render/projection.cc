#include "render/projection.h"

#include <cmath>

namespace fetchscope {
namespace {

using Vec3 = std::array<double, 3>;

double Dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

Vec3 Cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

Vec3 Normalized(Vec3 v) {
  const double n = std::sqrt(Dot(v, v));
  if (n > 0) {
    for (double& x : v) x /= n;
  }
  return v;
}

}  // namespace

CameraAxes SceneCameraAxes(const mjvScene& scene) {
  const mjvGLCamera cam = mjv_averageCamera(&scene.camera[0], &scene.camera[1]);
  // the view basis of mjr_lookAt: side = forward x up, true up = side x forward
  const Vec3 forward = Normalized({cam.forward[0], cam.forward[1], cam.forward[2]});
  const Vec3 up = {cam.up[0], cam.up[1], cam.up[2]};
  const Vec3 side = Normalized(Cross(forward, up));
  return {side, Cross(side, forward), forward};
}

std::optional<Pixel> ProjectToPixel(const mjvScene& scene, const mjrRect& tile, int frame_height,
                                    const std::array<double, 3>& point) {
  const mjvGLCamera cam = mjv_averageCamera(&scene.camera[0], &scene.camera[1]);
  const CameraAxes axes = SceneCameraAxes(scene);
  const Vec3 v = {point[0] - cam.pos[0], point[1] - cam.pos[1], point[2] - cam.pos[2]};
  const double depth = Dot(v, axes.forward);
  if (depth <= 1e-9) return std::nullopt;
  // glFrustum(center -+ halfwidth, bottom, top, near): halfwidth matches the viewport's aspect
  const double near = cam.frustum_near;
  const double halfheight = 0.5 * (cam.frustum_top - cam.frustum_bottom);
  const double halfwidth = halfheight * tile.width / static_cast<double>(tile.height);
  const double centre_y = 0.5 * (cam.frustum_top + cam.frustum_bottom);
  const double ndc_x = (near * Dot(v, axes.right) / depth - cam.frustum_center) / halfwidth;
  const double ndc_y = (near * Dot(v, axes.up) / depth - centre_y) / halfheight;
  const double gl_x = tile.left + 0.5 * (ndc_x + 1.0) * tile.width;
  const double gl_y = tile.bottom + 0.5 * (ndc_y + 1.0) * tile.height;  // from the bottom
  return Pixel{gl_x, frame_height - gl_y};
}

}  // namespace fetchscope
