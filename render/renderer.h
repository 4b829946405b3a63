// Renders Fetch frames off-screen with MuJoCo: one or more cameras tiled into one frame,
// the goal marker where Gymnasium puts it, overlays, and a single readback per frame.
#pragma once

#include <mujoco/mujoco.h>

#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "base/cpu_clock.h"
#include "render/camera.h"
#include "render/gl_context.h"
#include "render/look.h"
#include "render/mjr_handles.h"
#include "render/overlay.h"

namespace fetchscope {

/// Which image RenderLayer produces.
enum class Layer {
  kRgb,           ///< width*height*3 bytes, as Render
  kDepth,         ///< width*height uint16 (host byte order): mm along the view axis; 0 = none
                  ///< (sky, or farther than 65.535 m)
  kSegmentation,  ///< width*height*3 bytes: a fixed colour per object (see SegmentationColor),
                  ///< black = none; Renderer::segmentation_legend() names the colours
};

/// The colour of segmentation object `index` (see SegmentObject): kSegmentationColors colours
/// chosen to be far apart (CIEDE2000 at least 15.9 between any two of the first 36, 14.1 among
/// all, and from the black background), then golden-angle hues at two brightnesses, which are
/// not guaranteed to stay clear of each other.
/// Deterministic: an object has the same colour in every frame, camera and run.
std::array<uint8_t, 3> SegmentationColor(int index);
/// How many colours SegmentationColor takes from its far-apart palette.
inline constexpr int kSegmentationColors = 48;

/// One object of the segmentation layer: a body (all its geoms share its colour) or a site.
struct SegmentObject {
  int index = 0;                   ///< palette index: body id, or nbody + site id for a site
  std::array<uint8_t, 3> color{};  ///< SegmentationColor(index)
  std::string body;                ///< the body's name (the site's body for a site)
  std::vector<std::string> geoms;  ///< the body's geoms seen in the frame ("geom N" if unnamed)
  std::string site;                ///< the site's name; empty for a body
  long pixels = 0;                 ///< pixels of this colour in the frame
};

/// What the segmentation layer shows at one pixel (Renderer::Pick): a body's geom, or a site.
struct PickedObject {
  std::string body;                ///< the body's name ("body N" if unnamed)
  int body_id = -1;                ///< its id in the model
  std::string geom;                ///< the geom's name ("geom N"); empty for a site
  std::string site;                ///< the site's name; empty for a geom
  std::array<uint8_t, 3> color{};  ///< its colour in the segmentation layer (SegmentationColor)
};

/// RenderOptions::msaa_samples: the model's offsamples (4 in the Fetch models, as Gymnasium).
inline constexpr int kMsaaModel = -1;
/// RenderOptions::msaa_samples: kMsaaModel on hardware GL, 0 on a software rasterizer, where
/// multisampling costs about half the frame time.
inline constexpr int kMsaaAuto = -2;

/// How a renderer reads frames back from the GL (RenderOptions::readback).
enum class Readback {
  kAuto,   ///< kAsync on hardware GL, kSync on a software rasterizer (where it measured no faster)
  kSync,   ///< mjr_readPixels: the CPU waits for the GPU every frame
  kAsync,  ///< pixel buffer objects, kReadbackDepth frames in flight (Submit/Collect)
};
/// Frames in flight with Readback::kAsync: the GPU draws frame k+1 and k+2 while frame k
/// comes back.
inline constexpr int kReadbackDepth = 3;

/// Tile size, cameras and overlays of a renderer.
struct RenderOptions {
  int width = 480;                  ///< pixels of each camera's tile (see FrameSize)
  int height = 480;                 ///< pixels of each camera's tile
  std::vector<CameraSpec> cameras;  ///< tiled left to right (grid from 4 on); empty = default
  OverlaySet overlays;              ///< drawn by Render (not by the depth/segmentation layers)
  HudPosition hud_position = HudPosition::kTopLeft;  ///< corner of the frame the HUD sits in
  double hud_opacity = 0.6;             ///< HUD and tile-label box: 0 = none .. 1 = opaque black
  int msaa_samples = kMsaaModel;        ///< samples per pixel: 0 (off), 1, 2, 4, 8, 16, kMsaaModel
                                        ///< or kMsaaAuto; capped at the driver's maximum
  Readback readback = Readback::kAuto;  ///< how Submit/Collect read frames back
  /// Optional: adds more decor geoms after the overlays (the anatomy card's markers), in Render
  /// only; must stay within scene->maxgeom (kMaxOverlayGeoms are free when overlays are off).
  std::function<void(mjvScene*)> extra_geoms;
  /// Whether the segmentation layer shows the mocap body (robot0:mocap's crosshair: 2 m bars
  /// that Gymnasium draws at alpha 0.1). Off: the mask shows what lies behind it instead.
  bool segment_mocap = false;
};

/// Width and height of a whole frame.
struct FrameDims {
  int width = 0;   ///< pixels
  int height = 0;  ///< pixels
};

/// The frame size for `options`: each camera gets a width x height tile; up to three cameras
/// sit in one row, from four on a near-square grid (columns = ceil(sqrt(n))). Every frame
/// buffer, video and PNG of a renderer has this size.
FrameDims FrameSize(const RenderOptions& options);

/// The CPU rasterizer a GL_RENDERER string names ("llvmpipe", "softpipe", "swrast", "SWR",
/// Mesa's classic "Software Rasterizer"), or "" for hardware GL.
std::string SoftwareRendererName(const std::string& gl_renderer);

/// Off-screen renderer for one model on one GL context (one per thread).
class Renderer {
 public:
  /// Makes the MuJoCo scene and context on `gl` (which must outlive the renderer and is made
  /// current here) for `model`. Raises model->vis.global.offwidth/offheight to at least the
  /// frame size (hence the non-const model). Throws UsageError for a frame size that is not
  /// positive or exceeds the GL limits (the message gives the accepted range), for a camera
  /// the model lacks, or for an msaa_samples value not listed on RenderOptions; RunError when
  /// MuJoCo cannot make its offscreen buffer. With FETCHSCOPE_PROFILE set in the environment, the
  /// destructor prints a per-phase time breakdown to stderr (see docs/guide/recording.md: "Where a
  /// frame's time goes").
  Renderer(GlContext& gl, mjModel* model, const RenderOptions& options);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Renders the current state of `data` into `rgb` (width*height*3 bytes, row 0 = top).
  /// Reads `data` only: the goal marker is placed by moving the target0 site's scene geom to
  /// info.goal after mjv_updateScene (Gymnasium moves the site and runs mj_forward instead).
  void Render(const mjData* data, const FrameInfo& info, uint8_t* rgb);

  /// Pipelined rendering: draws the current state of `data` and starts reading it back into
  /// `rgb` (width*height*3 bytes, row 0 = top), which stays untouched until the frame is
  /// collected. With asynchronous readback up to pipeline_depth() frames are in flight; with
  /// synchronous readback the frame is complete on return but still counts as pending until
  /// collected. The pixels equal Render's. Call Collect when pending() == pipeline_depth().
  void Submit(const mjData* data, const FrameInfo& info, uint8_t* rgb);
  /// Submit, and when collected also writes `copy` (as many bytes as `rgb`): the same frame with
  /// its HUD and tile labels sized for a view shown at `copy_scale` (a GIF scaled down from the
  /// frame, render/overlay.h ShownScale).
  void Submit(const mjData* data, const FrameInfo& info, uint8_t* rgb, uint8_t* copy,
              ShownScale copy_scale);
  /// Completes the oldest pending frame (waits for the GPU if needed) and returns the `rgb`
  /// it was submitted with; nullptr when nothing is pending.
  uint8_t* Collect();
  /// Drops every pending frame without copying it (after a failure).
  void DiscardPending();
  int pending() const { return pending_count_; }
  int pipeline_depth() const { return async_ ? kReadbackDepth : 1; }
  /// Whether frames come back through pixel buffer objects, and why.
  bool async_readback() const { return async_; }
  const std::string& readback_reason() const { return readback_reason_; }

  /// Renders `layer` into `out` (resized; row 0 = top). Depth and segmentation show the scene
  /// with the goal marker but without overlays.
  void RenderLayer(const mjData* data, const FrameInfo& info, Layer layer,
                   std::vector<uint8_t>* out);

  /// The depth layer as numbers: metres along the view axis (float32, row 0 = top), 0 where
  /// nothing is hit; RenderLayer(kDepth)'s millimetres are these rounded (to 65.535 m).
  void RenderDepthMetres(const mjData* data, const FrameInfo& info, std::vector<float>* out);

  /// The segmentation layer as object indices (row 0 = top): the body id of a body's geom,
  /// model->nbody + site id for a site (the goal marker), -1 for nothing; the objects
  /// RenderLayer(kSegmentation) colours with SegmentationColor(index).
  void RenderSegmentIndices(const mjData* data, const FrameInfo& info, std::vector<int32_t>* out);

  /// The GL camera the last view of the last frame was drawn with (position, forward, up and
  /// frustum): the mean of the scene's left and right eye, as mjr_render draws a mono frame
  /// (each eye sits half the model's ipd aside). The pose and intrinsics of a one-camera frame.
  mjvGLCamera view_camera() const {
    return mjv_averageCamera(&scene_->get()->camera[0], &scene_->get()->camera[1]);
  }

  /// What the segmentation layer of `data` shows at pixel (x, y) of the frame (row 0 = top):
  /// the geom or site there and its body; nullopt for the background, an overlay or a pixel
  /// outside the frame. Renders the layer (as RenderLayer does) to find it.
  std::optional<PickedObject> Pick(const mjData* data, const FrameInfo& info, int x, int y);

  /// Points the views at `cameras` (as many as the renderer was made with: the tiles stay) and
  /// draws `overlays` from the next frame on (serve's live view, which moves both per frame).
  /// Throws UsageError as the constructor does for a camera the model lacks, or for another
  /// number of cameras.
  void SetView(const std::vector<CameraSpec>& cameras, const OverlaySet& overlays);

  /// The trail overlay's points before the next frame: `points[i]` at step i (the frame of
  /// step points.size() adds its own), so that a frame rendered alone shows the trail record's
  /// frame of that step showed.
  void SetTrail(const std::vector<std::array<double, 3>>& points);

  /// The objects of the last segmentation layer rendered, by palette index (those with pixels).
  const std::vector<SegmentObject>& segmentation_legend() const { return legend_; }

  /// The calling thread's CPU time in the renderer since it was made, by stage (scene, gl, hud
  /// and copy of base/cpu_clock.h; the other stages stay 0): Submit, Collect and Render.
  const CpuStages& cpu() const { return cpu_; }

  /// Draws every later frame with `look` (render/look.h), or the plain look for nullptr: colours
  /// by part, the table and floor textures, the model's lights and each view's camera jitter
  /// (the view's key is CameraText of its camera) are edited into the scene after
  /// mjv_updateScene / mjv_updateCamera, never into the model or data. rgb, depth and
  /// segmentation all use the jittered camera (view_camera() follows it); segmentation keeps
  /// its own colours. Textures that differ from those already on the GPU are uploaded here,
  /// once, never per frame (texture_uploads() counts them). The look is copied.
  void SetLook(const LookDraw* look);
  /// The camera keys of the views (CameraText of each view's camera, in tile order): the keys
  /// DrawLook draws camera jitter for.
  std::vector<std::string> camera_keys() const;
  /// How many textures SetLook has uploaded since the renderer was made.
  int texture_uploads() const { return texture_uploads_; }

  /// Starts a new episode's trail.
  void ResetTrail() { trail_.Clear(); }

  int width() const { return frame_.width; }    ///< frame width in pixels (FrameSize)
  int height() const { return frame_.height; }  ///< frame height in pixels (FrameSize)
  /// Multisamples per pixel actually used (auto and the driver's maximum resolved).
  int msaa_samples() const { return msaa_samples_; }
  /// Why msaa_samples() has its value, e.g. "auto: software renderer llvmpipe".
  const std::string& msaa_reason() const { return msaa_reason_; }
  /// The viewport of each camera within the frame (OpenGL convention: bottom-left origin).
  const std::vector<mjrRect>& tiles() const { return tiles_; }
  /// The scene of the last frame: maps segmentation ids (segid) to model objects.
  const mjvScene& scene() const { return *scene_->get(); }

 private:
  // Per-phase wall time, summed over frames (FETCHSCOPE_PROFILE only).
  struct Profile {
    Profile() {
    }  // user-provided: clang 14 rejects emplace() of a nested aggregate with initializers
    long frames = 0;
    double scene_ms = 0;     // mjv_updateScene, goal marker and overlay geoms
    double submit_ms = 0;    // mjr_render and mjr_overlay calls (GL command submission)
    double raster_ms = 0;    // glFinish after drawing: the rasterisation itself
    double readback_ms = 0;  // mjr_readPixels: multisample resolve and glReadPixels
    double flip_ms = 0;      // FlipRows
  };

  // Picks the sample count for options_.msaa_samples on this GL; sets msaa_reason_.
  int ResolveMsaa(int max_samples);
  // Updates the scene for `data` and draws every tile into the offscreen buffer.
  void Draw(const mjData* data, const FrameInfo& info, bool overlays);
  // `info`, or (with the contacts overlay) a copy with the contacts of `data` filled in.
  const FrameInfo& WithContacts(const mjData* data, const FrameInfo& info);
  // Reads the rgb of the whole frame, row 0 at the top.
  void ReadRgb(uint8_t* rgb);
  // Picks synchronous or asynchronous readback and makes the pixel buffers; sets
  // readback_reason_.
  void SetUpReadback();
  // Starts the readback of the frame just drawn into pixel buffer `slot`.
  void StartAsyncRead(int slot);
  // Draws the HUD (once, in the tile at options_.hud_position's corner) and the tile labels
  // into the read-back frame.
  void DrawText2d(const FrameInfo& info, uint8_t* rgb, ShownScale scale = {}) const;
  // The frame just read back into `frame.rgb`: its copy (if any) and the text of both.
  struct PendingFrame;
  void FinishFrame(const PendingFrame& frame, const FrameInfo& info) const;
  // Copies the bottom-up rows of `src` (row_bytes each) into `dst` top-down.
  void FlipRows(const uint8_t* src, size_t row_bytes, uint8_t* dst) const;

  GlContext& gl_;
  mjModel* model_;
  RenderOptions options_;
  FrameDims frame_;
  std::vector<mjvCamera> cameras_;
  std::vector<mjrRect> tiles_;
  bool tiles_leave_gaps_ = false;  // a grid with empty cells: clear the frame first
  bool drop_mocap_ = false;        // Draw leaves out the mocap bodies' geoms (segmentation)
  mjvOption option_;
  mjvPerturb perturb_;
  int target_site_ = -1;          // target0, the goal marker
  ContactBodies contact_bodies_;  // the bodies that name the contact pairs
  FrameInfo contact_info_;        // WithContacts's copy, its memory reused
  int grip_site_ = -1;            // robot0:grip, where the action arrow starts
  int msaa_samples_ = 0;
  std::string msaa_reason_;
  std::optional<Profile> profile_;  // set when FETCHSCOPE_PROFILE is
  mutable CpuStages cpu_;           // thread CPU by stage, always kept
  mutable HudText hud_;             // the HUD's text, reused frame to frame (DrawText2d)
  void (*gl_finish_)() = nullptr;   // glFinish, for the profile
  Trail trail_;
  // Made in the constructor body, after the size checks. Lifetime order: the GL context (gl_)
  // outlives both; the MuJoCo context is freed first, with gl_ current (see ~Renderer).
  std::optional<MjvScene> scene_;
  std::optional<MjrContext> context_;
  std::vector<uint8_t> rgb_bottom_up_;  // readback buffer, reused every frame
  // Asynchronous readback: GL entry points, kReadbackDepth pixel buffer objects used in
  // turn, and the destinations of the frames in flight (oldest first).
  struct PboGl;
  std::unique_ptr<PboGl> pbo_gl_;
  bool async_ = false;
  std::string readback_reason_;
  unsigned pbos_[kReadbackDepth] = {0, 0, 0};
  int next_slot_ = 0;
  struct PendingFrame {
    uint8_t* rgb;
    int slot;                 // -1: read synchronously, already in rgb (text included)
    FrameInfo info;           // for the text drawn once the pixels are back (async only)
    uint8_t* copy = nullptr;  // Submit's copy with text sized for copy_scale, or none
    ShownScale copy_scale = {};
  };
  // the frames in flight, oldest first (pending_head_): a fixed ring, so that no frame allocates
  std::array<PendingFrame, kReadbackDepth> pending_{};
  int pending_head_ = 0, pending_count_ = 0;
  PendingFrame& PushPending();  // the next slot of the ring, counted as pending
  std::vector<float> depth_bottom_up_;
  std::vector<SegmentObject> legend_;
  // Turns the segid colours of a segmentation readback into palette colours; fills legend_.
  void ColourSegments(std::vector<uint8_t>* rgb);
  // The depth layer's near and far planes (the model's znear/zfar times its extent), and the
  // distance along the view axis of depth-buffer value d in [0, 1).
  double DepthNear() const;
  double DepthFar() const;
  static double DepthAlongAxis(double d, double znear, double zfar);
  // Draws the scene without overlays and reads its depth buffer into depth_bottom_up_.
  void ReadDepth(const mjData* data, const FrameInfo& info);
  // The palette index of each segid of the last scene (-1: not an object).
  std::vector<int> SegmentObjectsOfScene() const;
  // Draws the segmentation scene and reads its segid colours (segid + 1, 0 = none) into `out`.
  void DrawSegmentIds(const mjData* data, const FrameInfo& info, std::vector<uint8_t>* out);
  std::vector<uint8_t> pick_ids_;  // Pick's readback, reused

  // The look (SetLook; renderer_look.cc). Per model geom its part key ("object", "table",
  // "floor", a robot0: body's name; "" for none) and surface (0 table, 1 floor, -1 none).
  std::optional<LookDraw> look_;
  std::vector<std::string> geom_part_;
  std::vector<int> geom_surface_;
  std::vector<const CameraJitter*> view_jitter_;  // per view, into look_; nullptr: none
  unsigned look_textures_[2] = {0, 0};            // GL names of the table and floor textures
  std::optional<SurfaceTexture> uploaded_[2];     // what each holds
  int texture_uploads_ = 0;
  void FindLookParts();
  void UpdateViewJitter();
  void UploadLookTexture(int surface, const SurfaceTexture& texture);
  void FreeLookTextures() noexcept;
  // Edits the scene's geoms and lights for look_ (after mjv_updateScene).
  void ApplyLook(const mjData* data, mjvScene* scene) const;
  // Moves and turns the scene's camera of view `view` for look_ (after its camera update).
  void JitterView(size_t view, mjvScene* scene) const;
};

}  // namespace fetchscope
