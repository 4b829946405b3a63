// Camera images as observations (--obs-camera, --obs-size, --obs-layers, parsed in
// cli/obs_options.h): which cameras a pixel dataset or a policy sees, and the renderer that draws
// them one camera at a time, each exactly as `fetchscope render --camera CAMERA --width W --height
// H --overlay none` draws that camera alone, with the camera's intrinsics and world pose
// (docs/guide/datasets.md, "Pixel datasets").
#pragma once

#include <mujoco/mujoco.h>

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "render/camera.h"
#include "render/gl_context.h"
#include "render/overlay.h"
#include "render/renderer.h"

namespace fetchscope {

/// One observed camera: its key in the dataset and what it is.
struct ObsCamera {
  std::string name;  ///< the dataset key (NAME of --obs-camera NAME=CAMERA)
  CameraSpec spec;   ///< the camera, as one --camera value
  std::string text;  ///< CameraText(spec): the --camera value that renders it
  /// whether its pose changes with the state (a track camera, or a model camera on a moving
  /// body such as gripper_camera_rgb): then its pose is stored per step, else once
  bool moving = false;
};

/// The images each step gives, as the command resolved them.
struct ObsSetup {
  std::vector<ObsCamera> cameras;               ///< in the order given; none: no images
  int width = 128;                              ///< pixels of each image
  int height = 128;                             ///< pixels of each image
  std::vector<Layer> layers = {Layer::kRgb};    ///< in the order rgb, depth, segmentation
  OverlaySet overlays = ParseOverlays("none");  ///< --obs-overlay (none by default)
  std::string overlay_text = "none";            ///< --obs-overlay as given
  int msaa_samples = kMsaaAuto;                 ///< as the command's --msaa
  bool enabled() const { return !cameras.empty(); }
  bool has(Layer layer) const;
};

/// Whether `spec`'s pose changes with the state on `model`: a track camera, or a model camera
/// on a body other than the world (gripper_camera_rgb, head_camera_rgb).
bool CameraMoves(const CameraSpec& spec, const mjModel* model);

/// A camera's pinhole model and pose in one image, from the GL camera MuJoCo drew it with.
/// Conventions (docs/guide/datasets.md): fovy is vertical, in degrees; pixel (u, v) has u to the
/// right and v down, pixel centres at integers, so cx = (W-1)/2 and cy = (H-1)/2 for MuJoCo's
/// centred frustum; fx = fy (square pixels). The pose is the camera frame in the world,
/// (x, y, z, qw, qx, qy, qz), in MuJoCo's camera convention: it looks along its -z with +y up.
/// OpenCV's camera frame (looking along +z, +y down) is this frame turned by pi about x.
struct ObsCameraGeometry {
  double fovy = 0;                  ///< degrees
  double fx = 0, fy = 0;            ///< focal lengths, pixels
  double cx = 0, cy = 0;            ///< principal point, pixels
  std::array<double, 7> pose = {};  ///< position (m) and unit quaternion (w, x, y, z)
};

/// The geometry of an image of `width` x `height` drawn with `camera`.
ObsCameraGeometry CameraGeometry(const mjvGLCamera& camera, int width, int height);

/// The images of one camera at one step (only the layers asked for are filled).
struct ObsImages {
  std::vector<uint8_t> rgb;           ///< height x width x 3, row 0 = top
  std::vector<float> depth;           ///< height x width metres along the view axis, 0 = none
  std::vector<int32_t> segmentation;  ///< height x width object indices, -1 = none
  ObsCameraGeometry geometry;         ///< the camera in this image
};

/// Draws the observed cameras of a model on one GL context (one renderer per camera).
class ObsRenderer {
 public:
  /// Throws UsageError as Renderer does (a size beyond the GL's limits).
  ObsRenderer(GlContext& gl, mjModel* model, const ObsSetup& setup);
  ~ObsRenderer();
  ObsRenderer(const ObsRenderer&) = delete;
  ObsRenderer& operator=(const ObsRenderer&) = delete;

  /// Renders every camera's layers of the current state of `data` (overlays as setup.overlays;
  /// the goal marker where `info` puts it).
  void Render(const mjData* data, const FrameInfo& info);
  /// Draws every later Render with `look` (Renderer::SetLook; nullptr: the plain look). Each
  /// camera's jitter is the look's entry for its ObsCamera::text; the images' geometry follows it.
  void SetLook(const LookDraw* look);
  /// The --camera texts of the observed cameras: DrawLook's camera keys.
  std::vector<std::string> camera_keys() const;
  /// Camera i's renderer (its texture_uploads(), for one).
  const Renderer& renderer(size_t i) const { return *renderers_.at(i); }
  /// Camera i's images of the last Render.
  const ObsImages& images(size_t i) const { return images_.at(i); }
  size_t cameras() const { return images_.size(); }

 private:
  ObsSetup setup_;
  std::vector<std::unique_ptr<Renderer>> renderers_;
  std::vector<ObsImages> images_;
};

}  // namespace fetchscope
