// OSMesa backend: Mesa's software rasteriser drawing into a buffer we own. libOSMesa is
// opened at run time, never linked.
#include <GL/osmesa.h>
#include <dlfcn.h>

#include <string>
#include <vector>

#include "base/errors.h"
#include "render/gl_context.h"

namespace fetchscope {
namespace {

using CreateContextAttribsFn = OSMesaContext (*)(const int*, OSMesaContext);
using CreateContextExtFn = OSMesaContext (*)(GLenum, GLint, GLint, GLint, OSMesaContext);
using DestroyContextFn = void (*)(OSMesaContext);
using MakeCurrentFn = GLboolean (*)(OSMesaContext, void*, GLenum, GLsizei, GLsizei);
using GetCurrentContextFn = OSMesaContext (*)();
using GetProcAddressFn = OSMESAproc (*)(const char*);

// The OSMesa entry points. The library stays loaded for the life of the process, in the
// global scope, where MuJoCo's GL loader looks for OSMesaGetProcAddress.
struct OsMesaApi {
  CreateContextAttribsFn CreateContextAttribs = nullptr;  // Mesa >= 11.2; may be null
  CreateContextExtFn CreateContextExt = nullptr;
  DestroyContextFn DestroyContext = nullptr;
  MakeCurrentFn MakeCurrent = nullptr;
  GetCurrentContextFn GetCurrentContext = nullptr;
  GetProcAddressFn GetProcAddress = nullptr;
  std::string load_error;  // non-empty when unusable
};

const OsMesaApi& OsMesa() {
  static const OsMesaApi api = [] {
    OsMesaApi a;
    void* lib = nullptr;
    for (const char* name : {"libOSMesa.so.8", "libOSMesa.so.6"}) {
      if ((lib = dlopen(name, RTLD_NOW | RTLD_GLOBAL))) break;
    }
    if (!lib) {
      a.load_error = "osmesa: cannot load libOSMesa.so.8 (Debian: apt install libosmesa6)";
      return a;
    }
    auto sym = [&](auto* fn, const char* name) {
      *fn = reinterpret_cast<std::remove_pointer_t<decltype(fn)>>(dlsym(lib, name));
    };
    sym(&a.CreateContextAttribs, "OSMesaCreateContextAttribs");
    sym(&a.CreateContextExt, "OSMesaCreateContextExt");
    sym(&a.DestroyContext, "OSMesaDestroyContext");
    sym(&a.MakeCurrent, "OSMesaMakeCurrent");
    sym(&a.GetCurrentContext, "OSMesaGetCurrentContext");
    sym(&a.GetProcAddress, "OSMesaGetProcAddress");
    if (!a.CreateContextExt || !a.DestroyContext || !a.MakeCurrent || !a.GetCurrentContext ||
        !a.GetProcAddress) {
      a.load_error = "osmesa: libOSMesa lacks the OSMesa 11 functions (broken install?)";
    }
    return a;
  }();
  return api;
}

class OsMesaContext : public GlContext {
 public:
  OsMesaContext() {
    const OsMesaApi& osmesa = OsMesa();
    info_.backend = "osmesa";
    info_.device = "software";
    if (osmesa.CreateContextAttribs) {
      // Compatibility profile: MuJoCo 2.2 draws with fixed-function GL.
      const int attribs[] = {OSMESA_FORMAT,
                             OSMESA_RGBA,
                             OSMESA_DEPTH_BITS,
                             24,
                             OSMESA_STENCIL_BITS,
                             8,
                             OSMESA_PROFILE,
                             OSMESA_COMPAT_PROFILE,
                             0};
      context_ = osmesa.CreateContextAttribs(attribs, nullptr);
    }
    if (!context_) context_ = osmesa.CreateContextExt(OSMESA_RGBA, 24, 8, 0, nullptr);
    if (!context_) throw RunError("osmesa: OSMesaCreateContext failed");
    try {
      MakeCurrent();
      ReadGlStrings(&info_);
    } catch (...) {
      Free();
      throw;
    }
  }

  ~OsMesaContext() override { Free(); }

  void MakeCurrent() override {
    // OSMesa needs a colour buffer to bind, but MuJoCo draws into its own offscreen FBO, so
    // a token window buffer is enough.
    if (OsMesa().GetCurrentContext() == context_) return;  // cheap on every frame
    if (!OsMesa().MakeCurrent(context_, buffer_.data(), GL_UNSIGNED_BYTE, kBufferSize,
                              kBufferSize)) {
      throw RunError("osmesa: OSMesaMakeCurrent failed");
    }
  }

  const GlInfo& info() const override { return info_; }

  void* GetProcAddress(const char* name) const override {
    return reinterpret_cast<void*>(OsMesa().GetProcAddress(name));
  }

 private:
  static constexpr int kBufferSize = 16;  // pixels per side of the unused window buffer

  void Free() noexcept {
    if (!context_) return;
    const OsMesaApi& osmesa = OsMesa();
    if (osmesa.GetCurrentContext() == context_) {
      osmesa.MakeCurrent(nullptr, nullptr, 0, 0, 0);  // unbind before destroying
    }
    osmesa.DestroyContext(context_);
    context_ = nullptr;
  }

  OSMesaContext context_ = nullptr;
  std::vector<unsigned char> buffer_ = std::vector<unsigned char>(kBufferSize * kBufferSize * 4);
  GlInfo info_;
};

}  // namespace

namespace internal {
bool LoadOsMesaGlobally() { return OsMesa().load_error.empty(); }
}  // namespace internal

std::unique_ptr<GlContext> CreateOsMesaContext() {
  const OsMesaApi& osmesa = OsMesa();
  if (!osmesa.load_error.empty()) throw RunError(osmesa.load_error);
  return std::make_unique<OsMesaContext>();
}

}  // namespace fetchscope
