// What renderer.cc and renderer_readback.cc share, inside render/ only: the clock of the
// FETCHSCOPE_PROFILE breakdown and the GL entry points of asynchronous readback.
#pragma once

#include <chrono>
#include <cstddef>
#include <string>
#include <type_traits>

#include "render/gl_context.h"
#include "render/renderer.h"

namespace fetchscope {
namespace renderer_detail {

using Clock = std::chrono::steady_clock;

inline double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

}  // namespace renderer_detail

// The GL entry points of asynchronous readback, looked up through the context.
struct Renderer::PboGl {
  void (*BindFramebuffer)(unsigned, unsigned) = nullptr;
  void (*BlitFramebuffer)(int, int, int, int, int, int, int, int, unsigned, unsigned) = nullptr;
  void (*ReadBuffer)(unsigned) = nullptr;
  void (*DrawBuffer)(unsigned) = nullptr;
  void (*ReadPixels)(int, int, int, int, unsigned, unsigned, void*) = nullptr;
  void (*GenBuffers)(int, unsigned*) = nullptr;
  void (*DeleteBuffers)(int, const unsigned*) = nullptr;
  void (*BindBuffer)(unsigned, unsigned) = nullptr;
  void (*BufferData)(unsigned, std::ptrdiff_t, const void*, unsigned) = nullptr;
  void* (*MapBufferRange)(unsigned, std::ptrdiff_t, std::ptrdiff_t, unsigned) = nullptr;
  unsigned char (*UnmapBuffer)(unsigned) = nullptr;
  void (*GetIntegerv)(unsigned, int*) = nullptr;
  void (*Flush)() = nullptr;
  size_t row_stride = 0;  // bytes per row in the pixel buffers (GL_PACK_ALIGNMENT applied)

  // Looks every entry point up; returns the first missing name, or "" when all are there.
  std::string Load(const GlContext& gl) {
    std::string missing;
    auto get = [&](auto** fn, const char* name) {
      *fn = reinterpret_cast<std::remove_pointer_t<decltype(fn)>>(gl.GetProcAddress(name));
      if (!*fn && missing.empty()) missing = name;
    };
    get(&BindFramebuffer, "glBindFramebuffer");
    get(&BlitFramebuffer, "glBlitFramebuffer");
    get(&ReadBuffer, "glReadBuffer");
    get(&DrawBuffer, "glDrawBuffer");
    get(&ReadPixels, "glReadPixels");
    get(&GenBuffers, "glGenBuffers");
    get(&DeleteBuffers, "glDeleteBuffers");
    get(&BindBuffer, "glBindBuffer");
    get(&BufferData, "glBufferData");
    get(&MapBufferRange, "glMapBufferRange");
    get(&UnmapBuffer, "glUnmapBuffer");
    get(&GetIntegerv, "glGetIntegerv");
    get(&Flush, "glFlush");
    return missing;
  }
};

}  // namespace fetchscope
