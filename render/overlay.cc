#include "render/overlay.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "render/text.h"
#include "src/errors.h"
#include "src/suggest.h"

namespace fetchscope {
namespace {

constexpr char kAcceptedOverlays[] =
    "accepted: default, none, all, or a comma list of goal, achieved, hud, action, trail, labels, "
    "hindsight";

// Colours (rgba).
constexpr float kGoalRed[4] = {1.0f, 0.0f, 0.0f, 1.0f};       // as target0
constexpr float kGoalShell[4] = {1.0f, 0.15f, 0.15f, 0.18f};  // translucent
constexpr float kSuccessGreen[4] = {0.1f, 0.85f, 0.2f, 1.0f};
constexpr float kMissOrange[4] = {1.0f, 0.55f, 0.0f, 1.0f};
constexpr float kArrowYellow[4] = {1.0f, 0.85f, 0.0f, 1.0f};
constexpr float kTrailCyan[4] = {0.0f, 0.75f, 1.0f, 1.0f};
constexpr float kRelabelGreen[4] = {0.0f, 0.9f, 0.25f, 1.0f};
constexpr float kRelabelRed[4] = {0.95f, 0.1f, 0.1f, 1.0f};

constexpr double kTargetRadius = 0.02;     // target0's size in the Fetch XMLs
constexpr double kAchievedRadius = 0.012;  // opaque core
constexpr double kAchievedHalo = 0.032;    // translucent halo: shows even around the 5 cm block
constexpr double kArrowWidth = 0.008;      // m
constexpr double kLineWidth = 2.0;         // pixels for mjGEOM_LINE
constexpr double kRelabelRadius = 0.014;   // hindsight goal markers: smaller than the goal (0.02)

// Distance from the scene's camera (between the two eyes) to the geom, for the transparent sort.
void SetCamdist(const mjvScene& scene, mjvGeom* g) {
  float d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const float head = 0.5f * (scene.camera[0].pos[k] + scene.camera[1].pos[k]);
    d2 += (g->pos[k] - head) * (g->pos[k] - head);
  }
  g->camdist = std::sqrt(d2);
}

// Returns a fresh decor geom at the end of the scene, or nullptr when the scene is full.
mjvGeom* NewGeom(mjvScene* scene, int type, const mjtNum size[3], const mjtNum pos[3],
                 const float rgba[4]) {
  if (scene->ngeom >= scene->maxgeom) return nullptr;
  mjvGeom* g = scene->geoms + scene->ngeom++;
  mjv_initGeom(g, type, size, pos, nullptr, rgba);
  g->category = mjCAT_DECOR;
  g->objtype = mjOBJ_UNKNOWN;
  g->objid = -1;
  g->segid = -1;  // overlays are not part of the segmentation layer
  // mjv_updateScene fills these for the geoms it makes, not for ones added after it: left as
  // they were, they would hold whatever the geom at this index had in an earlier frame (the
  // transparent sort would then depend on the frames rendered before, e.g. with --jobs)
  g->transparent = rgba[3] < 1.0f;
  g->modelrbound = 0;
  SetCamdist(*scene, g);
  return g;
}

void AddSphere(mjvScene* scene, const std::array<double, 3>& at, double radius,
               const float rgba[4]) {
  const mjtNum size[3] = {radius, radius, radius};
  const mjtNum pos[3] = {at[0], at[1], at[2]};
  NewGeom(scene, mjGEOM_SPHERE, size, pos, rgba);
}

void AddConnector(mjvScene* scene, int type, double width, const std::array<double, 3>& a,
                  const std::array<double, 3>& b, const float rgba[4]) {
  double length = std::sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) +
                            (b[2] - a[2]) * (b[2] - a[2]));
  if (length < 1e-6) return;  // a connector needs a direction
  mjvGeom* g = NewGeom(scene, type, nullptr, nullptr, rgba);
  if (!g) return;
  mjv_makeConnector(g, type, width, a[0], a[1], a[2], b[0], b[1], b[2]);
  SetCamdist(*scene, g);
}

// The one place frame text is drawn (HUD, tile labels): DejaVu Sans through FreeType
// (render/text.h), its em size chosen so that a line is about `line_px` pixels high.
int TextPixels(int line_px) { return std::max(4, line_px * 4 / 5); }
void DrawFrameText(uint8_t* rgb, int width, int height, int x, int y, const std::string& text,
                   int line_px, Rgb color) {
  TextStyle style;
  style.pixel_size = TextPixels(line_px);
  style.color = color;
  Font::Default().Draw(rgb, width, height, x, y, text, style);
}
int FrameTextWidth(const std::string& text, int line_px) {
  return Font::Default().Measure(text, TextPixels(line_px)).width;
}
int FrameTextHeight(const std::string& text, int line_px) {
  return Font::Default().Measure(text, TextPixels(line_px)).height;
}

constexpr Rgb kHudLabelColor = {200, 200, 200};
constexpr Rgb kHudValueColor = {255, 255, 255};
constexpr int kHudMinLine = 10;  // the smallest text that can be read: 8-pixel DejaVu Sans

// Darkens `r` (clipped to the image) to (1 - opacity) of its brightness.
void BlendBox(uint8_t* rgb, int width, int height, const PixelRect& r, double opacity) {
  if (opacity <= 0) return;
  const int x0 = std::max(0, r.x), y0 = std::max(0, r.y);
  const int x1 = std::min(width, r.x + r.width), y1 = std::min(height, r.y + r.height);
  // fixed-point blend: the same bytes on every machine
  const int keep = static_cast<int>(std::lround((1.0 - std::min(1.0, opacity)) * 256));
  for (int y = y0; y < y1; ++y) {
    uint8_t* p = rgb + (static_cast<size_t>(y) * width + x0) * 3;
    for (int i = 0; i < (x1 - x0) * 3; ++i) p[i] = static_cast<uint8_t>((p[i] * keep) >> 8);
  }
}

bool Overlaps(const PixelRect& a, const PixelRect& b) {
  return a.x < b.x + b.width && b.x < a.x + a.width && a.y < b.y + b.height && b.y < a.y + a.height;
}

std::string Format(const char* format, double value) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, value);
  return buf;
}

}  // namespace

OverlaySet ParseOverlays(const std::string& spec) {
  const std::string trimmed = TrimSpaces(spec);
  if (trimmed == "default") return OverlaySet{};
  OverlaySet set{false, false, false, false, false, false, false};
  if (trimmed == "none") return set;
  for (const std::string& token : SplitCommaList(spec)) {
    if (token == "goal") {
      set.goal = true;
    } else if (token == "achieved") {
      set.achieved = true;
    } else if (token == "hud") {
      set.hud = true;
    } else if (token == "action") {
      set.action = true;
    } else if (token == "trail") {
      set.trail = true;
    } else if (token == "labels") {
      set.labels = true;
    } else if (token == "hindsight") {
      set.hindsight = true;
    } else if (token == "default") {
      set.goal = set.achieved = set.hud = set.labels = true;
    } else if (token == "all") {
      set = OverlaySet{true, true, true, true, true, true, true};
    } else {
      const std::string suggestion = DidYouMean(
          token, {"goal", "achieved", "hud", "action", "trail", "labels", "hindsight", "default", "none", "all"});
      throw UsageError("overlay '" + token + "' in '" + spec + "' is not known" + suggestion +
                       "; " + kAcceptedOverlays);
    }
  }
  return set;
}

void Trail::Add(int step, const std::array<double, 3>& position) {
  if (step == 0 || step < last_step_) points_.clear();  // a new episode
  if (step == last_step_ && !points_.empty()) {
    points_.back() = position;
  } else {
    points_.push_back(position);
    if (points_.size() > kMaxPoints) points_.pop_front();
  }
  last_step_ = step;
}

bool PlaceSiteGeom(mjvScene* scene, int site_id, const std::array<double, 3>& goal) {
  if (site_id < 0) return false;
  for (int i = 0; i < scene->ngeom; ++i) {
    mjvGeom& g = scene->geoms[i];
    if (g.objtype == mjOBJ_SITE && g.objid == site_id) {
      for (int k = 0; k < 3; ++k) g.pos[k] = static_cast<float>(goal[k]);
      return true;
    }
  }
  return false;
}

void AddOverlayGeoms(const OverlaySet& overlays, const FrameInfo& info,
                     const std::array<double, 3>& grip, const Trail& trail, bool add_goal_sphere,
                     mjvScene* scene) {
  // Opaque geoms first: if the scene runs out of room, the translucent extras go first.
  if (add_goal_sphere) AddSphere(scene, info.goal, kTargetRadius, kGoalRed);
  const float* achieved_rgba = info.success ? kSuccessGreen : kMissOrange;
  if (overlays.achieved) {
    AddSphere(scene, info.achieved, kAchievedRadius, achieved_rgba);
    AddConnector(scene, mjGEOM_LINE, kLineWidth, info.achieved, info.goal, achieved_rgba);
  }
  if (overlays.action && info.has_action) {
    const double scale = 0.05 * kActionArrowScale;
    std::array<double, 3> tip = {grip[0] + scale * info.action[0], grip[1] + scale * info.action[1],
                                 grip[2] + scale * info.action[2]};
    AddConnector(scene, mjGEOM_ARROW, kArrowWidth, grip, tip, kArrowYellow);
  }
  if (overlays.hindsight) {
    for (const FrameInfo::Relabel& r : info.relabelled) {
      AddSphere(scene, r.goal, kRelabelRadius, r.success ? kRelabelGreen : kRelabelRed);
    }
  }
  if (overlays.trail) {
    const auto& points = trail.points();
    for (size_t i = 1; i < points.size(); ++i) {
      AddConnector(scene, mjGEOM_LINE, kLineWidth, points[i - 1], points[i], kTrailCyan);
    }
  }
  if (overlays.achieved) {
    const float halo[4] = {achieved_rgba[0], achieved_rgba[1], achieved_rgba[2], 0.35f};
    AddSphere(scene, info.achieved, kAchievedHalo, halo);
  }
  if (overlays.goal) AddSphere(scene, info.goal, info.distance_threshold, kGoalShell);
}

HudText FormatHud(const FrameInfo& info, const OverlaySet& overlays) {
  HudText hud;
  auto line = [&](const std::string& label, const std::string& value) {
    hud.labels += label + "\n";
    hud.values += value + "\n";
  };
  // the title goes in the values column: the labels column stays narrow
  if (!info.title.empty()) line("env", info.title);
  line("step", std::to_string(info.step));
  line("reward", std::isnan(info.reward) ? "-" : Format("%.4f", info.reward));
  line("distance", Format("%.4f m", info.distance));
  line("success", info.success ? "yes" : "no");
  if (info.has_action) {
    char buf[96];
    std::snprintf(buf, sizeof(buf), "%+.2f %+.2f %+.2f %+.2f", info.action[0], info.action[1],
                  info.action[2], info.action[3]);
    line("action", buf);
  } else {
    line("action", "-");
  }
  if (overlays.action) line("arrow", Format("x%.0f of 0.05 m/unit", kActionArrowScale));
  if (overlays.hindsight && info.relabelled_successes >= 0) {
    line("HER", std::to_string(info.relabelled_successes) + "/" +
                    std::to_string(info.relabelled.size()) + " relabelled successes");
  }
  // mjr_overlay wants no trailing newline
  hud.labels.pop_back();
  hud.values.pop_back();
  return hud;
}

}  // namespace fetchscope

namespace fetchscope {

HudPosition ParseHudPosition(const std::string& text) {
  if (text == "top-left") return HudPosition::kTopLeft;
  if (text == "top-right") return HudPosition::kTopRight;
  if (text == "bottom-left") return HudPosition::kBottomLeft;
  if (text == "bottom-right") return HudPosition::kBottomRight;
  throw UsageError("--hud-position '" + text +
                   "' is not known; accepted: top-left, top-right, bottom-left, bottom-right");
}

const char* HudPositionName(HudPosition position) {
  switch (position) {
    case HudPosition::kTopLeft: return "top-left";
    case HudPosition::kTopRight: return "top-right";
    case HudPosition::kBottomLeft: return "bottom-left";
    case HudPosition::kBottomRight: return "bottom-right";
  }
  return "top-left";
}

double CheckHudOpacity(double opacity) {
  if (!(opacity >= 0.0 && opacity <= 1.0)) {
    throw UsageError("--hud-opacity " + Format("%g", opacity) +
                     " is out of range; accepted: 0 (no box) .. 1 (opaque box)");
  }
  return opacity;
}

int HudLineHeight(int tile_width, int tile_height) {
  const int side = std::min(tile_width, tile_height);
  // one step of the 10-pixel line per 480 pixels of the tile's shorter side, rounded
  return kHudMinLine * std::max(1, (side * 10 / 480 + 5) / 10);
}

namespace {

struct HudGeometry {
  int line = 0, pad = 0, label_w = 0, gap = 0, text_h = 0;
  PixelRect box;
};

std::optional<HudGeometry> LayoutHud(const HudText& hud, const PixelRect& tile,
                                     HudPosition position) {
  HudGeometry g;
  g.line = HudLineHeight(tile.width, tile.height);
  g.pad = g.line * 4 / 10;
  g.gap = g.line;
  g.label_w = FrameTextWidth(hud.labels, g.line);
  const int value_w = FrameTextWidth(hud.values, g.line);
  g.text_h = std::max(FrameTextHeight(hud.labels, g.line), FrameTextHeight(hud.values, g.line));
  g.box.width = g.pad + g.label_w + g.gap + value_w + g.pad;
  g.box.height = g.pad + g.text_h + g.pad;
  const int margin = g.pad;
  // too small to read: the box would not fit, or would cover more than half the tile's height
  if (g.box.width + 2 * margin > tile.width || 2 * (g.box.height + margin) > tile.height) {
    return std::nullopt;
  }
  const bool right = position == HudPosition::kTopRight || position == HudPosition::kBottomRight;
  const bool bottom = position == HudPosition::kBottomLeft || position == HudPosition::kBottomRight;
  g.box.x = right ? tile.x + tile.width - margin - g.box.width : tile.x + margin;
  g.box.y = bottom ? tile.y + tile.height - margin - g.box.height : tile.y + margin;
  return g;
}

}  // namespace

std::optional<PixelRect> PlaceHud(const HudText& hud, const PixelRect& tile, HudPosition position) {
  const auto g = LayoutHud(hud, tile, position);
  if (!g) return std::nullopt;
  return g->box;
}

bool DrawHud(uint8_t* rgb, int width, int height, const PixelRect& tile, const HudText& hud,
             HudPosition position, double opacity) {
  const auto g = LayoutHud(hud, tile, position);
  if (!g) return false;
  BlendBox(rgb, width, height, g->box, opacity);
  const int x = g->box.x + g->pad, y = g->box.y + g->pad;
  DrawFrameText(rgb, width, height, x, y, hud.labels, g->line, kHudLabelColor);
  DrawFrameText(rgb, width, height, x + g->label_w + g->gap, y, hud.values, g->line, kHudValueColor);
  return true;
}

bool DrawTileLabel(uint8_t* rgb, int width, int height, const PixelRect& tile,
                   const std::string& label, double opacity, const std::optional<PixelRect>& avoid) {
  const int line = HudLineHeight(tile.width, tile.height);
  const int pad = line * 3 / 10;
  PixelRect box;
  box.width = FrameTextWidth(label, line) + 2 * pad;
  box.height = FrameTextHeight(label, line) + 2 * pad;
  if (box.width + 2 * pad > tile.width || 4 * box.height > tile.height) return false;
  box.x = tile.x + (tile.width - box.width) / 2;
  box.y = tile.y + pad;
  if (avoid && Overlaps(box, *avoid)) box.y = tile.y + tile.height - pad - box.height;
  if (avoid && Overlaps(box, *avoid)) return false;
  BlendBox(rgb, width, height, box, opacity);
  DrawFrameText(rgb, width, height, box.x + pad, box.y + pad, label, line, kHudValueColor);
  return true;
}

}  // namespace fetchscope
