// How large a frame may be: the pixels a run can hold in memory (a few frame buffers per
// worker, whatever --steps), checked before anything is rendered or written. The GL limits
// per side (GL_MAX_RENDERBUFFER_SIZE, GL_MAX_TEXTURE_SIZE, GL_MAX_VIEWPORT_DIMS) are queried
// from the context by the Renderer.
#pragma once

#include <cstdint>

namespace fetchscope {

/// The most pixels a whole frame (every camera's tile) may have: 4096 x 4096.
inline constexpr int64_t kMaxFramePixels = int64_t{4096} * 4096;

/// The memory a record worker needs per frame pixel, measured (renderer, GL buffers, the frame
/// pool's few buffers, the encoders' frames): about 90 bytes.
inline constexpr int64_t kRunBytesPerPixel = 90;

/// Throws UsageError when a `frame_width` x `frame_height` frame (made of `tiles` views of
/// `width` x `height`, as --width/--height ask) is over kMaxFramePixels; the one line names the
/// sizes, the memory they would need and the limit.
void CheckFrameSize(int width, int height, int tiles, int frame_width, int frame_height);

}  // namespace fetchscope
