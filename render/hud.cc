// The HUD and the tile labels, drawn into a frame's pixels: their text size for a view, their
// box, where they go. What the HUD says is FormatHud's (render/overlay.cc).
#include <algorithm>
#include <optional>
#include <string>
#include <string_view>

#include "render/canvas.h"
#include "render/overlay.h"
#include "render/text.h"

namespace fetchscope {
namespace {

// Frame text (HUD, tile labels) is DejaVu Sans through FreeType (render/text.h) at an em of
// `pixels`, drawn through the canvas.
TextMetrics FrameText(std::string_view text, int pixels) {
  return Font::Default().Measure(text, pixels);
}

constexpr Rgb kHudLabelColor = {200, 200, 200};
constexpr Rgb kBoxBlack = {0, 0, 0};
constexpr Rgb kHudValueColor = {255, 255, 255};
// The value column is as wide as the widest action line (DejaVu's '+' is wider than its '-',
// so this is the widest the action can be): the box keeps its size from frame to frame.
constexpr char kHudWidestValue[] = "+0.00 +0.00 +0.00 +0.00";

// The HUD's and tile labels' box: black blended over `r` at `opacity` (0: none, 1: opaque).
void DrawBox(Canvas* canvas, const PixelRect& r, double opacity) {
  canvas->FillRect(r.x, r.y, r.width, r.height, kBoxBlack, opacity);
}

// Frame text over a box: with a box lighter than kHudOutlineBelowOpacity (0 = none) the text
// gets a black outline, so that white text reads on the white table; over the darker box
// (the default 0.6) it is drawn as it always was.
void BoxedText(Canvas* canvas, int x, int y, std::string_view text, int pixels, Rgb color,
               double opacity) {
  TextStyle style;
  style.pixel_size = pixels;
  style.color = color;
  if (opacity < kHudOutlineBelowOpacity) style.outline = kBoxBlack;
  Font::Default().Draw(canvas, x, y, text, style);
}

bool Overlaps(const PixelRect& a, const PixelRect& b) {
  return a.x < b.x + b.width && b.x < a.x + a.width && a.y < b.y + b.height && b.y < a.y + a.height;
}

}  // namespace

const char* HudPositionName(HudPosition position) {
  switch (position) {
    case HudPosition::kTopLeft:
      return "top-left";
    case HudPosition::kTopRight:
      return "top-right";
    case HudPosition::kBottomLeft:
      return "bottom-left";
    case HudPosition::kBottomRight:
      return "bottom-right";
  }
  return "top-left";
}

int FrameTextPixels(int tile_width, int tile_height) {
  const long side = std::max(0, std::min(tile_width, tile_height));
  // 2.7 % of the shorter side, rounded, in integers (the same on every machine)
  return std::max(kHudMinTextPixels, static_cast<int>((side * 27 + 500) / 1000));
}

int HudTextPixels(int tile_width, int tile_height) {
  if (tile_width < kHudMinTileWidth || tile_height < kHudMinTileHeight) return 0;
  return FrameTextPixels(tile_width, tile_height);
}

namespace {

// `pixels` of the shown view in drawn pixels, rounded; integers only (the same on every machine).
int Drawn(int pixels, ShownScale scale) {
  return static_cast<int>((static_cast<long>(pixels) * scale.drawn + scale.shown / 2) /
                          scale.shown);
}

// A drawn length as shown (rounded down: a view is as big as the pixels it fills).
int Shown(int length, ShownScale scale) {
  return static_cast<int>(static_cast<long>(length) * scale.shown / scale.drawn);
}

}  // namespace

int FrameTextPixels(int tile_width, int tile_height, ShownScale scale) {
  return Drawn(FrameTextPixels(Shown(tile_width, scale), Shown(tile_height, scale)), scale);
}

int HudTextPixels(int tile_width, int tile_height, ShownScale scale) {
  return Drawn(HudTextPixels(Shown(tile_width, scale), Shown(tile_height, scale)), scale);
}

namespace {

// The line of `text` that starts at *at, *at moved past it (and its '\n'); no copy is made.
// *at == npos once the last line is taken.
std::string_view NextLine(std::string_view text, size_t* at) {
  const size_t start = *at;
  const size_t end = text.find('\n', start);
  *at = end == std::string_view::npos ? std::string_view::npos : end + 1;
  return text.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start);
}

int LineCount(std::string_view text) {
  return 1 + static_cast<int>(std::count(text.begin(), text.end(), '\n'));
}

struct HudGeometry {
  int pixels = 0;  // em
  int pitch = 0;   // baseline to baseline
  int pad = 0, label_w = 0, gap = 0, value_w = 0;
  PixelRect box;
};

// Rows one pitch apart: 1.25 em, so that the box's height is proportional to the text size
// (FreeType's own line height is rounded per size: 17 px at 13 px, 32 at 26).
int RowPitch(int pixels) { return (5 * pixels + 2) / 4; }

// The box depends on the tile and on the rows (labels) only, never on the values.
std::optional<HudGeometry> LayoutHud(const HudText& hud, const PixelRect& tile,
                                     HudPosition position, ShownScale scale) {
  HudGeometry g;
  g.pixels = HudTextPixels(tile.width, tile.height, scale);
  if (g.pixels == 0) return std::nullopt;
  g.pitch = RowPitch(g.pixels);
  g.pad = std::max(3, g.pixels * 2 / 5);
  g.gap = g.pixels;
  g.label_w = FrameText(hud.labels, g.pixels).width;
  g.value_w = FrameText(kHudWidestValue, g.pixels).width;
  const int rows = LineCount(hud.labels) + (hud.title.empty() ? 0 : 1);
  g.box.width = g.pad + g.label_w + g.gap + g.value_w + g.pad;
  g.box.height = g.pad + rows * g.pitch + g.pad;
  const int margin = g.pad;
  const bool right = position == HudPosition::kTopRight || position == HudPosition::kBottomRight;
  const bool bottom = position == HudPosition::kBottomLeft || position == HudPosition::kBottomRight;
  g.box.x = right ? tile.x + tile.width - margin - g.box.width : tile.x + margin;
  g.box.y = bottom ? tile.y + tile.height - margin - g.box.height : tile.y + margin;
  return g;
}

}  // namespace

std::optional<PixelRect> PlaceHud(const HudText& hud, const PixelRect& tile, HudPosition position,
                                  ShownScale scale) {
  const auto g = LayoutHud(hud, tile, position, scale);
  if (!g) return std::nullopt;
  return g->box;
}

bool DrawHud(uint8_t* rgb, int width, int height, const PixelRect& tile, const HudText& hud,
             HudPosition position, double opacity, ShownScale scale) {
  const auto g = LayoutHud(hud, tile, position, scale);
  if (!g) return false;
  Canvas canvas(rgb, width, height);
  DrawBox(&canvas, g->box, opacity);
  const Font& font = Font::Default();
  const int x = g->box.x + g->pad, value_x = x + g->label_w + g->gap;
  int y = g->box.y + g->pad;
  // text that fits is drawn as it is; only a text that must be cut is copied (Font::Fit)
  std::string cut;
  auto fitted = [&](std::string_view text, int width) -> std::string_view {
    if (font.Fits(text, g->pixels, width)) return text;
    cut = font.Fit(std::string(text), g->pixels, width);
    return cut;
  };
  if (!hud.title.empty()) {
    const int title_w = g->box.width - 2 * g->pad;
    BoxedText(&canvas, x, y, fitted(hud.title, title_w), g->pixels, kHudValueColor, opacity);
    y += g->pitch;
  }
  size_t label_at = 0, value_at = 0;
  for (; label_at != std::string_view::npos; y += g->pitch) {
    BoxedText(&canvas, x, y, NextLine(hud.labels, &label_at), g->pixels, kHudLabelColor, opacity);
    // each value cut to its column: the box never grows with the frame's text
    if (value_at != std::string_view::npos) {
      BoxedText(&canvas, value_x, y, fitted(NextLine(hud.values, &value_at), g->value_w), g->pixels,
                kHudValueColor, opacity);
    }
  }
  return true;
}

namespace {

// A one-line label on a box centred in `tile`: at its top (its bottom where `bottom_first`),
// moved to the other edge where it would overlap `avoid`, left out where it still would or the
// tile is too small for it.
bool DrawLabel(uint8_t* rgb, int width, int height, const PixelRect& tile, const std::string& label,
               double opacity, const std::optional<PixelRect>& avoid, ShownScale scale,
               bool bottom_first) {
  const int pixels = FrameTextPixels(tile.width, tile.height, scale);
  const TextMetrics m = FrameText(label, pixels);
  const int pad = std::max(2, pixels / 4);
  PixelRect box;
  box.width = m.width + 2 * pad;
  box.height = m.height + 2 * pad;
  if (box.width + 2 * pad > tile.width || 4 * box.height > tile.height) return false;
  box.x = tile.x + (tile.width - box.width) / 2;
  const int top = tile.y + pad, bottom = tile.y + tile.height - pad - box.height;
  box.y = bottom_first ? bottom : top;
  if (avoid && Overlaps(box, *avoid)) box.y = bottom_first ? top : bottom;
  if (avoid && Overlaps(box, *avoid)) return false;
  Canvas canvas(rgb, width, height);
  DrawBox(&canvas, box, opacity);
  BoxedText(&canvas, box.x + pad, box.y + pad, label, pixels, kHudValueColor, opacity);
  return true;
}

}  // namespace

bool DrawTileLabel(uint8_t* rgb, int width, int height, const PixelRect& tile,
                   const std::string& label, double opacity, const std::optional<PixelRect>& avoid,
                   ShownScale scale) {
  return DrawLabel(rgb, width, height, tile, label, opacity, avoid, scale, /*bottom_first=*/false);
}

std::string ContactLabel(const FrameInfo& info) {
  char text[160];
  std::snprintf(text, sizeof(text), "L %.0f N  R %.0f N%s%s  |  1 cm = 20 N",
                info.left_finger_force, info.right_finger_force,
                info.left_finger_force > 0 && info.right_finger_force > 0 ? "  grasp" : "",
                !info.has_object       ? ""
                : info.object_on_table ? "  on table"
                                       : "  off table");
  return text;
}

bool DrawContactLabel(uint8_t* rgb, int width, int height, const PixelRect& tile,
                      const FrameInfo& info, double opacity, const std::optional<PixelRect>& avoid,
                      ShownScale scale) {
  if (HudTextPixels(tile.width, tile.height, scale) == 0) return false;  // as small as no HUD
  return DrawLabel(rgb, width, height, tile, ContactLabel(info), opacity, avoid, scale,
                   /*bottom_first=*/true);
}

}  // namespace fetchscope
