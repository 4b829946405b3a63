// Label placement for drawings with leader lines (the anatomy card): each label is a box of
// text (or an empty box of a given size) that points at an anchor pixel with a leader line.
// LabelPlacer puts every box inside its area, off the other boxes, leaders, anchor dots and
// drawn segments, and never lets a leader cross another box; DrawLabels draws what it placed.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "render/canvas.h"
#include "render/text.h"
#include "render/vec.h"

namespace fetchscope {

/// Sizes of labels and their leaders, pixels.
struct LabelStyle {
  double scale = 1;      ///< of the design size: costs count design pixels (pixels / scale)
  int text_pixels = 15;  ///< em size of the label text
  int padding = 4;       ///< text to box edge
  int gap = 6;           ///< least space between two boxes, and between a box and the area's edge
  double leader = 2;     ///< leader line width
  double outline = 1.5;  ///< dark rim on each side of leaders and dots
  double dot = 3.5;      ///< anchor dot radius
};

/// A label to place. Its anchors (where it may point) are given beside it, in pixels.
struct LabelRequest {
  std::string text{};        ///< empty for a box of `box_size` (e.g. an inset view)
  Rgb color{255, 255, 255};  ///< text, leader and dot colour
  double direction = 0;      ///< preferred side of the anchor, degrees (0 right, 90 down)
  bool dot = true;           ///< mark the anchor with a dot (not on an arrow's tip or a line)
  Pixel box_size{};          ///< the box's size when there is no text
  double clear = 0;          ///< pixels around the anchor the leader may cross (a ring's radius)
  std::string name{};        ///< what errors call it; empty: "the label '<first line>'"
};

/// A label where it goes: its box and, unless it is a caption, its anchor and leader.
struct PlacedLabel {
  std::string text;
  Rgb color;
  std::optional<Pixel> anchor;  ///< none for captions
  Pixel attach{};               ///< where the leader meets the box
  bool dot = false;             ///< an anchor dot is drawn
  RectF box;                    ///< pixels, row 0 = top
};

/// Something drawn that labels keep off: the segment a-b and `half_width` pixels around it.
struct LabelObstacle {
  Pixel a, b;
  double half_width;
};

/// The box of `text` at `style` with its top-left corner at (x, y), padding included.
RectF TextBox(const std::string& text, const LabelStyle& style, double x, double y);

/// Places label boxes near their anchors. A box must lie inside the area and never on another
/// box, on another label's leader or anchor dot, and its leader must not run over another box or
/// dot; where there is any such place it must also stay off the obstacles. Among the places left
/// the cheapest wins: the shortest leader, with penalties for leaving the preferred side,
/// crossing other leaders or obstacles and covering the `soft` areas.
class LabelPlacer {
 public:
  /// `anchors[i]`: the pixels request i may point at (the best is picked; none: not placed);
  /// `fixed`: boxes already there (captions, an inset); `dots`: more anchor dots to keep clear,
  /// besides those of `requests`; `width` x `height`: the area; `where`: its name in errors.
  LabelPlacer(std::vector<LabelRequest> requests, std::vector<std::vector<Pixel>> anchors,
              std::vector<PlacedLabel> fixed, const std::vector<Pixel>& dots,
              std::vector<LabelObstacle> obstacles, std::vector<RectF> soft,
              const LabelStyle& style, int width, int height, std::string where);

  /// Every label that has an anchor, by request. The labels go in one by one, then each is
  /// taken out and put back where it is now best (four rounds), so that the early ones also
  /// make way for the later ones; that in the order given and in the reverse order, and the
  /// cheaper whole wins. Throws RunError ("no room for <name> in <where>") when a label has no
  /// place at all.
  std::vector<std::optional<PlacedLabel>> Place();

  /// Up to `count` places for label i alone (Place not called), cheapest first, none of them
  /// nearer another than half the box's size, with what each costs.
  std::vector<std::pair<PlacedLabel, double>> Alternatives(size_t i, size_t count) const;

  /// What the labels placed cost together (each crossing counted from both sides).
  double TotalCost() const;

 private:
  struct Option {
    PlacedLabel label;
    double cost;
  };
  static bool Cheaper(const Option& a, const Option& b) { return a.cost < b.cost; }

  void PlaceInOrder(const std::vector<size_t>& order);
  std::vector<const PlacedLabel*> Others(size_t i) const;
  std::vector<Option> Options(size_t i) const;
  std::optional<double> Cost(const LabelRequest& r, Pixel a, const RectF& box,
                             const std::vector<const PlacedLabel*>& others,
                             bool obstacles_hard) const;

  const std::vector<LabelRequest> requests_;
  const std::vector<std::vector<Pixel>> anchors_;
  const std::vector<PlacedLabel> fixed_;
  const std::vector<LabelObstacle> obstacles_;
  const std::vector<RectF> soft_;
  const LabelStyle st_;
  const int width_, height_;
  const std::string where_;
  std::vector<RectF> dots_;                         // the anchor dots' clear zones
  std::vector<std::optional<PlacedLabel>> placed_;  // by request
};

/// Draws `labels` onto `canvas`: the leaders and anchor dots first (a `rim` coloured outline,
/// then their colour), so that no line crosses a box, then each box (`rim` blended at
/// `box_alpha`) with its text.
void DrawLabels(const std::vector<PlacedLabel>& labels, const LabelStyle& style, Rgb rim,
                double box_alpha, Canvas* canvas);

}  // namespace fetchscope
