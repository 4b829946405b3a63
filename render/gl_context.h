// Off-screen OpenGL contexts: EGL (device enumeration or Mesa surfaceless) and OSMesa,
// chosen at run time. Neither library is linked: both are opened with dlopen, so a machine
// that lacks one still runs the other.
#pragma once

#include <memory>
#include <string>
#include <utility>

namespace fetchscope {

/// What a context reports about itself (for manifests and error messages).
struct GlInfo {
  std::string backend;   ///< "egl" or "osmesa"
  std::string vendor;    ///< GL_VENDOR
  std::string renderer;  ///< GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  std::string version;   ///< GL_VERSION
  std::string
      device;  ///< how the display was reached, e.g. "surfaceless" or "device 0 (/dev/dri/card0)"
};

/// A desktop (compatibility-profile) OpenGL context with no window, owned by one thread at a
/// time. MuJoCo renders into its own offscreen framebuffer, so the context needs no surface of
/// its own. The constructor of each backend leaves the new context current on its thread.
class GlContext {
 public:
  virtual ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  /// Makes this context current on the calling thread.
  virtual void MakeCurrent() = 0;

  /// Backend, vendor, renderer and version strings, read once at creation.
  virtual const GlInfo& info() const = 0;

  /// How the device was chosen (e.g. "--gpu cuda:1 = EGL device 2"); "" unless set.
  const std::string& selection() const { return selection_; }
  /// Records how the device was chosen, for manifests and --verbose.
  void set_selection(std::string selection) { selection_ = std::move(selection); }

  /// Looks up a GL entry point through the backend's GetProcAddress (nullptr if unknown).
  virtual void* GetProcAddress(const char* name) const = 0;

  /// Call before mjr_makeContext. MuJoCo 2.2 resolves its GL functions once per process, at
  /// the first mjr_makeContext, through the first of eglGetProcAddress, OSMesaGetProcAddress
  /// and glXGetProcAddressARB that the loaded libraries export. This steers that choice so the
  /// pointers serve this context, and Mesa's EGL and OSMesa both when possible (Mesa's shared
  /// glapi). Throws RunError when an earlier binding cannot serve this context.
  void PrepareForMujoco() const;

 protected:
  GlContext() = default;

  /// Reads GL_VENDOR/RENDERER/VERSION of the current context into `info`.
  void ReadGlStrings(GlInfo* info) const;

 private:
  std::string selection_;
};

/// The GL backend a context is made with.
enum class GlBackend {
  kAuto,    ///< EGL, then OSMesa
  kEgl,     ///< EGL only
  kOsmesa,  ///< OSMesa only
};

/// The backend `name` asks for: "auto", "egl", "osmesa"; an empty string means $MUJOCO_GL if
/// set (a windowed GL there, warned about once, means auto), else auto. Throws UsageError for
/// an unknown name, naming it (and MUJOCO_GL when it came from there).
GlBackend ResolveGlBackend(const std::string& name);

/// Creates a context on `backend`. gpu: EGL device index; -1 means what the environment
/// names (EffectiveGpuSpec: MUJOCO_EGL_DEVICE_ID, else cuda:0 when CUDA_VISIBLE_DEVICES is
/// set), else the first hardware device that initialises, else Mesa's surfaceless platform.
/// Throws UsageError for an out-of-range device index, and RunError when no context can be
/// made (saying why each backend failed and what to install).
std::unique_ptr<GlContext> CreateGlContext(GlBackend backend, int gpu = -1);

/// CreateGlContext(ResolveGlBackend(backend), gpu).
std::unique_ptr<GlContext> CreateGlContext(const std::string& backend, int gpu = -1);

/// When $MUJOCO_GL asks for a windowed GL (glfw, glx, glut, wgl, cgl), which fetchscope never
/// opens: warns once on stderr and sets MUJOCO_GL=auto, so that worker processes and child
/// runs do not warn again. Call it while the process has one thread (main does).
void ResolveWindowedMujocoGl();

/// The EGL backend alone (see CreateGlContext for `gpu`). Throws RunError/UsageError.
std::unique_ptr<GlContext> CreateEglContext(int gpu);

/// The OSMesa backend alone. Throws RunError.
std::unique_ptr<GlContext> CreateOsMesaContext();

namespace internal {
/// Loads libOSMesa into the global symbol scope; false if it is not installed.
bool LoadOsMesaGlobally();
/// Moves the already loaded libEGL into the global symbol scope (it is loaded locally so
/// that MuJoCo does not bind to it by accident).
void PromoteEglToGlobal();
}  // namespace internal

}  // namespace fetchscope
