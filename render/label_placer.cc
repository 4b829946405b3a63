#include "render/label_placer.h"

#include <algorithm>
#include <cmath>

#include "base/errors.h"

namespace fetchscope {
namespace {

std::string Name(const LabelRequest& r) {
  return !r.name.empty() ? r.name : "the label '" + r.text.substr(0, r.text.find('\n')) + "'";
}

}  // namespace

RectF TextBox(const std::string& text, const LabelStyle& style, double x, double y) {
  const TextMetrics m = Font::Default().Measure(text, style.text_pixels);
  return {x, y, x + m.width + 2.0 * style.padding, y + m.height + 2.0 * style.padding};
}

LabelPlacer::LabelPlacer(std::vector<LabelRequest> requests,
                         std::vector<std::vector<Pixel>> anchors, std::vector<PlacedLabel> fixed,
                         const std::vector<Pixel>& dots, std::vector<LabelObstacle> obstacles,
                         std::vector<RectF> soft, const LabelStyle& style, int width, int height,
                         std::string where)
    : requests_(std::move(requests)),
      anchors_(std::move(anchors)),
      fixed_(std::move(fixed)),
      obstacles_(std::move(obstacles)),
      soft_(std::move(soft)),
      st_(style),
      width_(width),
      height_(height),
      where_(std::move(where)),
      placed_(requests_.size()) {
  // every anchor dot is kept clear, those of labels not yet placed included
  std::vector<Pixel> all = dots;
  for (size_t i = 0; i < requests_.size(); ++i) {
    if (requests_[i].dot) all.insert(all.end(), anchors_[i].begin(), anchors_[i].end());
  }
  const double r = st_.dot + st_.outline + st_.gap;
  for (const Pixel& a : all) dots_.push_back({a.x - r, a.y - r, a.x + r, a.y + r});
}

std::vector<std::optional<PlacedLabel>> LabelPlacer::Place() {
  std::optional<RunError> error;
  std::optional<std::vector<std::optional<PlacedLabel>>> best;
  double best_total = 0;
  for (bool reverse : {false, true}) {
    std::vector<size_t> order(requests_.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = reverse ? order.size() - 1 - i : i;
    try {
      PlaceInOrder(order);
    } catch (const RunError& e) {
      if (!error) error = e;
      continue;
    }
    const double total = TotalCost();
    if (!best || total < best_total) best = placed_, best_total = total;
  }
  if (!best) throw *error;
  placed_ = *best;
  return placed_;
}

std::vector<std::pair<PlacedLabel, double>> LabelPlacer::Alternatives(size_t i,
                                                                      size_t count) const {
  std::vector<Option> options = Options(i);
  std::stable_sort(options.begin(), options.end(), Cheaper);
  std::vector<std::pair<PlacedLabel, double>> out;
  for (const Option& o : options) {
    if (out.size() == count) break;
    const RectF& b = o.label.box;
    bool apart = true;
    for (const auto& [p, cost] : out) {
      apart = apart && (std::abs(p.box.x0 - b.x0) > (b.x1 - b.x0) / 2 ||
                        std::abs(p.box.y0 - b.y0) > (b.y1 - b.y0) / 2);
    }
    if (apart) out.push_back({o.label, o.cost});
  }
  return out;
}

double LabelPlacer::TotalCost() const {
  double total = 0;
  for (size_t i = 0; i < placed_.size(); ++i) {
    if (!placed_[i]) continue;
    total +=
        Cost(requests_[i], *placed_[i]->anchor, placed_[i]->box, Others(i), false).value_or(1e9);
  }
  return total;
}

// A label that finds no room waits for a later round, when the others may have moved.
void LabelPlacer::PlaceInOrder(const std::vector<size_t>& order) {
  placed_.assign(requests_.size(), std::nullopt);
  for (int round = 0; round < 4; ++round) {
    for (size_t i : order) {
      if (anchors_[i].empty()) continue;  // behind the camera: nothing to point at
      std::optional<PlacedLabel> before = std::move(placed_[i]);
      placed_[i].reset();
      const std::vector<Option> options = Options(i);
      if (!options.empty()) {
        placed_[i] = std::min_element(options.begin(), options.end(), Cheaper)->label;
      } else {
        placed_[i] = std::move(before);  // where it fitted before, if it did
      }
    }
  }
  for (size_t i : order) {
    if (!anchors_[i].empty() && !placed_[i]) {
      throw RunError("no room for " + Name(requests_[i]) + " in " + where_);
    }
  }
}

// The fixed boxes and the labels placed so far but label i.
std::vector<const PlacedLabel*> LabelPlacer::Others(size_t i) const {
  std::vector<const PlacedLabel*> others;
  for (const PlacedLabel& p : fixed_) others.push_back(&p);
  for (size_t j = 0; j < placed_.size(); ++j) {
    if (j != i && placed_[j]) others.push_back(&*placed_[j]);
  }
  return others;
}

// The places label i may take among the others placed so far, in a fixed order: off the
// obstacles where there are any such, else anywhere allowed.
std::vector<LabelPlacer::Option> LabelPlacer::Options(size_t i) const {
  const std::vector<const PlacedLabel*> others = Others(i);
  const LabelRequest& r = requests_[i];
  const RectF size =
      r.text.empty() ? RectF{0, 0, r.box_size.x, r.box_size.y} : TextBox(r.text, st_, 0, 0);
  const double w = size.x1, h = size.y1;
  std::vector<Option> options;
  // the grid: half a line, or finer than a 120 x 90 grid over the area
  const double step_x = std::max(st_.text_pixels / 2.0, width_ / 120.0);
  const double step_y = std::max(st_.text_pixels / 2.0, height_ / 90.0);
  for (bool obstacles_hard : {true, false}) {
    for (const Pixel& a : anchors_[i]) {
      auto consider = [&](double x, double y) {
        x = std::round(x), y = std::round(y);
        const RectF box{x, y, x + w, y + h};
        if (const std::optional<double> cost = Cost(r, a, box, others, obstacles_hard)) {
          options.push_back({{r.text, r.color, a, Nearest(box, a), r.dot, box}, *cost});
        }
      };
      // around the anchor: the box's near side or corner at radius `reach`, 32 directions
      for (double reach : {1.0, 1.6, 2.4, 3.4, 4.6, 6.0, 8.0, 10.5}) {
        for (int k = 0; k < 32; ++k) {
          const double angle = k * (2 * M_PI / 32);
          const double cx = std::cos(angle), cy = std::sin(angle);
          const double px = a.x + cx * reach * st_.text_pixels,
                       py = a.y + cy * reach * st_.text_pixels;
          consider(cx > 0.38    ? px
                   : cx < -0.38 ? px - w
                                : px - w / 2,
                   cy > 0.38    ? py
                   : cy < -0.38 ? py - h
                                : py - h / 2);
        }
      }
      // and anywhere in the area: on a grid, and flush with the area's edges, with the
      // other boxes and with the anchor, where the grid may leave too narrow a gap unseen
      std::vector<double> xs, ys;
      for (double x = st_.gap; x + w <= width_ - st_.gap; x += step_x) xs.push_back(x);
      for (double y = st_.gap; y + h <= height_ - st_.gap; y += step_y) ys.push_back(y);
      xs.insert(xs.end(), {width_ - st_.gap - w, a.x, a.x - w, a.x - w / 2});
      ys.insert(ys.end(), {height_ - st_.gap - h, a.y, a.y - h, a.y - h / 2});
      for (const PlacedLabel* p : others) {
        xs.insert(xs.end(), {p->box.x1 + st_.gap, p->box.x0 - st_.gap - w});
        ys.insert(ys.end(), {p->box.y1 + st_.gap, p->box.y0 - st_.gap - h});
      }
      for (double y : ys) {
        for (double x : xs) consider(x, y);
      }
    }
    if (!options.empty()) break;
  }
  return options;
}

// What box `box` for label `r` pointing at `a` costs; none where it may not go.
std::optional<double> LabelPlacer::Cost(const LabelRequest& r, Pixel a, const RectF& box,
                                        const std::vector<const PlacedLabel*>& others,
                                        bool obstacles_hard) const {
  if (box.x0 < st_.gap || box.y0 < st_.gap || box.x1 > width_ - st_.gap ||
      box.y1 > height_ - st_.gap) {
    return std::nullopt;
  }
  const Pixel attach = Nearest(box, a);
  const double leader = Distance(a, attach);
  if (leader < 0.5) return std::nullopt;                       // on its own anchor
  const double line_clear = st_.leader / 2 + st_.outline + 1;  // a leader's reach, rim included
  for (const PlacedLabel* p : others) {
    if (Intersect(box, Grown(p->box, st_.gap))) return std::nullopt;
    if (SegmentHitsRect(a, attach, Grown(p->box, line_clear))) return std::nullopt;
    if (p->anchor && SegmentHitsRect(*p->anchor, p->attach, Grown(box, line_clear))) {
      return std::nullopt;
    }
  }
  // the leader leaves its own dot: test it from where it leaves the dot's clear zone
  const double skip =
      std::min(leader, std::max(r.clear, r.dot ? st_.dot + st_.outline + st_.gap + 1 : 1.0));
  const Pixel from{a.x + (attach.x - a.x) * skip / leader, a.y + (attach.y - a.y) * skip / leader};
  for (const RectF& d : dots_) {
    if (Intersect(box, d)) return std::nullopt;
    if (SegmentHitsRect(from, attach, Grown(d, -st_.gap))) return std::nullopt;
  }
  double cost = leader / st_.scale;
  if (leader < 0.8 * st_.text_pixels) cost += 60;  // a box right on its anchor reads badly
  const double angle = std::atan2(attach.y - a.y, attach.x - a.x) * 180 / M_PI;
  cost += 0.4 * std::abs(std::remainder(angle - r.direction, 360.0));
  for (const PlacedLabel* p : others) {
    if (p->anchor && SegmentsCross(a, attach, *p->anchor, p->attach)) cost += 400;
  }
  for (const LabelObstacle& m : obstacles_) {
    if (SegmentHitsRect(m.a, m.b, Grown(box, m.half_width + 1))) {
      if (obstacles_hard) return std::nullopt;
      cost += 5000;
    }
    if (SegmentsCross(from, attach, m.a, m.b)) cost += 250;
    // a leader along an obstacle hides in it
    const Pixel middle{(from.x + attach.x) / 2, (from.y + attach.y) / 2};
    const double near = m.half_width + st_.leader;
    if (DistanceToSegment(middle, m.a, m.b) < near && DistanceToSegment(attach, m.a, m.b) < near) {
      cost += 250;
    }
  }
  for (const RectF& s : soft_) cost += 2.0 * OverlapArea(box, s) / (st_.scale * st_.scale);
  return cost;
}

void DrawLabels(const std::vector<PlacedLabel>& labels, const LabelStyle& st, Rgb rim,
                double box_alpha, Canvas* canvas) {
  // leaders and dots first, so that no line crosses a box
  for (int pass = 0; pass < 2; ++pass) {
    const double grow = pass == 0 ? st.outline : 0;
    for (const PlacedLabel& l : labels) {
      if (!l.anchor) continue;
      const Rgb c = pass == 0 ? rim : l.color;
      canvas->Capsule(*l.anchor, l.attach, st.leader + 2 * grow, c);
      if (l.dot) canvas->Disc(*l.anchor, st.dot + grow, c);
    }
  }
  for (const PlacedLabel& l : labels) {
    const int x = static_cast<int>(l.box.x0), y = static_cast<int>(l.box.y0);
    canvas->FillRect(x, y, static_cast<int>(l.box.x1 - l.box.x0),
                     static_cast<int>(l.box.y1 - l.box.y0), rim, box_alpha);
    canvas->Text(x + st.padding, y + st.padding, l.text, st.text_pixels, l.color);
  }
}

}  // namespace fetchscope
