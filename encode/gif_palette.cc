#include "encode/gif_palette.h"

#include <cstdio>
#include <cstring>
#include <string>

#include "base/errors.h"
#include "encode/av_log.h"

extern "C" {
#include <libavfilter/avfilter.h>
#include <libavfilter/buffersink.h>
#include <libavfilter/buffersrc.h>
#include <libavutil/mem.h>
}

namespace fetchscope {

void GifPaletteFilter::GraphDeleter::operator()(AVFilterGraph* graph) const noexcept {
  avfilter_graph_free(&graph);
}

GifPaletteFilter::GifPaletteFilter(int width, int height, int fps, int out_width, int out_height)
    : width_(width), height_(height) {
  graph_.reset(avfilter_graph_alloc());
  input_.reset(av_frame_alloc());
  output_.reset(av_frame_alloc());
  if (!graph_ || !input_ || !output_) throw RunError("out of memory for the GIF filter");
  graph_->nb_threads = 1;  // the same bytes whatever the machine
  char source_args[160];
  std::snprintf(source_args, sizeof(source_args),
                "video_size=%dx%d:pix_fmt=%d:time_base=1/%d:pixel_aspect=1/1", width_, height_,
                static_cast<int>(AV_PIX_FMT_RGB24), fps);
  ClearLastAvError();
  if (int rc = avfilter_graph_create_filter(&source_, avfilter_get_by_name("buffer"), "in",
                                            source_args, nullptr, graph_.get());
      rc < 0) {
    throw RunError("cannot create the GIF filter source: " + DescribeAvError(rc));
  }
  if (int rc = avfilter_graph_create_filter(&sink_, avfilter_get_by_name("buffersink"), "out",
                                            nullptr, nullptr, graph_.get());
      rc < 0) {
    throw RunError("cannot create the GIF filter sink: " + DescribeAvError(rc));
  }
  // One palette for the whole clip (stats_mode=full), then each frame mapped onto it with
  // error diffusion; lanczos keeps thin lines when scaling down, and bitexact keeps swscale off
  // CPU-specific code paths whose rounding differs, so the bytes are the same on every machine.
  const std::string description =
      "scale=" + std::to_string(out_width) + ":" + std::to_string(out_height) +
      ":flags=lanczos+accurate_rnd+bitexact,split[a][b];"
      "[a]palettegen=stats_mode=full[p];[b][p]paletteuse=dither=sierra2_4a";
  AVFilterInOut* outputs = avfilter_inout_alloc();
  AVFilterInOut* inputs = avfilter_inout_alloc();
  if (!outputs || !inputs) {
    avfilter_inout_free(&outputs);
    avfilter_inout_free(&inputs);
    throw RunError("out of memory for the GIF filter");
  }
  outputs->name = av_strdup("in");
  outputs->filter_ctx = source_;
  outputs->pad_idx = 0;
  outputs->next = nullptr;
  inputs->name = av_strdup("out");
  inputs->filter_ctx = sink_;
  inputs->pad_idx = 0;
  inputs->next = nullptr;
  int rc = avfilter_graph_parse_ptr(graph_.get(), description.c_str(), &inputs, &outputs, nullptr);
  avfilter_inout_free(&outputs);
  avfilter_inout_free(&inputs);
  if (rc < 0) {
    throw RunError("cannot build the GIF palette filter (" + description +
                   "): " + DescribeAvError(rc) + "; Debian's libavfilter8 has it");
  }
  if (rc = avfilter_graph_config(graph_.get(), nullptr); rc < 0) {
    throw RunError("cannot configure the GIF palette filter: " + DescribeAvError(rc));
  }
}

void GifPaletteFilter::Push(const uint8_t* rgb, int64_t pts) {
  ClearLastAvError();
  if (rgb == nullptr) {
    if (int rc = av_buffersrc_add_frame_flags(source_, nullptr, 0); rc < 0) {
      throw RunError("cannot end the GIF clip: " + DescribeAvError(rc));
    }
    return;
  }
  AVFrame* in = input_.get();
  av_frame_unref(in);
  in->format = AV_PIX_FMT_RGB24;
  in->width = width_;
  in->height = height_;
  if (int rc = av_frame_get_buffer(in, 0); rc < 0) {
    throw RunError("cannot allocate a GIF input frame: " + DescribeAvError(rc));
  }
  const std::size_t row = static_cast<std::size_t>(width_) * 3;
  for (int y = 0; y < height_; ++y) {
    std::memcpy(in->data[0] + static_cast<std::size_t>(y) * in->linesize[0], rgb + y * row, row);
  }
  in->pts = pts;
  if (int rc = av_buffersrc_add_frame_flags(source_, in, AV_BUFFERSRC_FLAG_KEEP_REF); rc < 0) {
    throw RunError("cannot pass frame " + std::to_string(pts) +
                   " to the GIF filter: " + DescribeAvError(rc));
  }
  av_frame_unref(in);
}

void GifPaletteFilter::Drain(const std::function<void(const AVFrame*)>& take) {
  while (true) {
    ClearLastAvError();
    const int rc = av_buffersink_get_frame(sink_, output_.get());
    if (rc == AVERROR(EAGAIN) || rc == AVERROR_EOF) return;
    if (rc < 0) throw RunError("the GIF palette filter failed: " + DescribeAvError(rc));
    take(output_.get());
    av_frame_unref(output_.get());
  }
}

}  // namespace fetchscope
