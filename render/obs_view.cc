#include "render/obs_view.h"

#include <cmath>

namespace fetchscope {

bool ObsSetup::has(Layer layer) const {
  for (Layer l : layers) {
    if (l == layer) return true;
  }
  return false;
}

bool CameraMoves(const CameraSpec& spec, const mjModel* model) {
  if (spec.kind == CameraSpec::kTrack) return true;
  if (spec.kind != CameraSpec::kNamed) return false;
  const int id = mj_name2id(model, mjOBJ_CAMERA, spec.name.c_str());
  return id >= 0 && (model->cam_bodyid[id] != 0 || model->cam_mode[id] != mjCAMLIGHT_FIXED);
}

ObsCameraGeometry CameraGeometry(const mjvGLCamera& camera, int width, int height) {
  ObsCameraGeometry g;
  const double near = camera.frustum_near;
  const double half_height =
      0.5 * (static_cast<double>(camera.frustum_top) - camera.frustum_bottom);
  g.fovy = 2.0 * std::atan(half_height / near) * 180.0 / mjPI;
  // MuJoCo sets the frustum's left and right to the viewport's aspect: square pixels
  g.fy = 0.5 * height * near / half_height;
  g.fx = g.fy;
  g.cx = 0.5 * (width - 1);
  g.cy = 0.5 * (height - 1);
  // camera axes in the world: x = forward x up, y = up, z = -forward (MuJoCo's convention)
  const double f[3] = {camera.forward[0], camera.forward[1], camera.forward[2]};
  const double u[3] = {camera.up[0], camera.up[1], camera.up[2]};
  const double x[3] = {f[1] * u[2] - f[2] * u[1], f[2] * u[0] - f[0] * u[2],
                       f[0] * u[1] - f[1] * u[0]};
  const double mat[9] = {x[0], u[0], -f[0], x[1], u[1], -f[1], x[2], u[2], -f[2]};
  double quat[4];
  mju_mat2Quat(quat, mat);
  mju_normalize4(quat);
  for (int k = 0; k < 3; ++k) g.pose[k] = camera.pos[k];
  for (int k = 0; k < 4; ++k) g.pose[3 + k] = quat[k];
  return g;
}

ObsRenderer::ObsRenderer(GlContext& gl, mjModel* model, const ObsSetup& setup) : setup_(setup) {
  for (const ObsCamera& camera : setup_.cameras) {
    RenderOptions options;
    options.width = setup_.width;
    options.height = setup_.height;
    options.cameras = {camera.spec};
    options.overlays = setup_.overlays;
    options.msaa_samples = setup_.msaa_samples;
    options.readback = Readback::kSync;  // the images are needed at once
    renderers_.push_back(std::make_unique<Renderer>(gl, model, options));
  }
  images_.resize(renderers_.size());
}

ObsRenderer::~ObsRenderer() = default;

void ObsRenderer::SetLook(const LookDraw* look) {
  for (auto& r : renderers_) r->SetLook(look);
}

std::vector<std::string> ObsRenderer::camera_keys() const {
  std::vector<std::string> keys;
  for (const ObsCamera& c : setup_.cameras) keys.push_back(c.text);
  return keys;
}

void ObsRenderer::Render(const mjData* data, const FrameInfo& info) {
  for (size_t i = 0; i < renderers_.size(); ++i) {
    Renderer& r = *renderers_[i];
    ObsImages& out = images_[i];
    if (setup_.has(Layer::kRgb)) {
      out.rgb.resize(static_cast<size_t>(r.width()) * r.height() * 3);
      r.Render(data, info, out.rgb.data());
    }
    if (setup_.has(Layer::kDepth)) r.RenderDepthMetres(data, info, &out.depth);
    if (setup_.has(Layer::kSegmentation)) r.RenderSegmentIndices(data, info, &out.segmentation);
    out.geometry = CameraGeometry(r.view_camera(), r.width(), r.height());
  }
}

}  // namespace fetchscope
