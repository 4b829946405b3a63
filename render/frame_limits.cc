#include "render/frame_limits.h"

#include <cstdio>
#include <string>

#include "base/errors.h"

namespace fetchscope {

void CheckFrameSize(int width, int height, int tiles, int frame_width, int frame_height) {
  const int64_t pixels = int64_t{frame_width} * frame_height;
  if (pixels <= kMaxFramePixels) return;
  const std::string cameras = tiles > 1 ? " with " + std::to_string(tiles) + " cameras" : "";
  char text[512];
  std::snprintf(text, sizeof(text),
                "--width %d --height %d%s make a %dx%d frame (%.1f million pixels, about %.1f GB "
                "of frame buffers per worker): the limit is %.1f million pixels a frame "
                "(4096x4096, about %.1f GB); use a smaller --width/--height%s",
                width, height, cameras.c_str(), frame_width, frame_height, pixels / 1e6,
                pixels * kRunBytesPerPixel / 1e9, kMaxFramePixels / 1e6,
                kMaxFramePixels * kRunBytesPerPixel / 1e9, tiles > 1 ? " or fewer cameras" : "");
  throw UsageError(text);
}

}  // namespace fetchscope
