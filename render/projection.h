// World points to pixels for a rendered frame: the same projection mjr_render applies to the
// scene's camera (mjv_updateScene fills it from the camera's fovy and pose).
#pragma once

#include <mujoco/mujoco.h>

#include <array>
#include <optional>

#include "render/vec.h"

namespace fetchscope {

/// The scene camera's unit axes in world coordinates, as mjr_render's view matrix uses them.
struct CameraAxes {
  std::array<double, 3> right;    ///< the image's +x direction
  std::array<double, 3> up;       ///< the image's upward direction (-y in pixels)
  std::array<double, 3> forward;  ///< into the image
};

/// The axes of the scene's camera after mjv_updateScene (the average of scene.camera[0] and
/// [1], as mjr_render uses).
CameraAxes SceneCameraAxes(const mjvScene& scene);

/// Where world point `point` (m) appears in a frame `frame_height` pixels tall whose camera
/// viewport is `tile` (OpenGL convention, bottom-left origin, as Renderer::tiles()), for the
/// scene's camera after mjv_updateScene (the average of scene.camera[0] and [1], as mjr_render
/// uses). Empty when the point lies behind the camera or on its plane.
std::optional<Pixel> ProjectToPixel(const mjvScene& scene, const mjrRect& tile, int frame_height,
                                    const std::array<double, 3>& point);

}  // namespace fetchscope
