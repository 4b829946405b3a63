#include "encode/frame_pool.h"

#include <algorithm>

namespace fetchscope {

size_t BoundedFrameCount(size_t floor, size_t wanted, size_t frame_bytes) {
  const size_t fit = kFramePoolBudgetBytes / std::max<size_t>(1, frame_bytes);
  return std::max(floor, std::min(wanted, fit));
}

FramePool::FramePool(size_t count, size_t bytes, size_t layers, bool gif_copy)
    : count_(count), bytes_(bytes), layers_(layers), gif_copy_(gif_copy) {}

Frame* FramePool::Acquire() {
  std::unique_lock<std::mutex> lock(mutex_);
  if (free_.empty() && pool_.size() < count_) {
    pool_.push_back(std::make_unique<Frame>());
    pool_.back()->rgb.resize(bytes_);
    pool_.back()->layers.assign(layers_, std::vector<uint8_t>(bytes_));
    if (gif_copy_) pool_.back()->gif_rgb.resize(bytes_);
    return pool_.back().get();
  }
  cv_.wait(lock, [&] { return !free_.empty(); });
  Frame* f = free_.front();
  free_.pop_front();
  return f;
}

void FramePool::Release(Frame* f) {
  if (!f) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(f);
  }
  cv_.notify_one();
}

size_t FramePool::allocated() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return pool_.size();
}

}  // namespace fetchscope
