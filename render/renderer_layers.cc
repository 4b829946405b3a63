// The renderer's other layers: depth in millimetres and segmentation (a fixed colour per body
// or site, with its legend). Renderer's colour frame is in renderer.cc.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "render/renderer.h"

namespace fetchscope {
namespace {

// The segmentation palette (tools/segmentation_palette.py): greedy farthest-point colours in
// CIEDE2000, away from the black background; every prefix is spread out, the first 36 (all
// the objects of a Fetch model) at least 15.9 apart, all 48 at least 14.1.
constexpr uint32_t kSegmentationPalette[] = {
    0xFFFF00, 0xFFAAFF, 0x00DDFF, 0xDD6600, 0x008833, 0x6600FF, 0xBB0044, 0x55FFBB,
    0x2288FF, 0xFFDDCC, 0x665533, 0xAA9944, 0x887788, 0x006666, 0xFF6677, 0xEE00BB,
    0x88AA99, 0x225588, 0xBBCCFF, 0x77CC11, 0x993300, 0xEEFFFF, 0x9977DD, 0xFFAA22,
    0xDDDDAA, 0x883377, 0x0099AA, 0xAA7766, 0xCC99AA, 0xEE1122, 0x667766, 0xFF9977,
    0x00BB77, 0xBBBBBB, 0x667700, 0x996600, 0x665555, 0x665599, 0x557788, 0x66BBFF,
    0x00CCBB, 0xFFEEFF, 0xCCFF88, 0xBB6688, 0xCCAA88, 0xEECC55, 0xBBFFEE, 0x9999BB};

}  // namespace

std::array<uint8_t, 3> SegmentationColor(int index) {
  constexpr int n = kSegmentationColors;
  static_assert(sizeof(kSegmentationPalette) / sizeof(kSegmentationPalette[0]) == n);
  if (index >= 0 && index < n) {
    const uint32_t c = kSegmentationPalette[index];
    return {static_cast<uint8_t>(c >> 16), static_cast<uint8_t>(c >> 8), static_cast<uint8_t>(c)};
  }
  // golden-angle hues in integer arithmetic (no platform-dependent rounding): hue in 1/3600
  // turns, saturation 65%, value alternating 95% / 70%
  const int i = std::max(0, index - n);
  const int hue = (i * 2221) % 3600;  // 2221/3600 ~ 0.617 turn; 2221 is prime: no repeats
  const int v = (i % 2 == 0) ? 242 : 178;
  const int lo = v * 35 / 100;
  const int sector = hue / 600, f = hue % 600;
  const int up = lo + (v - lo) * f / 600, down = v - (v - lo) * f / 600;
  int r = v, g = lo, b = lo;
  switch (sector) {
    case 0:
      r = v;
      g = up;
      b = lo;
      break;
    case 1:
      r = down;
      g = v;
      b = lo;
      break;
    case 2:
      r = lo;
      g = v;
      b = up;
      break;
    case 3:
      r = lo;
      g = down;
      b = v;
      break;
    case 4:
      r = up;
      g = lo;
      b = v;
      break;
    default:
      r = v;
      g = lo;
      b = down;
      break;
  }
  std::array<uint8_t, 3> c = {static_cast<uint8_t>(r), static_cast<uint8_t>(g),
                              static_cast<uint8_t>(b)};
  if (c[0] == 0 && c[1] == 0 && c[2] == 0) c[2] = 1;  // black is the background
  return c;
}

void Renderer::RenderLayer(const mjData* data, const FrameInfo& info, Layer layer,
                           std::vector<uint8_t>* out) {
  const size_t pixels = static_cast<size_t>(frame_.width) * frame_.height;
  if (layer == Layer::kRgb) {
    out->resize(pixels * 3);
    Render(data, info, out->data());
    return;
  }
  if (layer == Layer::kSegmentation) {
    DrawSegmentIds(data, info, out);
    ColourSegments(out);
    return;
  }

  ReadDepth(data, info);
  const double znear = DepthNear(), zfar = DepthFar();
  std::vector<uint16_t> millimetres(pixels);
  for (size_t i = 0; i < pixels; ++i) {
    const double d = depth_bottom_up_[i];
    if (d >= 1.0) continue;  // stays 0
    const double mm = std::round(1000.0 * DepthAlongAxis(d, znear, zfar));
    if (mm <= 65535.0) millimetres[i] = static_cast<uint16_t>(mm);
  }
  out->resize(pixels * 2);
  FlipRows(reinterpret_cast<const uint8_t*>(millimetres.data()),
           static_cast<size_t>(frame_.width) * 2, out->data());
}

// Depth: the buffer holds d in [0, 1], non-linear; with near n and far f (MuJoCo scales the
// model's znear/zfar by the model extent), the distance along the view axis is
// n f / (f - d (f - n)). The far plane (d = 1) and, in millimetres, anything beyond uint16
// (65.535 m; MuJoCo's skybox lies ~100 m away) become 0: no measurement.
double Renderer::DepthNear() const { return model_->vis.map.znear * model_->stat.extent; }
double Renderer::DepthFar() const { return model_->vis.map.zfar * model_->stat.extent; }
double Renderer::DepthAlongAxis(double d, double znear, double zfar) {
  return znear * zfar / (zfar - d * (zfar - znear));
}

void Renderer::ReadDepth(const mjData* data, const FrameInfo& info) {
  Draw(data, info, /*overlays=*/false);
  depth_bottom_up_.resize(static_cast<size_t>(frame_.width) * frame_.height);
  mjr_readPixels(nullptr, depth_bottom_up_.data(), mjrRect{0, 0, frame_.width, frame_.height},
                 context_->get());
}

void Renderer::RenderDepthMetres(const mjData* data, const FrameInfo& info,
                                 std::vector<float>* out) {
  ReadDepth(data, info);
  const double znear = DepthNear(), zfar = DepthFar();
  const size_t w = static_cast<size_t>(frame_.width), h = static_cast<size_t>(frame_.height);
  out->resize(w * h);
  for (size_t y = 0; y < h; ++y) {  // bottom-up rows to top-down
    const float* src = depth_bottom_up_.data() + (h - 1 - y) * w;
    float* dst = out->data() + y * w;
    for (size_t x = 0; x < w; ++x) {
      const double d = src[x];
      dst[x] = d >= 1.0 ? 0.0f : static_cast<float>(DepthAlongAxis(d, znear, zfar));
    }
  }
}

void Renderer::RenderSegmentIndices(const mjData* data, const FrameInfo& info,
                                    std::vector<int32_t>* out) {
  DrawSegmentIds(data, info, &pick_ids_);
  const std::vector<int> object_of = SegmentObjectsOfScene();
  const size_t pixels = pick_ids_.size() / 3;
  out->resize(pixels);
  const uint8_t* p = pick_ids_.data();
  for (size_t i = 0; i < pixels; ++i, p += 3) {
    const int id = p[0] + 256 * p[1] + 65536 * p[2];  // segid + 1; 0 = background
    (*out)[i] = id > 0 && id <= static_cast<int>(object_of.size()) ? object_of[id - 1] : -1;
  }
}

std::vector<int> Renderer::SegmentObjectsOfScene() const {
  const mjvScene& scene = *scene_->get();
  std::vector<int> object_of(static_cast<size_t>(scene.ngeom), -1);
  for (int i = 0; i < scene.ngeom; ++i) {
    const mjvGeom& g = scene.geoms[i];
    if (g.segid < 0 || g.segid >= scene.ngeom) continue;
    if (g.objtype == mjOBJ_GEOM && g.objid >= 0 && g.objid < model_->ngeom) {
      object_of[g.segid] = model_->geom_bodyid[g.objid];
    } else if (g.objtype == mjOBJ_SITE && g.objid >= 0 && g.objid < model_->nsite) {
      object_of[g.segid] = model_->nbody + g.objid;
    }
  }
  return object_of;
}

void Renderer::DrawSegmentIds(const mjData* data, const FrameInfo& info,
                              std::vector<uint8_t>* out) {
  mjvScene* scene = scene_->get();
  scene->flags[mjRND_SEGMENT] = 1;
  scene->flags[mjRND_IDCOLOR] = 1;
  drop_mocap_ = !options_.segment_mocap;
  Draw(data, info, /*overlays=*/false);
  drop_mocap_ = false;
  scene->flags[mjRND_SEGMENT] = 0;
  scene->flags[mjRND_IDCOLOR] = 0;
  out->resize(static_cast<size_t>(frame_.width) * frame_.height * 3);
  ReadRgb(out->data());
}

std::optional<PickedObject> Renderer::Pick(const mjData* data, const FrameInfo& info, int x,
                                           int y) {
  if (x < 0 || y < 0 || x >= frame_.width || y >= frame_.height) return std::nullopt;
  DrawSegmentIds(data, info, &pick_ids_);
  const uint8_t* p = pick_ids_.data() + (static_cast<size_t>(y) * frame_.width + x) * 3;
  const int id = p[0] + 256 * p[1] + 65536 * p[2];  // segid + 1; 0 = background
  const mjvScene& scene = *scene_->get();
  for (int i = 0; id > 0 && i < scene.ngeom; ++i) {
    const mjvGeom& g = scene.geoms[i];
    if (g.segid != id - 1) continue;
    const auto name = [this](int type, int n) {
      const char* s = mj_id2name(model_, type, n);
      return s ? std::string(s) : std::string(mju_type2Str(type)) + " " + std::to_string(n);
    };
    PickedObject picked;
    if (g.objtype == mjOBJ_GEOM && g.objid >= 0 && g.objid < model_->ngeom) {
      picked.body_id = model_->geom_bodyid[g.objid];
      picked.geom = name(mjOBJ_GEOM, g.objid);
    } else if (g.objtype == mjOBJ_SITE && g.objid >= 0 && g.objid < model_->nsite) {
      picked.body_id = model_->site_bodyid[g.objid];
      picked.site = name(mjOBJ_SITE, g.objid);
    } else {
      return std::nullopt;
    }
    picked.body = name(mjOBJ_BODY, picked.body_id);
    picked.color =
        SegmentationColor(g.objtype == mjOBJ_SITE ? model_->nbody + g.objid : picked.body_id);
    return picked;
  }
  return std::nullopt;
}

void Renderer::ColourSegments(std::vector<uint8_t>* rgb) {
  const mjvScene& scene = *scene_->get();
  // scene segid -> palette index (-1: not an object, e.g. overlays)
  std::vector<int> object_of(static_cast<size_t>(scene.ngeom) + 1, -1);
  std::map<int, SegmentObject> objects;
  std::vector<std::set<int>> seen_geoms(static_cast<size_t>(model_->nbody));
  std::vector<int> geom_of_seg(static_cast<size_t>(scene.ngeom) + 1, -1);
  for (int i = 0; i < scene.ngeom; ++i) {
    const mjvGeom& g = scene.geoms[i];
    if (g.segid < 0 || g.segid >= scene.ngeom) continue;
    int index = -1, body = -1;
    if (g.objtype == mjOBJ_GEOM && g.objid >= 0 && g.objid < model_->ngeom) {
      body = model_->geom_bodyid[g.objid];
      index = body;
      geom_of_seg[g.segid] = g.objid;
    } else if (g.objtype == mjOBJ_SITE && g.objid >= 0 && g.objid < model_->nsite) {
      body = model_->site_bodyid[g.objid];
      index = model_->nbody + g.objid;
    }
    if (index < 0) continue;
    object_of[g.segid] = index;
    if (!objects.count(index)) {
      SegmentObject o;
      o.index = index;
      o.color = SegmentationColor(index);
      const char* name = mj_id2name(model_, mjOBJ_BODY, body);
      o.body = name ? name : "body " + std::to_string(body);
      if (g.objtype == mjOBJ_SITE) {
        const char* site = mj_id2name(model_, mjOBJ_SITE, g.objid);
        o.site = site ? site : "site " + std::to_string(g.objid);
      }
      objects.emplace(index, std::move(o));
    }
  }
  uint8_t* p = rgb->data();
  const size_t pixels = rgb->size() / 3;
  for (size_t i = 0; i < pixels; ++i, p += 3) {
    const int id = p[0] + 256 * p[1] + 65536 * p[2];  // segid + 1; 0 = background
    const int index = id > 0 && id <= scene.ngeom ? object_of[id - 1] : -1;
    if (index < 0) {
      p[0] = p[1] = p[2] = 0;
      continue;
    }
    SegmentObject& o = objects[index];
    ++o.pixels;
    if (index < model_->nbody && geom_of_seg[id - 1] >= 0)
      seen_geoms[index].insert(geom_of_seg[id - 1]);
    p[0] = o.color[0];
    p[1] = o.color[1];
    p[2] = o.color[2];
  }
  legend_.clear();
  for (auto& [index, o] : objects) {
    if (o.pixels == 0) continue;
    if (index < model_->nbody) {
      for (int geom : seen_geoms[index]) {
        const char* name = mj_id2name(model_, mjOBJ_GEOM, geom);
        o.geoms.push_back(name ? name : "geom " + std::to_string(geom));
      }
    }
    legend_.push_back(std::move(o));
  }
}

}  // namespace fetchscope
