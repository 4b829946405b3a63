// The renderer's way back from the GPU: mjr_readPixels and the row flip (--readback sync), or
// pixel buffer objects kReadbackDepth frames deep (Submit/Collect, --readback async). The rest of
// Renderer is in renderer.cc.
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>

#include "base/errors.h"
#include "render/readback_gl.h"
#include "render/renderer.h"

namespace fetchscope {
namespace {

// GL enums (from glext.h; we do not include GL headers here beyond what MuJoCo needs).
constexpr unsigned kGlReadFramebuffer = 0x8CA8;
constexpr unsigned kGlDrawFramebuffer = 0x8CA9;
constexpr unsigned kGlColorAttachment0 = 0x8CE0;
constexpr unsigned kGlColorBufferBit = 0x4000;
constexpr unsigned kGlNearest = 0x2600;
constexpr unsigned kGlRgb = 0x1907;
constexpr unsigned kGlUnsignedByte = 0x1401;
constexpr unsigned kGlPixelPackBuffer = 0x88EB;
constexpr unsigned kGlStreamRead = 0x88E1;
constexpr unsigned kGlMapReadBit = 0x0001;
constexpr unsigned kGlPackAlignment = 0x0D05;

using renderer_detail::Clock;
using renderer_detail::MsSince;

}  // namespace

void Renderer::SetUpReadback() {
  const Readback mode = options_.readback;
  if (mode == Readback::kSync) {
    readback_reason_ = "sync: requested";
    return;
  }
  const std::string software = SoftwareRendererName(gl_.info().renderer);
  if (mode == Readback::kAuto && !software.empty()) {
    // llvmpipe renders on the CPU thread that asks for the pixels: nothing to overlap
    readback_reason_ = "sync: auto, software renderer " + software;
    return;
  }
  auto gl = std::make_unique<PboGl>();
  const std::string missing = gl->Load(gl_);
  if (!missing.empty()) {
    if (mode == Readback::kAsync) {
      throw RunError("--readback async needs " + missing + ", which " + gl_.info().renderer +
                     " lacks; use --readback sync");
    }
    readback_reason_ = "sync: auto, the GL lacks " + missing;
    return;
  }
  int alignment = 4;
  gl->GetIntegerv(kGlPackAlignment, &alignment);
  if (alignment < 1) alignment = 1;
  const size_t row = static_cast<size_t>(frame_.width) * 3;
  gl->row_stride = (row + alignment - 1) / alignment * alignment;
  gl->GenBuffers(kReadbackDepth, pbos_);
  for (unsigned pbo : pbos_) {
    gl->BindBuffer(kGlPixelPackBuffer, pbo);
    gl->BufferData(kGlPixelPackBuffer, static_cast<std::ptrdiff_t>(gl->row_stride * frame_.height),
                   nullptr, kGlStreamRead);
  }
  gl->BindBuffer(kGlPixelPackBuffer, 0);
  pbo_gl_ = std::move(gl);
  async_ = true;
  readback_reason_ = std::string("async: ") +
                     (mode == Readback::kAsync ? "requested" : "auto, hardware renderer") + ", " +
                     std::to_string(kReadbackDepth) + " pixel buffers";
}

void Renderer::StartAsyncRead(int slot) {
  const auto start = Clock::now();
  PboGl& g = *pbo_gl_;
  mjrContext* con = context_->get();
  const int w = frame_.width, h = frame_.height;
  // as mjr_readPixels: resolve the multisampled buffer with a blit, then read the colour
  if (con->offSamples) {
    g.BindFramebuffer(kGlReadFramebuffer, con->offFBO);
    g.ReadBuffer(kGlColorAttachment0);
    g.BindFramebuffer(kGlDrawFramebuffer, con->offFBO_r);
    g.DrawBuffer(kGlColorAttachment0);
    g.BlitFramebuffer(0, 0, w, h, 0, 0, w, h, kGlColorBufferBit, kGlNearest);
    g.BindFramebuffer(kGlReadFramebuffer, con->offFBO_r);
  } else {
    g.BindFramebuffer(kGlReadFramebuffer, con->offFBO);
  }
  g.ReadBuffer(kGlColorAttachment0);
  g.BindBuffer(kGlPixelPackBuffer, pbos_[slot]);
  g.ReadPixels(0, 0, w, h, kGlRgb, kGlUnsignedByte, nullptr);  // into the buffer: returns at once
  g.BindBuffer(kGlPixelPackBuffer, 0);
  mjr_restoreBuffer(con);
  g.Flush();  // the GPU starts now, not when the buffer is mapped
  if (profile_) profile_->readback_ms += MsSince(start);
}

uint8_t* Renderer::Collect() {
  if (pending_count_ == 0) return nullptr;
  // the slot stays as it is until a later Submit, after this Collect has returned
  const PendingFrame& frame = pending_[pending_head_];
  pending_head_ = (pending_head_ + 1) % kReadbackDepth;
  --pending_count_;
  if (frame.slot < 0) return frame.rgb;
  gl_.MakeCurrent();
  const auto start = Clock::now();
  CpuLap lap;
  PboGl& g = *pbo_gl_;
  const size_t stride = g.row_stride;
  const int h = frame_.height;
  g.BindBuffer(kGlPixelPackBuffer, pbos_[frame.slot]);
  const auto* mapped = static_cast<const uint8_t*>(g.MapBufferRange(
      kGlPixelPackBuffer, 0, static_cast<std::ptrdiff_t>(stride * h), kGlMapReadBit));
  if (!mapped) {
    g.BindBuffer(kGlPixelPackBuffer, 0);
    throw RunError("cannot map the pixel buffer of a frame on " + gl_.info().renderer +
                   "; use --readback sync");
  }
  const auto copy_start = Clock::now();
  lap.Into(&cpu_.gl);
  // the flip is the copy out of the buffer: rows come bottom-up
  const size_t row = static_cast<size_t>(frame_.width) * 3;
  for (int r = 0; r < h; ++r) std::memcpy(frame.rgb + r * row, mapped + (h - 1 - r) * stride, row);
  lap.Into(&cpu_.copy);
  g.UnmapBuffer(kGlPixelPackBuffer);
  g.BindBuffer(kGlPixelPackBuffer, 0);
  lap.Into(&cpu_.gl);
  FinishFrame(frame, frame.info);  // the HUD and tile labels, as Render draws them
  if (profile_) {
    profile_->readback_ms += std::chrono::duration<double, std::milli>(copy_start - start).count();
    profile_->flip_ms += MsSince(copy_start);
  }
  return frame.rgb;
}

void Renderer::ReadRgb(uint8_t* rgb) {
  const mjrRect frame{0, 0, frame_.width, frame_.height};
  const auto start = Clock::now();
  CpuLap lap;
  // MuJoCo resolves the multisampled buffer (a blit) and reads GL_RGB rows bottom-up. On
  // llvmpipe this is ~0.5 ms of a 15-40 ms frame (docs/guide/recording.md, "Where a frame's time
  // goes"); on hardware GL Submit/Collect read through pixel buffers instead, overlapping the next
  // frame.
  mjr_readPixels(rgb_bottom_up_.data(), nullptr, frame, context_->get());
  const auto flip_start = Clock::now();
  lap.Into(&cpu_.gl);
  FlipRows(rgb_bottom_up_.data(), static_cast<size_t>(frame_.width) * 3, rgb);
  lap.Into(&cpu_.copy);
  if (profile_) {
    profile_->readback_ms += std::chrono::duration<double, std::milli>(flip_start - start).count();
    profile_->flip_ms += MsSince(flip_start);
  }
}

void Renderer::FlipRows(const uint8_t* src, size_t row_bytes, uint8_t* dst) const {
  const int h = frame_.height;
  for (int row = 0; row < h; ++row) {
    std::memcpy(dst + row * row_bytes, src + (h - 1 - row) * row_bytes, row_bytes);
  }
}

}  // namespace fetchscope
