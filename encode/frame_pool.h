// A bounded pool of reusable frame buffers, shared by a record worker's render thread (which
// fills them) and its episode encoder threads (which hand them back once encoded).
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace fetchscope {

/// One rendered frame travelling from the render thread to an episode's encoder thread.
struct Frame {
  std::vector<uint8_t> rgb;                  ///< width * height * 3 bytes, row 0 at the top
  std::vector<std::vector<uint8_t>> layers;  ///< the extra layers as rgb, in the run's order
  /// The frame for the GIF when it is scaled down: text sized for the GIF's width (render/
  /// overlay.h ShownScale); empty when the run writes no scaled GIF (the GIF then takes `rgb`).
  std::vector<uint8_t> gif_rgb;
  int t = 0;          ///< the step the frame shows (0: the reset)
  std::string label;  ///< the frame's contact sheet label
};

/// The memory a frame pool may fill beyond its floor: frames that only let the render thread run
/// ahead of its encoders stop there, so that large frames or many --steps never hold more.
inline constexpr size_t kFramePoolBudgetBytes = size_t{128} << 20;

/// The frames a pool of `frame_bytes` frames (rgb and layers together) may hold: `wanted`, but
/// no more than fit kFramePoolBudgetBytes, and never fewer than `floor` (the frames the render
/// thread and encoders hold at once, below which they would wait on each other).
size_t BoundedFrameCount(size_t floor, size_t wanted, size_t frame_bytes);

/// A bounded pool of frame buffers: no per-frame allocation, and a render thread that runs
/// ahead of its encoders waits for a free buffer. Thread-safe.
class FramePool {
 public:
  /// At most `count` frames of `bytes` each (and `layers` layer images of as many, and a
  /// gif_rgb of as many when `gif_copy`), made when first needed: a run whose render thread
  /// never gets ahead of its encoders never holds more than the few it cycles through.
  FramePool(size_t count, size_t bytes, size_t layers, bool gif_copy = false);
  FramePool(const FramePool&) = delete;
  FramePool& operator=(const FramePool&) = delete;

  /// A free frame (its contents are those it last held): a released one if any, else a new
  /// one while fewer than `count` exist, else blocks until one is released.
  Frame* Acquire();

  /// Returns `frame` (from Acquire) to the pool; null is ignored.
  void Release(Frame* frame);

  /// Frames made so far (at most `count`).
  size_t allocated() const;

 private:
  const size_t count_;
  const size_t bytes_;
  const size_t layers_;
  const bool gif_copy_;
  std::vector<std::unique_ptr<Frame>> pool_;
  std::deque<Frame*> free_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
};

}  // namespace fetchscope
