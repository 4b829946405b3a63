#include "render/layers.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace fetchscope {

const char* LayerName(Layer layer) {
  switch (layer) {
    case Layer::kRgb:
      return "rgb";
    case Layer::kDepth:
      return "depth";
    case Layer::kSegmentation:
      return "segmentation";
  }
  return "?";
}

std::string LayerFilePath(const std::string& output, Layer layer, size_t listed) {
  if (listed <= 1 || layer == Layer::kRgb) return output;
  const std::filesystem::path p(output);
  return (p.parent_path() / (p.stem().string() + "_" + LayerName(layer) + p.extension().string()))
      .string();
}

std::string LegendFilePath(const std::string& output) {
  const std::filesystem::path p(output);
  return (p.parent_path() / (p.stem().string() + "_segmentation_legend.json")).string();
}

std::string LayersLabel(const std::vector<Layer>& layers) {
  std::string label = "rgb";
  for (Layer layer : layers) label += std::string(",") + LayerName(layer);
  return label;
}

std::vector<DepthScale> ScalesFromFrame(const std::vector<uint8_t>& depth, int frame_width,
                                        int frame_height, const std::vector<mjrRect>& tiles) {
  const uint16_t* mm = reinterpret_cast<const uint16_t*>(depth.data());
  std::vector<DepthScale> scales;
  for (const mjrRect& tile : tiles) {
    DepthScale scale;
    scale.x = tile.left;
    scale.y = frame_height - tile.bottom - tile.height;
    scale.width = tile.width;
    scale.height = tile.height;
    int lo = 65535, hi = 0;
    for (int r = scale.y; r < scale.y + scale.height; ++r) {
      for (int c = scale.x; c < scale.x + scale.width; ++c) {
        const int v = mm[static_cast<size_t>(r) * frame_width + c];
        if (v == 0) continue;
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
    }
    if (hi == 0) {  // nothing in view at reset: 0..10 m
      lo = 0;
      hi = 10000;
    }
    scale.near_mm = lo / 100 * 100;
    scale.far_mm = std::max((hi + 99) / 100 * 100, scale.near_mm + 100);
    scales.push_back(scale);
  }
  return scales;
}

void DepthToGrey(const std::vector<uint8_t>& depth, int frame_width,
                 const std::vector<DepthScale>& scales, uint8_t* rgb) {
  const uint16_t* mm = reinterpret_cast<const uint16_t*>(depth.data());
  std::fill(rgb, rgb + depth.size() / 2 * 3, 0);
  for (const DepthScale& s : scales) {
    const double span = s.far_mm - s.near_mm;
    for (int r = s.y; r < s.y + s.height; ++r) {
      for (int c = s.x; c < s.x + s.width; ++c) {
        const size_t i = static_cast<size_t>(r) * frame_width + c;
        if (mm[i] == 0) continue;
        const double f = std::clamp((mm[i] - s.near_mm) / span, 0.0, 1.0);
        const auto grey = static_cast<uint8_t>(std::lround(255.0 - 223.0 * f));
        rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = grey;
      }
    }
  }
}

nlohmann::json SegmentObjectJson(const SegmentObject& o) {
  char hex[8];
  std::snprintf(hex, sizeof(hex), "#%02x%02x%02x", o.color[0], o.color[1], o.color[2]);
  return {{"color", hex},
          {"rgb", {o.color[0], o.color[1], o.color[2]}},
          {"body", o.body},
          {"geoms", o.geoms},
          {"site", o.site.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.site)},
          {"pixels", o.pixels}};
}

void EpisodeLegend::Add(const std::vector<SegmentObject>& frame) {
  ++frames_;
  for (const SegmentObject& o : frame) {
    Entry& e = objects_[o.index];
    e.object.index = o.index;
    e.object.color = o.color;
    e.object.body = o.body;
    e.object.site = o.site;
    e.object.pixels += o.pixels;
    e.geoms.insert(o.geoms.begin(), o.geoms.end());
    ++e.frames;
  }
}

nlohmann::json EpisodeLegend::Json(int episode) const {
  nlohmann::json list = nlohmann::json::array();
  for (const auto& [index, e] : objects_) {
    SegmentObject object = e.object;
    object.geoms.assign(e.geoms.begin(), e.geoms.end());
    nlohmann::json entry = SegmentObjectJson(object);
    entry["frames"] = e.frames;
    list.push_back(std::move(entry));
  }
  return {{"episode", episode},
          {"frames", frames_},
          {"background", "#000000"},
          {"note",
           "one colour per body (all its geoms) or site, the same in every frame; "
           "pixels and frames summed over the episode's video. Lossy video shifts "
           "colours slightly: match a pixel to the nearest colour here"},
          {"objects", list}};
}

}  // namespace fetchscope
