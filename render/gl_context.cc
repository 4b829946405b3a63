#include "render/gl_context.h"

#include <GL/gl.h>

#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>

#include "base/errors.h"
#include "base/suggest.h"

namespace fetchscope {

GlContext::~GlContext() = default;

void GlContext::ReadGlStrings(GlInfo* info) const {
  using GetStringFn = const GLubyte* (*)(GLenum);
  auto get_string = reinterpret_cast<GetStringFn>(GetProcAddress("glGetString"));
  if (!get_string) throw RunError(info->backend + ": glGetString is not available");
  auto read = [&](GLenum name) {
    const GLubyte* s = get_string(name);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string();
  };
  info->vendor = read(GL_VENDOR);
  info->renderer = read(GL_RENDERER);
  info->version = read(GL_VERSION);
  if (info->renderer.empty()) {
    throw RunError(info->backend + ": the new context answers no GL_RENDERER (not current?)");
  }
}

namespace {

// How MuJoCo's GL functions were bound in this process ("" = not yet): "glapi" = through
// OSMesaGetProcAddress, i.e. Mesa's shared dispatch, which serves OSMesa and Mesa's EGL alike;
// "egl" = through eglGetProcAddress (GLVND stubs), which serves EGL contexts only.
std::mutex binding_mutex;
std::string binding;
std::string binding_renderer;  // the context that made the binding, for messages

bool IsMesa(const GlInfo& info) { return info.version.find("Mesa") != std::string::npos; }

}  // namespace

void GlContext::PrepareForMujoco() const {
  std::lock_guard<std::mutex> lock(binding_mutex);
  const GlInfo& gl = info();
  if (binding.empty()) {
    if (gl.backend == "osmesa" || (IsMesa(gl) && internal::LoadOsMesaGlobally())) {
      // libEGL is loaded locally, so MuJoCo finds OSMesaGetProcAddress first.
      binding = "glapi";
    } else {
      internal::PromoteEglToGlobal();  // eglGetProcAddress is found before OSMesa's
      binding = "egl";
    }
    binding_renderer = gl.backend + " (" + gl.renderer + ")";
    return;
  }
  const bool served =
      binding == "glapi" ? gl.backend == "osmesa" || IsMesa(gl) : gl.backend == "egl";
  if (!served) {
    throw RunError(gl.backend +
                   ": cannot render in this process: MuJoCo 2.2 bound its GL "
                   "functions once, for " +
                   binding_renderer +
                   ", and they do not reach this context; use one backend per process");
  }
}

namespace {

// MUJOCO_GL values that ask MuJoCo's Python bindings for a windowed GL (GLFW, GLX, ...). Many
// laptops set one globally; fetchscope never opens a window, so they mean auto here.
bool IsWindowedGl(std::string name) {
  for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return name == "glfw" || name == "glx" || name == "glut" || name == "wgl" || name == "cgl";
}

void WarnWindowedGl(const std::string& name) {
  std::fprintf(stderr,
               "fetchscope: warning: MUJOCO_GL=%s opens a window; fetchscope renders off-screen "
               "and uses auto (EGL, then OSMesa)\n",
               name.c_str());
}

}  // namespace

void ResolveWindowedMujocoGl() {
  const char* env = std::getenv("MUJOCO_GL");
  if (!env || !IsWindowedGl(env)) return;
  WarnWindowedGl(env);
  setenv("MUJOCO_GL", "auto", 1);
}

GlBackend ResolveGlBackend(const std::string& backend) {
  std::string name = backend;
  std::string origin = "backend";
  if (name.empty()) {
    const char* env = std::getenv("MUJOCO_GL");
    name = env && *env ? env : "auto";
    if (env && *env) origin = "MUJOCO_GL";
    if (IsWindowedGl(name)) {
      static std::once_flag warned;  // once per process, however many workers make contexts
      std::call_once(warned, [&] { WarnWindowedGl(name); });
      name = "auto";
    }
  }
  if (name == "egl") return GlBackend::kEgl;
  if (name == "osmesa") return GlBackend::kOsmesa;
  if (name != "auto") {
    throw UsageError(origin + " '" + name + "' is not known" +
                     DidYouMean(name, {"auto", "egl", "osmesa"}) + "; accepted: auto|egl|osmesa");
  }
  return GlBackend::kAuto;
}

std::unique_ptr<GlContext> CreateGlContext(const std::string& backend, int gpu) {
  return CreateGlContext(ResolveGlBackend(backend), gpu);
}

std::unique_ptr<GlContext> CreateGlContext(GlBackend backend, int gpu) {
  if (backend == GlBackend::kEgl) return CreateEglContext(gpu);
  if (backend == GlBackend::kOsmesa) return CreateOsMesaContext();

  // auto: EGL first (hardware when present), OSMesa as the software fallback. A bad device
  // index is the user's mistake, not a missing backend, so UsageError is not caught here.
  std::string egl_error;
  try {
    return CreateEglContext(gpu);
  } catch (const RunError& e) {
    egl_error = e.what();
  }
  std::string osmesa_error;
  try {
    return CreateOsMesaContext();
  } catch (const RunError& e) {
    osmesa_error = e.what();
  }
  throw RunError("no OpenGL backend could be created; " + egl_error + "; " + osmesa_error +
                 ". Install EGL (Debian: libegl1 libegl-mesa0, or the NVIDIA driver) or OSMesa "
                 "(Debian: libosmesa6), or pick one with --backend egl|osmesa / MUJOCO_GL");
}

}  // namespace fetchscope
