// The renderer's randomized look (Renderer::SetLook, render/look.h): scene edits after
// mjv_updateScene and mjv_updateCamera, and the table and floor textures it uploads itself.
//
// MuJoCo 2.2.2 draws a geom's 2D texture from mjvGeom::texid: it binds mjrContext::texture[texid]
// when textureType[texid] is mjTEXTURE_2D and maps it with object-plane texture coordinates
// scaled by mjvGeom::texrepeat (times the geom's size when texuniform is set). The renderer
// keeps its two textures in the slots just past the model's (ntexture and ntexture + 1), which
// mjr_freeContext does not delete: ~Renderer does.
#include <cmath>
#include <string>

#include "base/errors.h"
#include "render/renderer.h"

namespace fetchscope {
namespace {

// GL enums (glext.h values).
constexpr unsigned kGlTexture2d = 0x0DE1;
constexpr unsigned kGlRgb = 0x1907;
constexpr unsigned kGlUnsignedByte = 0x1401;
constexpr unsigned kGlTextureMagFilter = 0x2800;
constexpr unsigned kGlTextureMinFilter = 0x2801;
constexpr unsigned kGlTextureWrapS = 0x2802;
constexpr unsigned kGlTextureWrapT = 0x2803;
constexpr int kGlLinear = 0x2601;
constexpr int kGlLinearMipmapLinear = 0x2703;
constexpr int kGlRepeat = 0x2901;
constexpr unsigned kGlUnpackAlignment = 0x0CF5;

// Texels per side of a look texture: one pattern tile (a checker tile holds 2 x 2 cells).
constexpr int kTextureSide = 64;

const char* const kSurfaces[2] = {"table", "floor"};

bool StartsWith(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

}  // namespace

void Renderer::FindLookParts() {
  if (!geom_part_.empty() || model_->ngeom == 0) return;
  geom_part_.assign(model_->ngeom, "");
  geom_surface_.assign(model_->ngeom, -1);
  const int table = mj_name2id(model_, mjOBJ_BODY, "table0");
  for (int g = 0; g < model_->ngeom; ++g) {
    const char* gname = mj_id2name(model_, mjOBJ_GEOM, g);
    const std::string geom = gname ? gname : "";
    const int body = model_->geom_bodyid[g];
    const char* bname = mj_id2name(model_, mjOBJ_BODY, body);
    const std::string body_name = bname ? bname : "";
    if (geom == "object0") {
      geom_part_[g] = "object";
    } else if (body == table && table >= 0) {
      geom_part_[g] = "table";
      geom_surface_[g] = 0;
    } else if (geom == "floor0") {
      geom_part_[g] = "floor";
      geom_surface_[g] = 1;
    } else if (StartsWith(body_name, "robot0:")) {
      geom_part_[g] = body_name;
    }
  }
}

void Renderer::UpdateViewJitter() {
  view_jitter_.assign(options_.cameras.size(), nullptr);
  if (!look_) return;
  for (size_t i = 0; i < options_.cameras.size(); ++i) {
    const auto it = look_->cameras.find(CameraText(options_.cameras[i]));
    if (it != look_->cameras.end()) view_jitter_[i] = &it->second;
  }
}

std::vector<std::string> Renderer::camera_keys() const {
  std::vector<std::string> keys;
  for (const CameraSpec& spec : options_.cameras) keys.push_back(CameraText(spec));
  return keys;
}

void Renderer::SetLook(const LookDraw* look) {
  if (!look) {
    look_.reset();
    view_jitter_.clear();
    return;
  }
  look_ = *look;
  FindLookParts();
  UpdateViewJitter();
  for (int s = 0; s < 2; ++s) {
    const auto it = look_->textures_by_surface.find(kSurfaces[s]);
    if (it != look_->textures_by_surface.end() && !(uploaded_[s] && *uploaded_[s] == it->second)) {
      UploadLookTexture(s, it->second);
    }
  }
}

void Renderer::UploadLookTexture(int surface, const SurfaceTexture& texture) {
  gl_.MakeCurrent();
  mjrContext* con = context_->get();
  const int slot = con->ntexture + surface;
  const int max_slots = static_cast<int>(sizeof(con->texture) / sizeof(con->texture[0]));
  if (slot >= max_slots) {
    throw RunError("the model has " + std::to_string(con->ntexture) +
                   " textures: no room for the randomized look's table and floor textures");
  }
  using GenFn = void (*)(int, unsigned*);
  using BindFn = void (*)(unsigned, unsigned);
  using ParamFn = void (*)(unsigned, unsigned, int);
  using ImageFn = void (*)(unsigned, int, int, int, int, int, unsigned, unsigned, const void*);
  using StoreFn = void (*)(unsigned, int);
  using MipmapFn = void (*)(unsigned);
  auto gen = reinterpret_cast<GenFn>(gl_.GetProcAddress("glGenTextures"));
  auto bind = reinterpret_cast<BindFn>(gl_.GetProcAddress("glBindTexture"));
  auto param = reinterpret_cast<ParamFn>(gl_.GetProcAddress("glTexParameteri"));
  auto image = reinterpret_cast<ImageFn>(gl_.GetProcAddress("glTexImage2D"));
  auto store = reinterpret_cast<StoreFn>(gl_.GetProcAddress("glPixelStorei"));
  auto mipmap = reinterpret_cast<MipmapFn>(gl_.GetProcAddress("glGenerateMipmap"));
  if (!gen || !bind || !param || !image || !store) {
    throw RunError(gl_.info().backend + ": the GL texture functions are not available");
  }
  if (look_textures_[surface] == 0) gen(1, &look_textures_[surface]);
  const std::vector<uint8_t> pixels = TexturePixels(texture, kTextureSide);
  bind(kGlTexture2d, look_textures_[surface]);
  store(kGlUnpackAlignment, 1);
  image(kGlTexture2d, 0, static_cast<int>(kGlRgb), kTextureSide, kTextureSide, 0, kGlRgb,
        kGlUnsignedByte, pixels.data());
  param(kGlTexture2d, kGlTextureWrapS, kGlRepeat);
  param(kGlTexture2d, kGlTextureWrapT, kGlRepeat);
  param(kGlTexture2d, kGlTextureMagFilter, kGlLinear);
  if (mipmap) mipmap(kGlTexture2d);
  param(kGlTexture2d, kGlTextureMinFilter, mipmap ? kGlLinearMipmapLinear : kGlLinear);
  bind(kGlTexture2d, 0);
  con->texture[slot] = look_textures_[surface];
  con->textureType[slot] = mjTEXTURE_2D;
  uploaded_[surface] = texture;
  ++texture_uploads_;
}

void Renderer::FreeLookTextures() noexcept {
  using DeleteFn = void (*)(int, const unsigned*);
  for (unsigned& name : look_textures_) {
    if (name == 0) continue;
    auto del = reinterpret_cast<DeleteFn>(gl_.GetProcAddress("glDeleteTextures"));
    if (del) del(1, &name);
    name = 0;
  }
}

void Renderer::ApplyLook(const mjData* data, mjvScene* scene) const {
  const LookDraw& look = *look_;
  const int ntexture = context_->get()->ntexture;
  for (int i = 0; i < scene->ngeom; ++i) {
    mjvGeom& g = scene->geoms[i];
    if (g.objtype != mjOBJ_GEOM || g.objid < 0 || g.objid >= model_->ngeom) continue;
    const std::string& part = geom_part_[g.objid];
    if (part.empty()) continue;
    const auto colour = look.colors_by_part.find(part);
    if (colour != look.colors_by_part.end()) {
      for (int k = 0; k < 3; ++k) g.rgba[k] = static_cast<float>(colour->second[k]);
      g.rgba[3] *= static_cast<float>(colour->second[3]);
    }
    const int s = geom_surface_[g.objid];
    if (s < 0 || !uploaded_[s]) continue;
    const auto tex = look.textures_by_surface.find(kSurfaces[s]);
    if (tex == look.textures_by_surface.end()) continue;
    // the texture shows its own colours (times the part's colour when colours are drawn)
    if (colour == look.colors_by_part.end()) g.rgba[0] = g.rgba[1] = g.rgba[2] = 1.0f;
    g.texid = ntexture + s;
    g.texuniform = 1;
    // with texuniform, MuJoCo repeats texrepeat/2 tiles per metre of the surface
    g.texrepeat[0] = g.texrepeat[1] = static_cast<float>(2.0 * tex->second.scale);
  }
  // mjv_updateScene lists the headlight (if active) first, then the active model lights in order
  int model_light = -1;
  for (int i = 0; i < scene->nlight; ++i) {
    mjvLight& l = scene->lights[i];
    if (l.headlight) continue;
    do {
      ++model_light;
    } while (model_light < model_->nlight && !model_->light_active[model_light]);
    if (model_light >= model_->nlight) break;
    const auto it = look.lights.find(model_light);
    if (it == look.lights.end()) continue;
    const LightLook& d = it->second;
    const int body = model_->light_bodyid[model_light];
    const mjtNum* xpos = data->xpos + 3 * body;
    const mjtNum* xmat = data->xmat + 9 * body;
    for (int r = 0; r < 3; ++r) {  // the body frame to the world, as for a fixed light
      if (d.pos) {
        double p = xpos[r];
        for (int c = 0; c < 3; ++c) p += xmat[3 * r + c] * (*d.pos)[c];
        l.pos[r] = static_cast<float>(p);
      }
      if (d.dir) {
        double v = 0;
        for (int c = 0; c < 3; ++c) v += xmat[3 * r + c] * (*d.dir)[c];
        l.dir[r] = static_cast<float>(v);
      }
      if (d.ambient) l.ambient[r] = static_cast<float>((*d.ambient)[r]);
      if (d.diffuse) l.diffuse[r] = static_cast<float>((*d.diffuse)[r]);
      if (d.specular) l.specular[r] = static_cast<float>((*d.specular)[r]);
    }
  }
}

void Renderer::JitterView(size_t view, mjvScene* scene) const {
  if (view >= view_jitter_.size() || !view_jitter_[view]) return;
  const CameraJitter& j = *view_jitter_[view];
  mjvGLCamera* eyes = scene->camera;  // left and right eye: same forward and up
  double f[3], u[3], head[3];
  for (int k = 0; k < 3; ++k) {
    f[k] = eyes[0].forward[k];
    u[k] = eyes[0].up[k];
    head[k] = 0.5 * (eyes[0].pos[k] + eyes[1].pos[k]);
  }
  const double x[3] = {f[1] * u[2] - f[2] * u[1], f[2] * u[0] - f[0] * u[2],
                       f[0] * u[1] - f[1] * u[0]};
  // the rotation's axis in the world: camera x = right, y = up, z = -forward
  double axis[3];
  for (int k = 0; k < 3; ++k) axis[k] = x[k] * j.drot[0] + u[k] * j.drot[1] - f[k] * j.drot[2];
  const double angle = mju_normalize3(axis);
  double quat[4] = {1, 0, 0, 0};
  if (angle > 0) mju_axisAngle2Quat(quat, axis, angle);
  for (int e = 0; e < 2; ++e) {
    mjvGLCamera& c = eyes[e];
    double offset[3], turned[3], fw[3], up[3];
    for (int k = 0; k < 3; ++k) offset[k] = c.pos[k] - head[k];
    mju_rotVecQuat(turned, offset, quat);
    mju_rotVecQuat(fw, f, quat);
    mju_rotVecQuat(up, u, quat);
    for (int k = 0; k < 3; ++k) {
      c.pos[k] = static_cast<float>(head[k] + j.dpos[k] + turned[k]);
      c.forward[k] = static_cast<float>(fw[k]);
      c.up[k] = static_cast<float>(up[k]);
    }
    if (j.fovy) {
      const double half = 0.5 * (static_cast<double>(c.frustum_top) - c.frustum_bottom);
      const double old_tan = half / c.frustum_near;
      const double scale = std::tan(0.5 * *j.fovy * mjPI / 180.0) / old_tan;
      c.frustum_top = static_cast<float>(c.frustum_top * scale);
      c.frustum_bottom = static_cast<float>(c.frustum_bottom * scale);
      c.frustum_center = static_cast<float>(c.frustum_center * scale);
    }
  }
}

}  // namespace fetchscope
