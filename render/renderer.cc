#include "render/renderer.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <type_traits>

#include "base/errors.h"
#include "render/readback_gl.h"

namespace fetchscope {
namespace {

// GL enums (from glext.h; we do not include GL headers here beyond what MuJoCo needs).
constexpr unsigned kGlMaxTextureSize = 0x0D33;
constexpr unsigned kGlMaxViewportDims = 0x0D3A;
constexpr unsigned kGlMaxRenderbufferSize = 0x84E8;
constexpr unsigned kGlMaxSamples = 0x8D57;

// The largest frame side we accept even where GL allows more: beyond this the offscreen
// buffers alone take gigabytes.
constexpr int kMaxFrameSide = 16384;

constexpr int kMinSceneGeoms = 1000;  // Gymnasium's maxgeom

constexpr int kMaxMsaaSamples = 16;

using renderer_detail::Clock;
using renderer_detail::MsSince;

bool IsPowerOfTwoUpTo16(int n) { return n == 1 || n == 2 || n == 4 || n == 8 || n == 16; }

struct GlLimits {
  int max_side = kMaxFrameSide;
  int max_samples = 0;
};

GlLimits QueryLimits(const GlContext& gl) {
  using GetIntegervFn = void (*)(unsigned, int*);
  auto get = reinterpret_cast<GetIntegervFn>(gl.GetProcAddress("glGetIntegerv"));
  if (!get) throw RunError(gl.info().backend + ": glGetIntegerv is not available");
  GlLimits limits;
  int value[2] = {0, 0};
  for (unsigned name : {kGlMaxRenderbufferSize, kGlMaxTextureSize}) {
    value[0] = 0;
    get(name, value);
    if (value[0] > 0) limits.max_side = std::min(limits.max_side, value[0]);
  }
  value[0] = value[1] = 0;
  get(kGlMaxViewportDims, value);
  if (value[0] > 0) limits.max_side = std::min({limits.max_side, value[0], value[1]});
  get(kGlMaxSamples, &limits.max_samples);
  return limits;
}

// Columns and rows of the tile grid for n cameras: one row up to three, then near-square.
std::pair<int, int> TileGrid(int n) {
  const int cols = n <= 3 ? n : static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n))));
  return {cols, (n + cols - 1) / cols};
}

// Tiles of tile_w x tile_h for n cameras in a frame of frame_h rows (GL: bottom-left origin).
std::vector<mjrRect> TileFrame(int n, int tile_w, int tile_h, int frame_h) {
  const int cols = TileGrid(n).first;
  std::vector<mjrRect> tiles;
  for (int i = 0; i < n; ++i) {
    const int col = i % cols, row = i / cols;
    tiles.push_back(mjrRect{col * tile_w, frame_h - (row + 1) * tile_h, tile_w, tile_h});
  }
  return tiles;
}

// The tile's rectangle with row 0 at the top, as the read-back frame has it.
PixelRect TopDown(const mjrRect& t, int frame_h) {
  return PixelRect{t.left, frame_h - t.bottom - t.height, t.width, t.height};
}

// A tile's label: the camera as named (free cameras as "free").
std::string CameraLabel(const CameraSpec& spec) {
  if (spec.name.rfind("free:", 0) == 0) return "free";
  return spec.name;
}

}  // namespace

FrameDims FrameSize(const RenderOptions& options) {
  const int n = std::max<int>(1, static_cast<int>(options.cameras.size()));
  const auto [cols, rows] = TileGrid(n);
  return FrameDims{cols * options.width, rows * options.height};
}

std::string SoftwareRendererName(const std::string& gl_renderer) {
  std::string lower = gl_renderer;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  // Mesa's CPU drivers: gallium llvmpipe and softpipe, classic swrast (GL_RENDERER "Software
  // Rasterizer", or "Mesa OffScreen" from classic OSMesa), and OpenSWR ("SWR ...").
  for (const char* name : {"llvmpipe", "softpipe", "swrast"}) {
    if (lower.find(name) != std::string::npos) return name;
  }
  if (lower.find("software rasterizer") != std::string::npos ||
      lower.find("mesa offscreen") != std::string::npos) {
    return "swrast";
  }
  if (lower.rfind("swr", 0) == 0 || lower.find(" swr") != std::string::npos) return "SWR";
  return "";
}

int Renderer::ResolveMsaa(int max_samples) {
  const int requested = options_.msaa_samples;
  const int model_samples = model_->vis.quality.offsamples;
  int samples = 0;
  if (requested == kMsaaAuto) {
    const std::string software = SoftwareRendererName(gl_.info().renderer);
    if (!software.empty()) {
      samples = 0;
      msaa_reason_ = "auto: software renderer " + software;
    } else {
      samples = model_samples;
      msaa_reason_ = "auto: hardware renderer, the model's offsamples";
    }
  } else if (requested == kMsaaModel) {
    samples = model_samples;
    msaa_reason_ = "the model's offsamples";
  } else {
    samples = requested;
    msaa_reason_ = "requested";
  }
  if (max_samples > 0 &&
      samples > max_samples) {  // a driver without 4x multisampling still renders
    msaa_reason_ += "; " + std::to_string(samples) + " capped at the driver's maximum " +
                    std::to_string(max_samples);
    samples = max_samples;
  }
  return samples;
}

Renderer::Renderer(GlContext& gl, mjModel* model, const RenderOptions& options)
    : gl_(gl), model_(model), options_(options), frame_(FrameSize(options)) {
  if (options_.width <= 0 || options_.height <= 0) {
    throw UsageError("frame size " + std::to_string(options_.width) + "x" +
                     std::to_string(options_.height) + " is not positive; accepted: 1.." +
                     std::to_string(kMaxFrameSide) + " pixels per side");
  }
  const int w = frame_.width, h = frame_.height;
  const int msaa = options_.msaa_samples;
  if (msaa != kMsaaAuto && msaa != kMsaaModel && msaa != 0 && !IsPowerOfTwoUpTo16(msaa)) {
    throw UsageError("msaa " + std::to_string(msaa) +
                     " is not accepted; use auto, 0, 1, 2, 4, 8 or " +
                     std::to_string(kMaxMsaaSamples));
  }
  gl_.MakeCurrent();
  GlLimits limits = QueryLimits(gl_);
  if (w > limits.max_side || h > limits.max_side) {
    throw UsageError("frame size " + std::to_string(w) + "x" + std::to_string(h) +
                     " is too large; accepted: 1.." + std::to_string(limits.max_side) +
                     " pixels per side (limit of " + gl_.info().renderer + ")");
  }
  gl_.PrepareForMujoco();

  if (options_.cameras.empty()) {
    options_.cameras.push_back(CameraSpec{CameraSpec::kDefault, "default", DefaultFreeCamera()});
  }
  for (const CameraSpec& spec : options_.cameras) cameras_.push_back(ToMjvCamera(spec, model_));
  tiles_ = TileFrame(static_cast<int>(cameras_.size()), options_.width, options_.height, h);
  long covered = 0;
  for (const mjrRect& t : tiles_) covered += static_cast<long>(t.width) * t.height;
  tiles_leave_gaps_ = covered < static_cast<long>(w) * h;

  mjv_defaultOption(&option_);
  mjv_defaultPerturb(&perturb_);
  target_site_ = mj_name2id(model_, mjOBJ_SITE, "target0");
  contact_bodies_ = FindContactBodies(model_);
  grip_site_ = mj_name2id(model_, mjOBJ_SITE, "robot0:grip");

  // MuJoCo sizes its offscreen buffer from the model, and only in mjr_makeContext.
  mjVisual& vis = model_->vis;
  vis.global.offwidth = std::max(vis.global.offwidth, w);
  vis.global.offheight = std::max(vis.global.offheight, h);
  // offsamples too is read only there; it is put back afterwards, so that a later renderer's
  // kMsaaModel still means the model's own value
  msaa_samples_ = ResolveMsaa(limits.max_samples);
  const int model_samples = vis.quality.offsamples;
  vis.quality.offsamples = msaa_samples_;

  const int model_geoms = model_->ngeom + model_->nsite + model_->ntendon + model_->nskin;
  scene_.emplace(model_, std::max(kMinSceneGeoms, 2 * model_geoms) + kMaxOverlayGeoms);

  // Text stays about the same fraction of the frame: 100% font up to 600 rows.
  int fontscale = h <= 600 ? mjFONTSCALE_100 : h <= 1200 ? mjFONTSCALE_150 : mjFONTSCALE_200;
  context_.emplace(model_, fontscale);
  vis.quality.offsamples = model_samples;
  mjrContext* con = context_->get();
  if (con->offSamples != msaa_samples_) {  // llvmpipe, for one, makes 4 where 2 is asked
    msaa_reason_ += "; " + std::to_string(msaa_samples_) + " asked, the driver gave " +
                    std::to_string(con->offSamples);
    msaa_samples_ = con->offSamples;
  }
  mjr_setBuffer(mjFB_OFFSCREEN, con);
  if (con->currentBuffer != mjFB_OFFSCREEN || con->offWidth < w || con->offHeight < h) {
    throw RunError("MuJoCo could not make its " + std::to_string(w) + "x" + std::to_string(h) +
                   " offscreen buffer on " + gl_.info().renderer);
  }
  rgb_bottom_up_.resize(static_cast<size_t>(w) * h * 3);
  SetUpReadback();

  if (std::getenv("FETCHSCOPE_PROFILE")) {
    gl_finish_ = reinterpret_cast<void (*)()>(gl_.GetProcAddress("glFinish"));
    if (gl_finish_) profile_.emplace();
  }
}

Renderer::~Renderer() {
  if (profile_ && profile_->frames > 0) {
    const Profile& p = *profile_;
    const double n = static_cast<double>(p.frames);
    std::fprintf(stderr,
                 "fetchscope profile: %ld frames %dx%d msaa %d on %s, ms/frame: scene %.2f, "
                 "submit %.2f, raster %.2f, readback %.2f, flip %.2f\n",
                 p.frames, frame_.width, frame_.height, msaa_samples_, gl_.info().renderer.c_str(),
                 p.scene_ms / n, p.submit_ms / n, p.raster_ms / n, p.readback_ms / n,
                 p.flip_ms / n);
  }
  // mjr_freeContext deletes GL objects: our context must be the current one.
  try {
    gl_.MakeCurrent();
    if (async_) pbo_gl_->DeleteBuffers(kReadbackDepth, pbos_);
    FreeLookTextures();
  } catch (...) {
    // nothing better to do in a destructor; MuJoCo then frees into whatever is current
  }
}

void Renderer::Submit(const mjData* data, const FrameInfo& info, uint8_t* rgb) {
  Submit(data, info, rgb, nullptr, ShownScale{});
}

void Renderer::Submit(const mjData* data, const FrameInfo& frame_info, uint8_t* rgb, uint8_t* copy,
                      ShownScale copy_scale) {
  if (pending() >= pipeline_depth()) {
    throw RunError("internal error: Renderer::Submit with " + std::to_string(pending()) +
                   " frames pending; Collect first");
  }
  const FrameInfo& info = WithContacts(data, frame_info);
  Draw(data, info, /*overlays=*/true);
  if (!async_) {
    ReadRgb(rgb);
    FinishFrame({rgb, -1, {}, copy, copy_scale}, info);
    PendingFrame& p = PushPending();
    p.rgb = rgb;
    p.slot = -1;
    return;
  }
  const int slot = next_slot_;
  next_slot_ = (next_slot_ + 1) % kReadbackDepth;
  StartAsyncRead(slot);
  PendingFrame& p = PushPending();
  p.rgb = rgb;
  p.slot = slot;
  p.info = info;  // copied into the slot's own strings and vectors: their memory is reused
  p.copy = copy;
  p.copy_scale = copy_scale;
}

Renderer::PendingFrame& Renderer::PushPending() {
  PendingFrame& p = pending_[(pending_head_ + pending_count_) % kReadbackDepth];
  ++pending_count_;
  return p;
}

void Renderer::FinishFrame(const PendingFrame& frame, const FrameInfo& info) const {
  CpuLap lap;
  if (frame.copy) {
    std::memcpy(frame.copy, frame.rgb, static_cast<size_t>(frame_.width) * frame_.height * 3);
    lap.Into(&cpu_.copy);
    DrawText2d(info, frame.copy, frame.copy_scale);
  }
  DrawText2d(info, frame.rgb);
  lap.Into(&cpu_.hud);
}

void Renderer::DiscardPending() { pending_count_ = 0; }

namespace {

// Removes the geoms of mocap bodies from `scene` (the crosshair is a mocap target, not an object;
// Gymnasium draws its bars at alpha 0.1) and renumbers the segmentation ids, which MuJoCo draws
// as colours, to the remaining geoms' places.
void DropMocapGeoms(const mjModel* model, mjvScene* scene) {
  int kept = 0;
  for (int i = 0; i < scene->ngeom; ++i) {
    const mjvGeom& g = scene->geoms[i];
    const bool mocap = g.objtype == mjOBJ_GEOM && g.objid >= 0 && g.objid < model->ngeom &&
                       model->body_mocapid[model->geom_bodyid[g.objid]] >= 0;
    if (mocap) continue;
    scene->geoms[kept] = g;
    if (scene->geoms[kept].segid >= 0) scene->geoms[kept].segid = kept;
    ++kept;
  }
  scene->ngeom = kept;
}

}  // namespace

void Renderer::Draw(const mjData* data, const FrameInfo& info, bool overlays) {
  CpuLap lap;
  gl_.MakeCurrent();
  mjvScene* scene = scene_->get();
  mjrContext* con = context_->get();
  mjr_setBuffer(mjFB_OFFSCREEN, con);
  const mjrRect frame{0, 0, frame_.width, frame_.height};
  if (tiles_leave_gaps_) mjr_rectangle(frame, 0, 0, 0, 1);  // empty grid cells stay black

  // mjv_updateScene takes a non-const mjData but only reads it (positions, orientations,
  // camera poses); the simulation state is left as it was.
  mjData* readonly = const_cast<mjData*>(data);
  for (mjvCamera& cam : cameras_) {
    // MuJoCo's tracking camera eases its lookat 20% of the way to the body per update, so a
    // frame would depend on the frames before it; centring it on the body each frame keeps
    // frames reproducible (golden images, re-renders) and the gripper in the middle.
    if (cam.type == mjCAMERA_TRACKING) {
      for (int k = 0; k < 3; ++k) cam.lookat[k] = data->subtree_com[3 * cam.trackbodyid + k];
    }
  }
  double scene_ms = 0, submit_ms = 0;
  for (size_t i = 0; i < cameras_.size(); ++i) {
    const auto scene_start = Clock::now();
    if (i == 0) {
      mjv_updateScene(model_, readonly, &option_, &perturb_, &cameras_[0], mjCAT_ALL, scene);
      bool placed = PlaceSiteGeom(scene, target_site_, info.goal);
      if (drop_mocap_) DropMocapGeoms(model_, scene);
      if (look_) ApplyLook(data, scene);
      if (overlays) {
        std::array<double, 3> grip = info.achieved;
        if (grip_site_ >= 0) {
          for (int k = 0; k < 3; ++k) grip[k] = data->site_xpos[3 * grip_site_ + k];
        }
        if (options_.overlays.trail) trail_.Add(info.step, info.achieved);
        AddOverlayGeoms(options_.overlays, info, grip, trail_, !placed, scene);
        if (options_.extra_geoms) options_.extra_geoms(scene);
      } else if (!placed) {
        AddOverlayGeoms(ParseOverlays("none"), info, {}, trail_, true, scene);
      }
    } else {
      mjv_updateCamera(model_, readonly, &cameras_[i], scene);  // same geoms, next view
    }
    if (look_) JitterView(i, scene);
    const auto submit_start = Clock::now();
    scene_ms += std::chrono::duration<double, std::milli>(submit_start - scene_start).count();
    lap.Into(&cpu_.scene);
    mjr_render(tiles_[i], scene, con);
    submit_ms += MsSince(submit_start);
    lap.Into(&cpu_.gl);
  }
  const auto hud_start = Clock::now();
  if (profile_) {
    // GL queues the drawing; finishing here separates rasterisation from the readback
    // (only while profiling: it costs the overlap of the two)
    const auto raster_start = Clock::now();
    submit_ms += std::chrono::duration<double, std::milli>(raster_start - hud_start).count();
    gl_finish_();
    lap.Into(&cpu_.gl);
    profile_->raster_ms += MsSince(raster_start);
    profile_->scene_ms += scene_ms;
    profile_->submit_ms += submit_ms;
    ++profile_->frames;
  }
}

void Renderer::SetView(const std::vector<CameraSpec>& cameras, const OverlaySet& overlays) {
  if (cameras.size() != cameras_.size()) {
    throw UsageError(std::to_string(cameras.size()) + " camera(s) for a renderer of " +
                     std::to_string(cameras_.size()) + " view(s)");
  }
  std::vector<mjvCamera> made;
  for (const CameraSpec& spec : cameras) made.push_back(ToMjvCamera(spec, model_));
  cameras_ = std::move(made);
  options_.cameras = cameras;
  options_.overlays = overlays;
  UpdateViewJitter();
}

void Renderer::SetTrail(const std::vector<std::array<double, 3>>& points) {
  trail_.Clear();
  for (size_t i = 0; i < points.size(); ++i) trail_.Add(static_cast<int>(i), points[i]);
}

void Renderer::Render(const mjData* data, const FrameInfo& frame_info, uint8_t* rgb) {
  const FrameInfo& info = WithContacts(data, frame_info);
  Draw(data, info, /*overlays=*/true);
  ReadRgb(rgb);
  CpuLap lap;
  DrawText2d(info, rgb);
  lap.Into(&cpu_.hud);
}

const FrameInfo& Renderer::WithContacts(const mjData* data, const FrameInfo& info) {
  if (!options_.overlays.contacts) return info;
  contact_info_ = info;
  SetContactInfo(ReadContacts(model_, data, contact_bodies_), contact_bodies_.object >= 0,
                 &contact_info_);
  return contact_info_;
}

void Renderer::DrawText2d(const FrameInfo& info, uint8_t* rgb, ShownScale scale) const {
  const OverlaySet& o = options_.overlays;
  std::optional<PixelRect> hud_box;
  size_t hud_tile = 0;
  if (o.hud) {
    // the tile whose corner is the frame's corner at hud_position (tile 0 where a grid leaves
    // that cell empty): the HUD never crosses a tile boundary
    const HudPosition pos = options_.hud_position;
    const bool right = pos == HudPosition::kTopRight || pos == HudPosition::kBottomRight;
    const bool bottom = pos == HudPosition::kBottomLeft || pos == HudPosition::kBottomRight;
    const int cx = right ? frame_.width - 1 : 0, cy = bottom ? frame_.height - 1 : 0;
    for (size_t i = 0; i < tiles_.size(); ++i) {
      const PixelRect t = TopDown(tiles_[i], frame_.height);
      if (cx >= t.x && cx < t.x + t.width && cy >= t.y && cy < t.y + t.height) hud_tile = i;
    }
    HudText& hud = hud_;  // formatted into the same strings every frame: no allocation
    FormatHud(info, o, &hud);
    const PixelRect tile = TopDown(tiles_[hud_tile], frame_.height);
    hud_box = PlaceHud(hud, tile, pos, scale);
    DrawHud(rgb, frame_.width, frame_.height, tile, hud, pos, options_.hud_opacity, scale);
  }
  if (o.contacts) {  // the fingers' forces, in the HUD's tile (the first view without a HUD)
    DrawContactLabel(rgb, frame_.width, frame_.height, TopDown(tiles_[hud_tile], frame_.height),
                     info, options_.hud_opacity, hud_box, scale);
  }
  if (o.labels && tiles_.size() > 1) {
    for (size_t i = 0; i < tiles_.size(); ++i) {
      DrawTileLabel(rgb, frame_.width, frame_.height, TopDown(tiles_[i], frame_.height),
                    CameraLabel(options_.cameras[i]), options_.hud_opacity,
                    i == hud_tile ? hud_box : std::nullopt, scale);
    }
  }
}

}  // namespace fetchscope
