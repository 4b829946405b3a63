// The GIF's palette filter (libavfilter): RGB24 frames of the episode in, PAL8 frames of the GIF
// out, scaled to its size, with one palette made from the whole clip (palettegen stats_mode=full,
// then paletteuse with error diffusion). Single-threaded and bit-exact, so the bytes are the same
// on every machine. VideoWriter hands it the frames a GIF keeps and encodes what it lets out.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>

#include "encode/av_handles.h"

struct AVFilterGraph;
struct AVFilterContext;

namespace fetchscope {

class GifPaletteFilter {
 public:
  /// Frames of width x height at `fps` in, out_width x out_height out. Throws RunError when
  /// libavfilter cannot build the graph.
  GifPaletteFilter(int width, int height, int fps, int out_width, int out_height);
  /// Hands frame `pts` (RGB24, width * height * 3 bytes) to the graph; nullptr ends the clip
  /// (only then does paletteuse let frames out: the palette needs every frame).
  void Push(const uint8_t* rgb, int64_t pts);
  /// Calls `take` with each frame the graph has ready, in order.
  void Drain(const std::function<void(const AVFrame*)>& take);

 private:
  struct GraphDeleter {
    void operator()(AVFilterGraph* graph) const noexcept;
  };
  int width_, height_;
  std::unique_ptr<AVFilterGraph, GraphDeleter> graph_;  // buffer -> scale -> split -> palette
  AVFilterContext* source_ = nullptr;                   // owned by graph_
  AVFilterContext* sink_ = nullptr;                     // owned by graph_
  FramePtr input_;                                      // RGB24 frame handed to the graph
  FramePtr output_;                                     // PAL8 frame out of the graph
};

}  // namespace fetchscope
