// EGL backend: a hardware device through EGL_EXT_platform_device when one is enumerated,
// else Mesa's surfaceless platform. libEGL is opened at run time, never linked.
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <dlfcn.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "base/errors.h"
#include "render/gl_context.h"
#include "render/gpu_select.h"

namespace fetchscope {
namespace {

constexpr char kMissingLibrary[] =
    "egl: cannot load libEGL.so.1 (Debian: apt install libegl1 libegl-mesa0, or the NVIDIA "
    "driver's EGL)";

// The EGL entry points we use. The library stays loaded for the life of the process:
// unloading a GL driver while threads may still hold its state is never safe. It is loaded
// RTLD_LOCAL: MuJoCo binds its GL functions to whichever eglGetProcAddress/
// OSMesaGetProcAddress it finds first in the global scope, and GlContext::PrepareForMujoco
// decides which that should be (see there).
struct EglApi {
  PFNEGLGETPROCADDRESSPROC GetProcAddress = nullptr;
  PFNEGLGETERRORPROC GetError = nullptr;
  PFNEGLQUERYSTRINGPROC QueryString = nullptr;
  PFNEGLINITIALIZEPROC Initialize = nullptr;
  PFNEGLTERMINATEPROC Terminate = nullptr;
  PFNEGLBINDAPIPROC BindAPI = nullptr;
  PFNEGLCHOOSECONFIGPROC ChooseConfig = nullptr;
  PFNEGLCREATECONTEXTPROC CreateContext = nullptr;
  PFNEGLDESTROYCONTEXTPROC DestroyContext = nullptr;
  PFNEGLCREATEPBUFFERSURFACEPROC CreatePbufferSurface = nullptr;
  PFNEGLDESTROYSURFACEPROC DestroySurface = nullptr;
  PFNEGLMAKECURRENTPROC MakeCurrent = nullptr;
  PFNEGLGETCURRENTCONTEXTPROC GetCurrentContext = nullptr;
  PFNEGLRELEASETHREADPROC ReleaseThread = nullptr;
  // extensions (null when absent)
  PFNEGLGETPLATFORMDISPLAYEXTPROC GetPlatformDisplayEXT = nullptr;
  PFNEGLQUERYDEVICESEXTPROC QueryDevicesEXT = nullptr;
  PFNEGLQUERYDEVICESTRINGEXTPROC QueryDeviceStringEXT = nullptr;
  PFNEGLQUERYDEVICEATTRIBEXTPROC QueryDeviceAttribEXT = nullptr;
  std::string load_error;  // non-empty when the library or a core symbol is missing
};

const EglApi& Egl() {
  static const EglApi api = [] {
    EglApi a;
    void* lib = dlopen("libEGL.so.1", RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
      a.load_error = kMissingLibrary;
      return a;
    }
    bool ok = true;
    auto sym = [&](auto* fn, const char* name) {
      *fn = reinterpret_cast<std::remove_pointer_t<decltype(fn)>>(dlsym(lib, name));
      if (!*fn) ok = false;
    };
    sym(&a.GetProcAddress, "eglGetProcAddress");
    sym(&a.GetError, "eglGetError");
    sym(&a.QueryString, "eglQueryString");
    sym(&a.Initialize, "eglInitialize");
    sym(&a.Terminate, "eglTerminate");
    sym(&a.BindAPI, "eglBindAPI");
    sym(&a.ChooseConfig, "eglChooseConfig");
    sym(&a.CreateContext, "eglCreateContext");
    sym(&a.DestroyContext, "eglDestroyContext");
    sym(&a.CreatePbufferSurface, "eglCreatePbufferSurface");
    sym(&a.DestroySurface, "eglDestroySurface");
    sym(&a.MakeCurrent, "eglMakeCurrent");
    sym(&a.GetCurrentContext, "eglGetCurrentContext");
    sym(&a.ReleaseThread, "eglReleaseThread");
    if (!ok) {
      a.load_error = "egl: libEGL.so.1 lacks core EGL 1.4 functions (broken install?)";
      return a;
    }
    auto ext = [&](auto* fn, const char* name) {
      *fn = reinterpret_cast<std::remove_pointer_t<decltype(fn)>>(a.GetProcAddress(name));
    };
    ext(&a.GetPlatformDisplayEXT, "eglGetPlatformDisplayEXT");
    ext(&a.QueryDevicesEXT, "eglQueryDevicesEXT");
    ext(&a.QueryDeviceStringEXT, "eglQueryDeviceStringEXT");
    ext(&a.QueryDeviceAttribEXT, "eglQueryDeviceAttribEXT");
    return a;
  }();
  return api;
}

std::string ErrorName(EGLint code) {
  switch (code) {
    case EGL_SUCCESS:
      return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED:
      return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS:
      return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC:
      return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE:
      return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG:
      return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT:
      return "EGL_BAD_CONTEXT";
    case EGL_BAD_CURRENT_SURFACE:
      return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY:
      return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH:
      return "EGL_BAD_MATCH";
    case EGL_BAD_NATIVE_PIXMAP:
      return "EGL_BAD_NATIVE_PIXMAP";
    case EGL_BAD_NATIVE_WINDOW:
      return "EGL_BAD_NATIVE_WINDOW";
    case EGL_BAD_PARAMETER:
      return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE:
      return "EGL_BAD_SURFACE";
    case EGL_CONTEXT_LOST:
      return "EGL_CONTEXT_LOST";
    default:
      return "EGL error " + std::to_string(code);
  }
}

bool HasExtension(const char* list, const char* name) {
  if (!list) return false;
  const size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    bool starts = p == list || p[-1] == ' ';
    bool ends = p[n] == '\0' || p[n] == ' ';
    if (starts && ends) return true;
  }
  return false;
}

// eglInitialize/eglTerminate act on a display, not a context, and contexts on other threads
// may share one: count the users, initialise with the first and terminate after the last,
// under one lock so that a terminate never lands between another thread's initialise and use.
std::mutex display_mutex;
std::map<EGLDisplay, int> display_users;

// Initialises `display` if no one uses it yet and counts one more user. Throws RunError.
void AcquireDisplay(EGLDisplay display, const std::string& description) {
  std::lock_guard<std::mutex> lock(display_mutex);
  auto it = display_users.find(display);
  if (it == display_users.end()) {
    EGLint major = 0, minor = 0;
    if (!Egl().Initialize(display, &major, &minor)) {
      throw RunError("egl: " + description + ": eglInitialize: " + ErrorName(Egl().GetError()));
    }
    it = display_users.emplace(display, 0).first;
  }
  ++it->second;
}

void ReleaseDisplay(EGLDisplay display) {
  std::lock_guard<std::mutex> lock(display_mutex);
  auto it = display_users.find(display);
  if (it != display_users.end() && --it->second == 0) {
    display_users.erase(it);
    Egl().Terminate(display);
  }
}

class EglContext : public GlContext {
 public:
  // Initialises `display` (shared with other contexts) and makes a context on it.
  EglContext(EGLDisplay display, std::string description) {
    info_.backend = "egl";
    info_.device = std::move(description);
    AcquireDisplay(display, info_.device);
    display_ = display;
    try {
      Init();
    } catch (...) {
      Free();
      throw;
    }
  }

  ~EglContext() override { Free(); }

  void MakeCurrent() override {
    // The bound API is per thread (ES by default) and eglGetCurrentContext answers for it.
    Egl().BindAPI(EGL_OPENGL_API);
    if (Egl().GetCurrentContext() == context_) return;  // cheap on every frame
    if (!Egl().MakeCurrent(display_, surface_, surface_, context_)) {
      throw RunError("egl: eglMakeCurrent failed on " + info_.device + ": " +
                     ErrorName(Egl().GetError()));
    }
  }

  const GlInfo& info() const override { return info_; }

  void* GetProcAddress(const char* name) const override {
    return reinterpret_cast<void*>(Egl().GetProcAddress(name));
  }

 private:
  void Init() {
    const EglApi& egl = Egl();
    if (!egl.BindAPI(EGL_OPENGL_API)) {
      throw RunError("egl: desktop OpenGL is not supported on " + info_.device + " (" +
                     ErrorName(egl.GetError()) + ")");
    }
    // The default framebuffer is never drawn to (MuJoCo has its own FBO), so any config that
    // supports desktop GL will do; prefer one that also allows a pbuffer fallback.
    const EGLint with_pbuffer[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE,
                                   EGL_PBUFFER_BIT, EGL_NONE};
    const EGLint any_surface[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE,
                                  EGL_DONT_CARE, EGL_NONE};
    EGLConfig config = nullptr;
    EGLint count = 0;
    bool pbuffer_ok = egl.ChooseConfig(display_, with_pbuffer, &config, 1, &count) && count > 0;
    if (!pbuffer_ok &&
        !(egl.ChooseConfig(display_, any_surface, &config, 1, &count) && count > 0)) {
      throw RunError("egl: no EGLConfig with desktop OpenGL on " + info_.device);
    }
    // No attributes: a compatibility-profile context of the highest version; MuJoCo 2.2 uses
    // fixed-function GL, which a core profile lacks.
    const EGLint context_attribs[] = {EGL_NONE};
    context_ = egl.CreateContext(display_, config, EGL_NO_CONTEXT, context_attribs);
    if (context_ == EGL_NO_CONTEXT) {
      throw RunError("egl: eglCreateContext failed on " + info_.device + ": " +
                     ErrorName(egl.GetError()));
    }
    const char* extensions = egl.QueryString(display_, EGL_EXTENSIONS);
    if (!HasExtension(extensions, "EGL_KHR_surfaceless_context")) {
      if (!pbuffer_ok) {
        throw RunError("egl: " + info_.device +
                       " supports neither surfaceless contexts nor pbuffers");
      }
      const EGLint pbuffer_attribs[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
      surface_ = egl.CreatePbufferSurface(display_, config, pbuffer_attribs);
      if (surface_ == EGL_NO_SURFACE) {
        throw RunError("egl: eglCreatePbufferSurface failed on " + info_.device + ": " +
                       ErrorName(egl.GetError()));
      }
    }
    MakeCurrent();
    ReadGlStrings(&info_);
  }

  void Free() noexcept {
    const EglApi& egl = Egl();
    if (context_ != EGL_NO_CONTEXT) {
      egl.BindAPI(EGL_OPENGL_API);
      if (egl.GetCurrentContext() == context_) {
        egl.MakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      }
      egl.DestroyContext(display_, context_);
      context_ = EGL_NO_CONTEXT;
    }
    if (surface_ != EGL_NO_SURFACE) {
      egl.DestroySurface(display_, surface_);
      surface_ = EGL_NO_SURFACE;
    }
    if (display_ != EGL_NO_DISPLAY) {
      ReleaseDisplay(display_);
      display_ = EGL_NO_DISPLAY;
    }
  }

  EGLDisplay display_ = EGL_NO_DISPLAY;
  EGLSurface surface_ = EGL_NO_SURFACE;
  EGLContext context_ = EGL_NO_CONTEXT;
  GlInfo info_;
};

// The display of `platform`/`native`, or EGL_NO_DISPLAY with `why` set.
EGLDisplay GetDisplay(EGLenum platform, void* native, std::string* why) {
  EGLDisplay display = Egl().GetPlatformDisplayEXT(platform, native, nullptr);
  if (display == EGL_NO_DISPLAY) {
    *why = "eglGetPlatformDisplayEXT: " + ErrorName(Egl().GetError());
  }
  return display;
}

bool IsSoftwareDevice(EGLDeviceEXT device) {
  const EglApi& egl = Egl();
  if (!egl.QueryDeviceStringEXT) return false;
  return HasExtension(egl.QueryDeviceStringEXT(device, EGL_EXTENSIONS), "EGL_MESA_device_software");
}

// "egl: why" -> "why", for messages that collect several failures under one "egl:".
std::string WithoutPrefix(const std::string& message) {
  return message.rfind("egl: ", 0) == 0 ? message.substr(5) : message;
}

// Whether this EGL lists devices and makes displays of them; `why` says what is missing.
// NVIDIA's driver advertises EGL_EXT_device_base, which stands for EGL_EXT_device_enumeration
// and EGL_EXT_device_query together, and not the enumeration token itself.
bool CanEnumerate(const char* client_extensions, std::string* why) {
  const EglApi& egl = Egl();
  const bool listing = HasExtension(client_extensions, "EGL_EXT_device_enumeration") ||
                       HasExtension(client_extensions, "EGL_EXT_device_base");
  const bool platform = HasExtension(client_extensions, "EGL_EXT_platform_device");
  if (listing && platform && egl.QueryDevicesEXT) return true;
  *why = !listing    ? "neither EGL_EXT_device_enumeration nor EGL_EXT_device_base"
         : !platform ? "no EGL_EXT_platform_device"
                     : "eglQueryDevicesEXT is missing";
  return false;
}

// The driver's device handles, in its order (empty when it lists none).
std::vector<EGLDeviceEXT> QueryDeviceHandles() {
  const EglApi& egl = Egl();
  std::vector<EGLDeviceEXT> devices;
  EGLint n = 0;
  if (egl.QueryDevicesEXT(0, nullptr, &n) && n > 0) {
    devices.resize(n);
    if (!egl.QueryDevicesEXT(n, devices.data(), &n)) n = 0;
    devices.resize(std::max<EGLint>(n, 0));
  }
  return devices;
}

// What the driver says of one device.
EglDevice DescribeDevice(EGLDeviceEXT handle, int index) {
  const EglApi& egl = Egl();
  EglDevice device;
  device.index = index;
  if (!egl.QueryDeviceStringEXT) return device;
  const char* extensions = egl.QueryDeviceStringEXT(handle, EGL_EXTENSIONS);
  device.extensions = extensions ? extensions : "";
  device.software = HasExtension(extensions, "EGL_MESA_device_software");
  if (HasExtension(extensions, "EGL_EXT_device_drm")) {
    const char* file = egl.QueryDeviceStringEXT(handle, EGL_DRM_DEVICE_FILE_EXT);
    if (file) device.drm_node = file;
  }
  EGLAttrib cuda = -1;
  if (HasExtension(extensions, "EGL_NV_device_cuda") && egl.QueryDeviceAttribEXT &&
      egl.QueryDeviceAttribEXT(handle, kEglCudaDeviceNv, &cuda) && cuda >= 0) {
    device.cuda_id = static_cast<int>(cuda);
  }
  return device;
}

}  // namespace

namespace internal {
void PromoteEglToGlobal() {
  // RTLD_NOLOAD only changes the flags of the copy that is already loaded.
  dlopen("libEGL.so.1", RTLD_NOW | RTLD_GLOBAL | RTLD_NOLOAD);
}
}  // namespace internal

EglDeviceList ListEglDevices() {
  const EglApi& egl = Egl();
  if (!egl.load_error.empty()) throw RunError(egl.load_error);
  EglDeviceList list;
  const char* client_extensions = egl.QueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  list.client_extensions = client_extensions ? client_extensions : "";
  list.enumerable = CanEnumerate(client_extensions, &list.why_not);
  if (!list.enumerable) return list;
  const std::vector<EGLDeviceEXT> handles = QueryDeviceHandles();
  for (size_t i = 0; i < handles.size(); ++i) {
    list.devices.push_back(DescribeDevice(handles[i], static_cast<int>(i)));
  }
  return list;
}

namespace {

// Without an explicit index (`gpu` < 0), MUJOCO_EGL_DEVICE_ID or CUDA_VISIBLE_DEVICES may name
// one: the index to use (-1: none named); `source` says who named it.
int ChosenGpu(int gpu, bool enumerable, const std::string& why_not_enumerable,
              const std::vector<EGLDeviceEXT>& devices, std::string* source) {
  *source = "--gpu " + std::to_string(gpu);
  if (gpu >= 0) return gpu;
  EglDeviceList list;
  list.enumerable = enumerable;
  list.why_not = why_not_enumerable;
  for (size_t i = 0; i < devices.size(); ++i) {
    list.devices.push_back(DescribeDevice(devices[i], static_cast<int>(i)));
  }
  const GpuChoice choice = ChooseGpus(EffectiveGpuSpec(""), list);
  if (!choice.devices.empty()) {
    *source = choice.reason;
    return choice.devices.front();
  }
  return gpu;
}

// A context on `platform`'s display, or null with why not added to `failures`.
std::unique_ptr<GlContext> TryDisplay(EGLenum platform, void* native,
                                      const std::string& description,
                                      std::vector<std::string>* failures) {
  std::string why;
  EGLDisplay display = GetDisplay(platform, native, &why);
  if (display == EGL_NO_DISPLAY) {
    failures->push_back(description + ": " + why);
    return nullptr;
  }
  try {
    return std::make_unique<EglContext>(display, description);
  } catch (const RunError& e) {
    failures->push_back(WithoutPrefix(e.what()));
    return nullptr;
  }
}

std::unique_ptr<GlContext> TryDevice(const std::vector<EGLDeviceEXT>& devices, int index,
                                     std::vector<std::string>* failures) {
  return TryDisplay(EGL_PLATFORM_DEVICE_EXT, devices[index],
                    DescribeDevice(devices[index], index).Describe(), failures);
}

// An explicit index names one device and nothing else will do.
std::unique_ptr<GlContext> NamedDevice(int gpu, const std::string& source, bool enumerable,
                                       const std::string& why_not_enumerable,
                                       const std::vector<EGLDeviceEXT>& devices) {
  if (!enumerable || devices.empty()) {
    throw RunError("egl: " + source + " asks for an EGL device, but this EGL enumerates none (" +
                   (enumerable ? std::string("it lists no devices") : why_not_enumerable) + ")");
  }
  if (gpu >= static_cast<int>(devices.size())) {
    throw UsageError(source + " is out of range; accepted: 0.." +
                     std::to_string(devices.size() - 1) +
                     " (EGL devices on this machine: " + std::to_string(devices.size()) + ")");
  }
  std::vector<std::string> failures;
  if (auto context = TryDevice(devices, gpu, &failures)) return context;
  throw RunError("egl: " + failures.back());
}

}  // namespace

std::unique_ptr<GlContext> CreateEglContext(int gpu) {
  const EglApi& egl = Egl();
  if (!egl.load_error.empty()) throw RunError(egl.load_error);
  const char* client_extensions = egl.QueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!egl.GetPlatformDisplayEXT || !HasExtension(client_extensions, "EGL_EXT_platform_base")) {
    throw RunError("egl: this libEGL lacks EGL_EXT_platform_base, so it needs a display server");
  }
  std::string why_not_enumerable;
  const bool enumerable = CanEnumerate(client_extensions, &why_not_enumerable);
  const std::vector<EGLDeviceEXT> devices =
      enumerable ? QueryDeviceHandles() : std::vector<EGLDeviceEXT>{};
  std::string source;
  gpu = ChosenGpu(gpu, enumerable, why_not_enumerable, devices, &source);
  if (gpu >= 0) return NamedDevice(gpu, source, enumerable, why_not_enumerable, devices);

  // Hardware devices first, then Mesa's surfaceless platform, then a software device.
  std::vector<std::string> failures;
  std::vector<int> software_devices;
  for (int i = 0; i < static_cast<int>(devices.size()); ++i) {
    if (IsSoftwareDevice(devices[i])) {
      software_devices.push_back(i);
      continue;
    }
    if (auto context = TryDevice(devices, i, &failures)) return context;
  }
  if (HasExtension(client_extensions, "EGL_MESA_platform_surfaceless")) {
    auto context =
        TryDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, "surfaceless", &failures);
    if (context) return context;
  } else {
    failures.push_back("no EGL_MESA_platform_surfaceless");
  }
  for (int i : software_devices) {
    if (auto context = TryDevice(devices, i, &failures)) return context;
  }
  if (!enumerable) {
    failures.push_back("no device enumeration (" + why_not_enumerable + ")");
  } else if (devices.empty()) {
    failures.push_back("no EGL devices enumerated");
  }
  std::string message = "egl: no usable display (";
  for (size_t i = 0; i < failures.size(); ++i) message += (i ? "; " : "") + failures[i];
  throw RunError(message + ")");
}

}  // namespace fetchscope
