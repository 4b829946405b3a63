// fetchscope anatomy: the chapter's deliverables in one command (D1 describe, D2 reward check,
// D3 random baseline, the D4 answers) and the anatomy card: a labelled Reach frame and a
// labelled Push frame that show where each observation slice and each action component lives.
//
// Each panel is rendered with two translucent scene geoms (the success shell, the object's
// halo); everything else is drawn in 2D over the rendered pixels after projecting its 3D points
// (render/projection.h), so that no arrow or axis hides inside the robot. The fingers, a few
// pixels wide in the main view, get a magnified detail view of their own (ringed in the main
// view) with the finger-width bracket and the a[3] arrows. LabelPlacer puts every label inside
// its panel, off the other labels, leaders, anchor dots and markers, and never lets a leader
// cross another label. Text, lines, arrow heads, spacing and the detail view scale with the
// panel (CardStyle), so a larger card is the same card, sharper; below 480 x 360 the text would
// be under 10 px and `--width/--height` refuse it.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "base/errors.h"
#include "base/json_util.h"
#include "cli/chapter.h"
#include "cli/command.h"
#include "cli/common.h"
#include "encode/png_io.h"
#include "render/projection.h"
#include "render/renderer.h"
#include "render/text.h"
#include "render/view.h"
#include "src/episode.h"
#include "src/policy.h"

namespace fetchscope::cli {
namespace {

// ---- sizes: everything drawn on the card scales with the panel --------------------------------

// The card is designed at 720 x 540 per panel, with 15 px text.
constexpr int kDesignWidth = 720, kDesignHeight = 540, kDesignTextPixels = 15;
// The smallest panel: 10 px text, the smallest that stays legible, and room for every label.
constexpr int kMinPanelWidth = 480, kMinPanelHeight = 360;
constexpr int kMaxPanelSize = 4096;

struct CardStyle {
  double scale;        // of the design size: the smaller of width / 720 and height / 540
  int text_pixels;     // em size of the label text
  int padding;         // text to box edge
  int gap;             // least space between two boxes, and between a box and the panel's edge
  double leader;       // leader line width
  double outline;      // dark rim on each side of lines, arrows and dots
  double shaft;        // arrow shaft width
  double head_length;  // arrow head, along the arrow
  double head_width;   // arrow head, across
  double thin;         // bracket and extension line width
  double tick;         // bracket end tick, half length
  double dot;          // anchor dot radius
};

CardStyle StyleFor(int width, int height) {
  const double s = std::min(static_cast<double>(width) / kDesignWidth,
                            static_cast<double>(height) / kDesignHeight);
  CardStyle c;
  c.scale = s;
  c.text_pixels = static_cast<int>(std::lround(kDesignTextPixels * s));
  c.padding = std::max(2, static_cast<int>(std::lround(4 * s)));
  c.gap = std::max(3, static_cast<int>(std::lround(6 * s)));
  c.leader = std::max(1.5, 2.0 * s);
  c.outline = std::max(1.0, 1.5 * s);
  c.shaft = std::max(2.5, 4.0 * s);
  c.head_length = 16 * s;
  c.head_width = 13 * s;
  c.thin = std::max(1.5, 2.0 * s);
  c.tick = 7 * s;
  c.dot = std::max(2.5, 3.5 * s);
  return c;
}

// ---- anti-aliased 2D drawing on RGB24 frames (row 0 = top; pixel (i, j)'s centre at i + 0.5) --

struct RectF {
  double x0, y0, x1, y1;  // pixels, x0 <= x1, y0 <= y1
};

RectF Grown(const RectF& r, double d) { return {r.x0 - d, r.y0 - d, r.x1 + d, r.y1 + d}; }

bool Intersect(const RectF& a, const RectF& b) {
  return a.x0 < b.x1 && b.x0 < a.x1 && a.y0 < b.y1 && b.y0 < a.y1;
}

double OverlapArea(const RectF& a, const RectF& b) {
  const double w = std::min(a.x1, b.x1) - std::max(a.x0, b.x0);
  const double h = std::min(a.y1, b.y1) - std::max(a.y0, b.y0);
  return w > 0 && h > 0 ? w * h : 0;
}

// Segment a-b cut to rectangle r (Liang-Barsky); none when it misses r.
std::optional<std::pair<Pixel, Pixel>> ClipSegment(Pixel a, Pixel b, const RectF& r) {
  double t0 = 0, t1 = 1;
  const double dx = b.x - a.x, dy = b.y - a.y;
  const double p[4] = {-dx, dx, -dy, dy};
  const double q[4] = {a.x - r.x0, r.x1 - a.x, a.y - r.y0, r.y1 - a.y};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0) {
      if (q[i] < 0) return std::nullopt;
    } else {
      const double t = q[i] / p[i];
      if (p[i] < 0)
        t0 = std::max(t0, t);
      else
        t1 = std::min(t1, t);
      if (t0 > t1) return std::nullopt;
    }
  }
  return std::make_pair(Pixel{a.x + t0 * dx, a.y + t0 * dy}, Pixel{a.x + t1 * dx, a.y + t1 * dy});
}

// Whether segment a-b meets rectangle r.
bool SegmentHitsRect(Pixel a, Pixel b, const RectF& r) { return ClipSegment(a, b, r).has_value(); }

// Whether segments a-b and c-d cross (touching ends do not count).
bool SegmentsCross(Pixel a, Pixel b, Pixel c, Pixel d) {
  auto side = [](Pixel p, Pixel q, Pixel r) {
    return (q.x - p.x) * (r.y - p.y) - (q.y - p.y) * (r.x - p.x);
  };
  const double d1 = side(c, d, a), d2 = side(c, d, b), d3 = side(a, b, c), d4 = side(a, b, d);
  return d1 * d2 < 0 && d3 * d4 < 0;
}

double Distance(Pixel a, Pixel b) { return std::hypot(b.x - a.x, b.y - a.y); }

// How far p is from segment a-b.
double DistanceToSegment(Pixel p, Pixel a, Pixel b) {
  const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
  const double t =
      len2 > 0 ? std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / len2, 0.0, 1.0) : 0;
  return Distance(p, {a.x + t * dx, a.y + t * dy});
}

class Canvas {
 public:
  Canvas(std::vector<uint8_t>* rgb, int width, int height)
      : rgb_(rgb), width_(width), height_(height) {}

  int width() const { return width_; }
  int height() const { return height_; }

  void Blend(int x, int y, Rgb c, double alpha) {
    if (x < 0 || y < 0 || x >= width_ || y >= height_ || alpha <= 0) return;
    uint8_t* p = rgb_->data() + (static_cast<size_t>(y) * width_ + x) * 3;
    const uint8_t src[3] = {c.r, c.g, c.b};
    for (int k = 0; k < 3; ++k) {
      p[k] = static_cast<uint8_t>(std::lround((1 - alpha) * p[k] + alpha * src[k]));
    }
  }

  void FillRect(int x, int y, int w, int h, Rgb c, double alpha) {
    for (int row = std::max(0, y); row < std::min(height_, y + h); ++row) {
      for (int col = std::max(0, x); col < std::min(width_, x + w); ++col)
        Blend(col, row, c, alpha);
    }
  }

  // A segment `width` pixels wide with round ends (a disc when a == b).
  void Capsule(Pixel a, Pixel b, double width, Rgb c) {
    const double r = width / 2;
    const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
    ForEachPixel(
        {std::min(a.x, b.x) - r, std::min(a.y, b.y) - r, std::max(a.x, b.x) + r,
         std::max(a.y, b.y) + r},
        [&](double px, double py) {
          double t = len2 > 0 ? ((px - a.x) * dx + (py - a.y) * dy) / len2 : 0;
          t = std::clamp(t, 0.0, 1.0);
          const double d = std::hypot(px - a.x - t * dx, py - a.y - t * dy);
          return std::clamp(r + 0.5 - d, 0.0, 1.0);
        },
        c);
  }

  // The triangle p0 p1 p2 grown by `grow` pixels on every side.
  void Triangle(Pixel p0, Pixel p1, Pixel p2, double grow, Rgb c) {
    const Pixel p[3] = {p0, p1, p2};
    const double area = (p1.x - p0.x) * (p2.y - p0.y) - (p1.y - p0.y) * (p2.x - p0.x);
    if (std::abs(area) < 1e-9) return;
    const double sign = area > 0 ? 1 : -1;
    const double margin = grow * 3;  // the grown corners reach out further than `grow`
    ForEachPixel(
        {std::min({p0.x, p1.x, p2.x}) - margin, std::min({p0.y, p1.y, p2.y}) - margin,
         std::max({p0.x, p1.x, p2.x}) + margin, std::max({p0.y, p1.y, p2.y}) + margin},
        [&](double px, double py) {
          double inside = 1e300;  // distance to the nearest edge, > 0 inside
          for (int i = 0; i < 3; ++i) {
            const Pixel a = p[i], b = p[(i + 1) % 3];
            const double ex = b.x - a.x, ey = b.y - a.y, len = std::hypot(ex, ey);
            inside = std::min(inside, sign * (ex * (py - a.y) - ey * (px - a.x)) / len);
          }
          return std::clamp(inside + grow + 0.5, 0.0, 1.0);
        },
        c);
  }

  void Text(int x, int y, const std::string& text, int pixel_size, Rgb c) {
    TextStyle style;
    style.pixel_size = pixel_size;
    style.color = c;
    Font::Default().Draw(rgb_->data(), width_, height_, x, y, text, style);
  }

 private:
  // Blends `c` into the pixels of `r` by coverage(centre x, centre y).
  template <typename Coverage>
  void ForEachPixel(const RectF& r, Coverage coverage, Rgb c) {
    const int x0 = std::max(0, static_cast<int>(std::floor(r.x0 - 1)));
    const int y0 = std::max(0, static_cast<int>(std::floor(r.y0 - 1)));
    const int x1 = std::min(width_ - 1, static_cast<int>(std::ceil(r.x1 + 1)));
    const int y1 = std::min(height_ - 1, static_cast<int>(std::ceil(r.y1 + 1)));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) Blend(x, y, c, coverage(x + 0.5, y + 0.5));
    }
  }

  std::vector<uint8_t>* rgb_;
  int width_, height_;
};

// ---- what a panel shows -------------------------------------------------------------------------

using Vec3 = std::array<double, 3>;

Vec3 Add(const Vec3& a, const Vec3& b, double scale = 1.0) {
  return {a[0] + scale * b[0], a[1] + scale * b[1], a[2] + scale * b[2]};
}

Vec3 Mid(const Vec3& a, const Vec3& b) { return Add(a, Add(b, a, -1.0), 0.5); }

Vec3 Unit(const Vec3& v) {
  const double n = std::max(1e-12, std::hypot(v[0], v[1], v[2]));
  return {v[0] / n, v[1] / n, v[2] / n};
}

// marker and label colours (labels: text on a dark box)
constexpr Rgb kWhite{255, 255, 255}, kRed{255, 80, 80}, kGreen{60, 235, 60}, kBlue{90, 150, 255},
    kYellow{255, 220, 60}, kOrange{255, 150, 30}, kCyan{60, 225, 255}, kMagenta{255, 100, 255},
    kGoalRed{255, 110, 110};
constexpr Rgb kDark{20, 20, 28};  // label boxes and the rims of everything drawn
constexpr double kBoxAlpha = 0.8;

enum class MarkerKind {
  kArrow,    // from -> to with a head at `to`
  kLine,     // plain line
  kBracket,  // a dimension line with end ticks
};

// One thing drawn in 2D over the frame, between two world points.
struct Marker {
  std::string name;  // for the sidecar: what it draws
  MarkerKind kind;
  Vec3 from, to;
  Rgb color;
  bool thin = false;  // a thin line (extension lines)
};

// A label and the 3D point it names; the placer picks the best of `at` when there are several.
struct LabelRequest {
  std::string text;  // empty for a box of `box_size` (the detail view)
  std::vector<Vec3> at;
  Rgb color;
  double direction;  // preferred side of the anchor, degrees in the image (0 right, 90 down)
  bool dot = true;   // mark the anchor with a dot (not where it is an arrow's tip or a line)
  Pixel box_size{};  // the box's size when there is no text
  double clear = 0;  // pixels around the anchor that the leader may cross (the detail's ring)
};

struct Geom {
  Vec3 at;
  double radius;  // m
  Rgb color;
  float alpha;
};

// The markers and labels of one panel, from the reset observation. The fingers are small in
// the main view: they have a magnified detail view of their own, placed beside it, with their
// labels inside it.
struct PanelContent {
  std::vector<Geom> spheres;                // translucent scene geoms
  std::vector<Marker> markers;              // drawn in 2D over the main view, in this order
  std::vector<LabelRequest> labels;         // placed in this order
  std::vector<Marker> detail_markers;       // drawn over the detail view
  std::vector<LabelRequest> detail_labels;  // placed inside the detail view
  std::vector<Vec3> detail_keep;            // what the detail's labels should leave uncovered
  Vec3 detail_at;                           // what the detail view looks at
  double detail_distance;                   // from how far, m
  Vec3 detail_across;                       // the line it looks across (the fingers')
  std::vector<Vec3> points;                 // what the camera must show
  std::string footer;                       // the slices without a place in the scene
  std::string action_note;                  // what the arrows' length means
};

// Where body `name` is in `env`'s current state; `fallback` when the model lacks it.
Vec3 BodyPosition(const FetchEnv& env, const char* name, const Vec3& fallback) {
  const int id = mj_name2id(env.model(), mjOBJ_BODY, name);
  const mjtNum* x = env.data()->xpos;
  return id < 0 ? fallback : Vec3{x[3 * id], x[3 * id + 1], x[3 * id + 2]};
}

std::string Fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

// The parts both panels have: grip_pos with the axes that a[0:3] move it along, the fingers with
// their width and the a[3] arrows, the goal and its success shell (`view_up`: the camera's up,
// so that the radius line ends on the shell's outline). `arrow_scale`: how many times 0.05 m
// (one unit of a[0:3]) the arrows are drawn.
PanelContent CommonContent(const FetchEnv& env, const StepRecord& s, const Vec3& view_up,
                           int arrow_scale) {
  const EnvSpec& spec = env.spec();
  const bool obj = spec.has_object;
  const auto& o = s.obs.observation;
  const Vec3 grip = {o[0], o[1], o[2]};
  const Vec3 goal = s.obs.desired_goal;
  const Vec3 right = BodyPosition(env, "robot0:r_gripper_finger_link", grip);
  const Vec3 left = BodyPosition(env, "robot0:l_gripper_finger_link", grip);
  const double threshold = spec.distance_threshold;
  const double arrow = 0.05 * arrow_scale;
  const Vec3 ax = Add(grip, {arrow, 0, 0}), ay = Add(grip, {0, arrow, 0}),
             az = Add(grip, {0, 0, arrow});
  // the finger bracket hangs just below the finger tips (3.85 cm below the finger bodies'
  // origins); a[3] > 0 would move each finger outward along the line between them
  const Vec3 drop = {0, 0, -0.047};
  const Vec3 left_low = Add(left, drop), right_low = Add(right, drop);
  const Vec3 open = Unit(Add(left, right, -1.0));
  const Vec3 left_open = Add(left_low, open, 0.04), right_open = Add(right_low, open, -0.04);
  const Vec3 shell_edge = Add(goal, view_up, threshold);
  const int r_index = obj ? 9 : 3;  // obs[r_index] r, obs[r_index + 1] l
  const double width = o[r_index] + o[r_index + 1];

  PanelContent c;
  c.spheres = {{goal, threshold, kGoalRed, 0.25f}};
  c.detail_markers = {
      {"finger r extension", MarkerKind::kLine, right, right_low, kYellow, true},
      {"finger l extension", MarkerKind::kLine, left, left_low, kYellow, true},
      {"finger width", MarkerKind::kBracket, right_low, left_low, kYellow},
      {"a[3] r", MarkerKind::kArrow, right_low, right_open, kMagenta},
      {"a[3] l", MarkerKind::kArrow, left_low, left_open, kMagenta},
  };
  // fingers in the upper half, their labels below them
  c.detail_at = Add(Mid(left, right), {0, 0, -0.075});
  c.detail_distance = 0.15;
  c.detail_across = open;
  c.detail_keep = {right, left, right_low, left_low};
  c.markers = {
      {"shell radius", MarkerKind::kLine, goal, shell_edge, kWhite},
      {"a[0] x", MarkerKind::kArrow, grip, ax, kRed},
      {"a[1] y", MarkerKind::kArrow, grip, ay, kGreen},
      {"a[2] z", MarkerKind::kArrow, grip, az, kBlue},
  };
  const std::string r = "obs[" + std::to_string(r_index) + "]",
                    l = "obs[" + std::to_string(r_index + 1) + "]";
  c.labels = {
      {"grip_pos " + ObservationSlice(obj, "grip_pos") + (obj ? "" : "\n= achieved_goal"),
       {grip},
       kCyan,
       200},
      {"x obs[0] \xc2\xb7 a[0]", {ax}, kRed, 60, false},
      {"y obs[1] \xc2\xb7 a[1]", {ay}, kGreen, -30, false},
      {"z obs[2] \xc2\xb7 a[2]", {az}, kBlue, -30, false},

      {"desired_goal (goal)", {goal}, kGoalRed, 60},
      {"success shell\nr = " + Fixed(threshold, 2) + " m", {shell_edge}, kWhite, -45},
  };
  c.detail_labels = {
      {"finger width\n" + r + " r + " + l + " l\n= " + Fixed(width, 3) + " m" +
           (width < 0.0005 ? " (closed)" : ""),
       {Mid(left_low, right_low)},
       kYellow,
       90,
       false},
      {std::string("a[3] > 0 opens") + (spec.block_gripper ? "\n(blocked: ignored)" : ""),
       {right_open, left_open},
       kMagenta,
       90,
       false},
  };
  c.points = {grip, goal, ax, ay, az, left_low, right_low, shell_edge};
  c.action_note = "a[0:3]: the target moves 0.05 m per unit\nalong x, y, z (arrows: a = +1, x" +
                  std::to_string(arrow_scale) + ")";
  return c;
}

PanelContent ReachContent(const FetchEnv& env, const StepRecord& s, const Vec3& view_up) {
  PanelContent c = CommonContent(env, s, view_up, 5);
  c.footer = "obs[5:8] grip_velp  obs[8:10] finger vel\n(velocities x dt: per step)";
  return c;
}

PanelContent PushContent(const FetchEnv& env, const StepRecord& s, const Vec3& view_up) {
  PanelContent c = CommonContent(env, s, view_up, 3);
  const auto& o = s.obs.observation;
  const Vec3 grip = {o[0], o[1], o[2]};
  const Vec3 object = {o[3], o[4], o[5]};
  c.spheres.push_back({object, 0.036, kYellow, 0.3f});
  c.markers.insert(c.markers.begin(),
                   {"object_rel_pos", MarkerKind::kArrow, grip, object, kOrange});
  // after grip_pos and its axes
  c.labels.insert(
      c.labels.begin() + 4,
      {{"object_pos " + ObservationSlice(true, "object_pos") + "\n= achieved_goal",
        {object},
        kYellow,
        135},
       {"object_rel_pos " + ObservationSlice(true, "object_rel_pos") + "\n= object - grip",
        {Mid(grip, object)},
        kOrange,
        -135,
        false}});
  c.points.push_back(object);
  c.footer =
      "obs[11:14] object_rot  obs[14:17] object_velp\n"
      "obs[17:20] object_velr  obs[20:23] grip_velp\n"
      "obs[23:25] finger vel  (velocities x dt: per step)";
  return c;
}

// ---- label placement ----------------------------------------------------------------------------

struct PlacedLabel {
  std::string text;
  Rgb color;
  std::optional<Pixel> anchor;  // none for captions
  Pixel attach{};               // where the leader meets the box
  bool dot = false;
  RectF box;  // pixels, row 0 = top
};

struct ProjectedMarker {
  Marker marker;
  Pixel a, b;
  double half_width;  // how far from the segment it draws, rim included
};

RectF TextBox(const std::string& text, const CardStyle& style, double x, double y) {
  const TextMetrics m = Font::Default().Measure(text, style.text_pixels);
  return {x, y, x + m.width + 2.0 * style.padding, y + m.height + 2.0 * style.padding};
}

// The point of `box` nearest to `p`.
Pixel Nearest(const RectF& box, Pixel p) {
  return {std::clamp(p.x, box.x0, box.x1), std::clamp(p.y, box.y0, box.y1)};
}

// Places label boxes near their anchors. A box must lie inside the panel and never on another
// box, on another label's leader or anchor dot, and its leader must not run over another box or
// dot; where there is any such place it must also stay off the markers. Among the places left
// the cheapest wins: the shortest leader, with penalties for leaving the preferred side,
// crossing other leaders or markers and covering the `soft` areas.
class LabelPlacer {
 public:
  // `fixed`: boxes already there (captions, the detail view); `dots`: more anchor dots to keep
  // clear, besides those of `requests`; `where`: the area's name in errors.
  LabelPlacer(const std::vector<LabelRequest>& requests,
              const std::vector<std::vector<Pixel>>& anchors, std::vector<PlacedLabel> fixed,
              const std::vector<Pixel>& dots, const std::vector<ProjectedMarker>& markers,
              const std::vector<RectF>& soft, const CardStyle& style, int width, int height,
              std::string where)
      : requests_(requests),
        anchors_(anchors),
        fixed_(std::move(fixed)),
        markers_(markers),
        soft_(soft),
        st_(style),
        width_(width),
        height_(height),
        where_(std::move(where)),
        placed_(requests.size()) {
    // every anchor dot is kept clear, those of labels not yet placed included
    std::vector<Pixel> all = dots;
    for (size_t i = 0; i < requests_.size(); ++i) {
      if (requests_[i].dot) all.insert(all.end(), anchors_[i].begin(), anchors_[i].end());
    }
    const double r = st_.dot + st_.outline + st_.gap;
    for (const Pixel& a : all) dots_.push_back({a.x - r, a.y - r, a.x + r, a.y + r});
  }

  // Every label that has an anchor in view, by request. The labels go in one by one, then
  // each is taken out and put back where it is now best (twice over), so that the early ones
  // also make way for the later ones; that in the order given and in the reverse order, and
  // the cheaper whole wins. Throws RunError when a label has no place at all (a panel too
  // small for its labels).
  std::vector<std::optional<PlacedLabel>> Place() {
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

  // Up to `count` places for label i alone (Place not called), cheapest first, none of them
  // nearer another than half the box's size, with what each costs.
  std::vector<std::pair<PlacedLabel, double>> Alternatives(size_t i, size_t count) const {
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

  void Dump() const {
    for (size_t i = 0; i < placed_.size(); ++i)
      if (placed_[i])
        fprintf(stderr, "   %-20.20s %8.1f at %g %g\n", requests_[i].text.c_str(),
                *Cost(requests_[i], *placed_[i]->anchor, placed_[i]->box, Others(i), false),
                placed_[i]->box.x0, placed_[i]->box.y0);
  }
  // What the labels placed cost together (each crossing counted from both sides).
  double TotalCost() const {
    double total = 0;
    for (size_t i = 0; i < placed_.size(); ++i) {
      if (!placed_[i]) continue;
      total +=
          Cost(requests_[i], *placed_[i]->anchor, placed_[i]->box, Others(i), false).value_or(1e9);
    }
    return total;
  }

 private:
  // A label that finds no room waits for a later round, when the others may have moved.
  void PlaceInOrder(const std::vector<size_t>& order) {
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
        throw RunError("anatomy card: no room for " + Name(requests_[i]) + " in " + where_ +
                       "; give a larger --width/--height");
      }
    }
  }

  struct Option {
    PlacedLabel label;
    double cost;
  };
  static bool Cheaper(const Option& a, const Option& b) { return a.cost < b.cost; }

  static std::string Name(const LabelRequest& r) {
    return r.text.empty() ? "the fingers' detail view"
                          : "the label '" + r.text.substr(0, r.text.find('\n')) + "'";
  }

  // The fixed boxes and the labels placed so far but label i.
  std::vector<const PlacedLabel*> Others(size_t i) const {
    std::vector<const PlacedLabel*> others;
    for (const PlacedLabel& p : fixed_) others.push_back(&p);
    for (size_t j = 0; j < placed_.size(); ++j) {
      if (j != i && placed_[j]) others.push_back(&*placed_[j]);
    }
    return others;
  }

  // The places label i may take among the others placed so far, in a fixed order: off the
  // markers where there are any such, else anywhere allowed.
  std::vector<Option> Options(size_t i) const {
    const std::vector<const PlacedLabel*> others = Others(i);
    const LabelRequest& r = requests_[i];
    const RectF size =
        r.text.empty() ? RectF{0, 0, r.box_size.x, r.box_size.y} : TextBox(r.text, st_, 0, 0);
    const double w = size.x1, h = size.y1;
    std::vector<Option> options;
    // the grid: half a line, or finer than a 120 x 90 grid over the area
    const double step_x = std::max(st_.text_pixels / 2.0, width_ / 120.0);
    const double step_y = std::max(st_.text_pixels / 2.0, height_ / 90.0);
    for (bool markers_hard : {true, false}) {
      for (const Pixel& a : anchors_[i]) {
        auto consider = [&](double x, double y) {
          x = std::round(x), y = std::round(y);
          const RectF box{x, y, x + w, y + h};
          if (const std::optional<double> cost = Cost(r, a, box, others, markers_hard)) {
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
        // and anywhere in the panel: on a grid, and flush with the panel's edges, with the
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
  std::optional<double> Cost(const LabelRequest& r, Pixel a, const RectF& box,
                             const std::vector<const PlacedLabel*>& others,
                             bool markers_hard) const {
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
    const Pixel from{a.x + (attach.x - a.x) * skip / leader,
                     a.y + (attach.y - a.y) * skip / leader};
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
    for (const ProjectedMarker& m : markers_) {
      if (SegmentHitsRect(m.a, m.b, Grown(box, m.half_width + 1))) {
        if (markers_hard) return std::nullopt;
        cost += 5000;
      }
      if (SegmentsCross(from, attach, m.a, m.b)) cost += 250;
      // a leader along a marker hides in it
      const Pixel middle{(from.x + attach.x) / 2, (from.y + attach.y) / 2};
      const double near = m.half_width + st_.leader;
      if (DistanceToSegment(middle, m.a, m.b) < near &&
          DistanceToSegment(attach, m.a, m.b) < near) {
        cost += 250;
      }
    }
    for (const RectF& s : soft_) cost += 2.0 * OverlapArea(box, s) / (st_.scale * st_.scale);
    return cost;
  }

  const std::vector<LabelRequest>& requests_;
  const std::vector<std::vector<Pixel>>& anchors_;
  const std::vector<PlacedLabel> fixed_;  // the captions
  const std::vector<ProjectedMarker>& markers_;
  const std::vector<RectF>& soft_;
  const CardStyle& st_;
  const int width_, height_;
  const std::string where_;  // the area, for the error
  std::vector<RectF> dots_;
  std::vector<std::optional<PlacedLabel>> placed_;  // by request
};

// ---- drawing ------------------------------------------------------------------------------------

// Draws the markers: all the dark rims first, then the colours, so that lines that meet merge.
void DrawMarkers(const std::vector<ProjectedMarker>& markers, const CardStyle& st, Canvas* canvas) {
  for (int pass = 0; pass < 2; ++pass) {
    const double rim = pass == 0 ? st.outline : 0;
    for (const ProjectedMarker& pm : markers) {
      const Marker& m = pm.marker;
      const Rgb c = pass == 0 ? kDark : m.color;
      const Pixel a = pm.a, b = pm.b;
      const double len = Distance(a, b);
      if (len < 1e-6) continue;
      const double ux = (b.x - a.x) / len, uy = (b.y - a.y) / len;
      switch (m.kind) {
        case MarkerKind::kLine:
          canvas->Capsule(a, b, (m.thin ? std::max(1.5, st.thin * 0.75) : st.thin) + 2 * rim, c);
          break;
        case MarkerKind::kBracket: {
          canvas->Capsule(a, b, st.thin + 2 * rim, c);
          for (const Pixel& end : {a, b}) {
            canvas->Capsule({end.x - uy * st.tick, end.y + ux * st.tick},
                            {end.x + uy * st.tick, end.y - ux * st.tick}, st.thin + 2 * rim, c);
          }
          break;
        }
        case MarkerKind::kArrow: {
          const double head = std::min(st.head_length, 0.5 * len);
          const double half = 0.5 * st.head_width * head / st.head_length;
          const Pixel base{b.x - ux * head, b.y - uy * head};
          canvas->Capsule(a, {base.x + ux * 0.5, base.y + uy * 0.5}, st.shaft + 2 * rim, c);
          canvas->Triangle(b, {base.x - uy * half, base.y + ux * half},
                           {base.x + uy * half, base.y - ux * half}, rim, c);
          break;
        }
      }
    }
  }
}

void DrawLabels(const std::vector<PlacedLabel>& labels, const CardStyle& st, Canvas* canvas) {
  // leaders and dots first, so that no line crosses a box
  for (int pass = 0; pass < 2; ++pass) {
    const double rim = pass == 0 ? st.outline : 0;
    for (const PlacedLabel& l : labels) {
      if (!l.anchor) continue;
      const Rgb c = pass == 0 ? kDark : l.color;
      canvas->Capsule(*l.anchor, l.attach, st.leader + 2 * rim, c);
      if (l.dot) canvas->Capsule(*l.anchor, *l.anchor, 2 * (st.dot + rim), c);
    }
  }
  for (const PlacedLabel& l : labels) {
    const int x = static_cast<int>(l.box.x0), y = static_cast<int>(l.box.y0);
    canvas->FillRect(x, y, static_cast<int>(l.box.x1 - l.box.x0),
                     static_cast<int>(l.box.y1 - l.box.y0), kDark, kBoxAlpha);
    canvas->Text(x + st.padding, y + st.padding, l.text, st.text_pixels, l.color);
  }
}

// ---- the card -----------------------------------------------------------------------------------

struct CardOptions {
  EnvOptions env;    // assets and seed of the frames
  ViewOptions view;  // width, height (per panel), backend, gpu, msaa
};

struct Panel {
  std::string env_id;
  std::string camera;  // as `render --camera` takes it
  std::vector<uint8_t> rgb;
  std::vector<PlacedLabel> labels;
  std::vector<ProjectedMarker> markers;
  std::string detail_camera;  // the fingers' detail view, as `render --camera` takes it
  RectF detail_box;           // where it is in the panel
};

// A free camera that frames `points` from Gymnasium's side of the table in a `width` x
// `height` frame, as a --camera spec (short decimals, so that `render --camera` reproduces it
// exactly). The field of view is vertical: a frame narrower than 4:3 takes the camera further.
std::string FramingCamera(const std::vector<Vec3>& points, int width, int height) {
  Vec3 lo = points[0], hi = points[0];
  for (const Vec3& p : points) {
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
  }
  const double span = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 0.25});
  char buf[200];
  std::snprintf(buf, sizeof(buf),
                "free:lookat=%.3f,%.3f,%.3f,distance=%.2f,azimuth=140,elevation=-24",
                0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2]),
                (0.3 + 1.7 * span) * std::max(1.0, 4.0 * height / (3.0 * width)));
  return buf;
}

// One rendered view of the panel's state: its pixels and its projection.
class View {
 public:
  // `show_goal` false: without the goal marker.
  View(GlContext& gl, FetchEnv& fetch, const StepRecord& reset, const ViewOptions& base,
       const std::string& camera, int width, int height, const std::vector<Geom>& spheres,
       bool show_goal = true)
      : camera_(camera), width_(width), height_(height) {
    ViewOptions view = base;
    view.camera = camera;
    view.overlay = "none";
    view.width = width;
    view.height = height;
    RenderOptions options = MakeRenderOptions(view, fetch.model());
    options.extra_geoms = [spheres](mjvScene* scene) {
      for (const Geom& g : spheres) {
        if (scene->ngeom >= scene->maxgeom) return;
        mjvGeom* geom = scene->geoms + scene->ngeom++;
        const mjtNum size[3] = {g.radius, g.radius, g.radius};
        const mjtNum pos[3] = {g.at[0], g.at[1], g.at[2]};
        const float rgba[4] = {g.color.r / 255.0f, g.color.g / 255.0f, g.color.b / 255.0f, g.alpha};
        mjv_initGeom(geom, mjGEOM_SPHERE, size, pos, nullptr, rgba);
        geom->category = mjCAT_DECOR;
        geom->objtype = mjOBJ_UNKNOWN;
        geom->objid = -1;
        geom->segid = -1;
      }
    };
    renderer_ = std::make_unique<Renderer>(gl, fetch.model(), options);
    rgb_.resize(static_cast<size_t>(width) * height * 3);
    FrameInfo info = MakeFrameInfo(fetch, reset);
    if (!show_goal) info.goal = {0, 0, -100};  // far under the floor, out of view
    renderer_->Render(fetch.data(), info, rgb_.data());
  }

  std::optional<Pixel> Project(const Vec3& p) const {
    return ProjectToPixel(renderer_->scene(), renderer_->tiles()[0], height_, p);
  }
  CameraAxes axes() const { return SceneCameraAxes(renderer_->scene()); }
  std::vector<uint8_t>& rgb() { return rgb_; }
  const std::string& camera() const { return camera_; }
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  std::string camera_;
  int width_, height_;
  std::unique_ptr<Renderer> renderer_;
  std::vector<uint8_t> rgb_;
};

// The markers of `markers` that `view` shows, in pixels shifted by `offset`.
std::vector<ProjectedMarker> ProjectMarkers(const std::vector<Marker>& markers, const View& view,
                                            const CardStyle& st, Pixel offset = {0, 0}) {
  std::vector<ProjectedMarker> out;
  for (const Marker& m : markers) {
    const auto a = view.Project(m.from), b = view.Project(m.to);
    if (!a || !b) continue;
    const double half = m.kind == MarkerKind::kArrow     ? 0.5 * std::max(st.shaft, st.head_width)
                        : m.kind == MarkerKind::kBracket ? st.tick
                                                         : 0.5 * st.thin;
    out.push_back({m,
                   {a->x + offset.x, a->y + offset.y},
                   {b->x + offset.x, b->y + offset.y},
                   half + st.outline});
  }
  return out;
}

// A free camera at `at` from `distance` m that looks across the fingers' axis `across` (so
// that the fingers sit side by side in the image), from the side nearer the main view's.
std::string DetailCamera(const Vec3& at, double distance, const Vec3& across) {
  // a free camera's image x axis is (sin a, -cos a, 0) for azimuth a
  double azimuth = std::atan2(across[0], -across[1]) * 180 / M_PI;
  if (std::abs(std::remainder(azimuth - 140, 360.0)) > 90) azimuth += 180;
  azimuth = std::remainder(azimuth, 360.0);
  char buf[200];
  std::snprintf(buf, sizeof(buf),
                "free:lookat=%.4f,%.4f,%.4f,distance=%.3f,azimuth=%.1f,elevation=-50", at[0], at[1],
                at[2], distance, azimuth);
  return buf;
}

// The captions of a panel: the title and what the arrows mean at the top left, the slices
// without a place in the scene at the bottom left.
std::vector<PlacedLabel> Captions(const EnvSpec& spec, const std::string& seed,
                                  const PanelContent& content, const CardStyle& st, int h) {
  const std::string title = spec.id + " after reset(seed=" + seed + ")\nobservation[" +
                            std::to_string(spec.has_object ? 25 : 10) + "], action[4]\n" +
                            content.action_note;
  RectF footer = TextBox(content.footer, st, st.gap, 0);
  footer = {footer.x0, h - st.gap - footer.y1, footer.x1, h - st.gap - 0.0};
  return {{title, kWhite, std::nullopt, {}, false, TextBox(title, st, st.gap, st.gap)},
          {content.footer, kWhite, std::nullopt, {}, false, footer}};
}

// Where each label's candidate anchors are in `view` (none for those out of view).
std::vector<std::vector<Pixel>> Anchors(const std::vector<LabelRequest>& labels, const View& view) {
  std::vector<std::vector<Pixel>> anchors;
  for (const LabelRequest& r : labels) {
    anchors.emplace_back();
    for (const Vec3& at : r.at) {
      if (const auto p = view.Project(at)) anchors.back().push_back(*p);
    }
  }
  return anchors;
}

// The fingers' detail view with its markers and labels drawn on its own pixels (so that they
// stay inside it); their positions in its pixels.
struct Detail {
  std::unique_ptr<View> view;
  std::vector<ProjectedMarker> markers;
  std::vector<PlacedLabel> labels;
};

Detail MakeDetail(GlContext& gl, FetchEnv& fetch, const StepRecord& reset, const ViewOptions& base,
                  const PanelContent& content, const CardStyle& st, int dw, int dh,
                  const std::string& where) {
  Detail d;
  d.view = std::make_unique<View>(
      gl, fetch, reset, base,
      DetailCamera(content.detail_at, content.detail_distance, content.detail_across), dw, dh,
      std::vector<Geom>{}, /*show_goal=*/false);  // the goal beyond the fingers is no part of them
  Canvas canvas(&d.view->rgb(), dw, dh);
  d.markers = ProjectMarkers(content.detail_markers, *d.view, st);
  DrawMarkers(d.markers, st, &canvas);
  std::vector<RectF> fingers;  // better left uncovered
  for (const Vec3& at : content.detail_keep) {
    if (const auto p = d.view->Project(at)) {
      if (fingers.empty()) fingers.push_back({p->x, p->y, p->x, p->y});
      RectF& f = fingers[0];
      f = {std::min(f.x0, p->x), std::min(f.y0, p->y), std::max(f.x1, p->x), std::max(f.y1, p->y)};
    }
  }
  for (const auto& l : LabelPlacer(content.detail_labels, Anchors(content.detail_labels, *d.view),
                                   {}, {}, d.markers, fingers, st, dw, dh, where)
                           .Place()) {
    if (l) d.labels.push_back(*l);
  }
  DrawLabels(d.labels, st, &canvas);
  return d;
}

// A ring in the main view around `points` (what the detail view shows), as line segments.
struct Ring {
  Pixel centre{0, 0};
  double radius = 0;
  std::vector<ProjectedMarker> segments;
};

Ring RingAround(const std::vector<Vec3>& points, const View& view, const CardStyle& st) {
  std::vector<Pixel> seen;
  for (const Vec3& at : points) {
    if (const auto p = view.Project(at)) seen.push_back(*p);
  }
  Ring ring;
  if (seen.empty()) return ring;
  for (const Pixel& p : seen) {
    ring.centre = {ring.centre.x + p.x / seen.size(), ring.centre.y + p.y / seen.size()};
  }
  for (const Pixel& p : seen) ring.radius = std::max(ring.radius, Distance(ring.centre, p));
  ring.radius += 4 * st.scale;
  constexpr int kSides = 32;
  for (int k = 0; k < kSides; ++k) {
    const double a0 = 2 * M_PI * k / kSides, a1 = 2 * M_PI * (k + 1) / kSides;
    const Pixel c = ring.centre;
    const double r = ring.radius;
    ring.segments.push_back({{"detail ring", MarkerKind::kLine, {}, {}, kWhite, true},
                             {c.x + r * std::cos(a0), c.y + r * std::sin(a0)},
                             {c.x + r * std::cos(a1), c.y + r * std::sin(a1)},
                             0.5 * st.thin + st.outline});
  }
  return ring;
}

Panel RenderPanel(const std::string& env_id, const CardOptions& o, GlContext& gl) {
  const EnvSpec& spec = FindEnvSpec(env_id);
  FetchEnv fetch(spec, ResolveAssets(o.env.assets));
  PolicyContext context;
  context.seed = ParseSeed(o.env.seed);
  auto policy = MakePolicy("zero", spec, context);
  const EpisodeRecord episode = RunEpisode(fetch, *policy, 0, context.seed, 0);
  const StepRecord& reset = episode.steps.back();
  auto content_for = [&](const Vec3& view_up) {
    return spec.has_object ? PushContent(fetch, reset, view_up)
                           : ReachContent(fetch, reset, view_up);
  };
  const int w = o.view.width, h = o.view.height;
  const CardStyle st = StyleFor(w, h);

  // the main view; then the content again, now that the camera's up is known
  const PanelContent framing = content_for({0, 0, 1});
  View main(gl, fetch, reset, o.view, FramingCamera(framing.points, w, h), w, h, framing.spheres);
  const CameraAxes axes = main.axes();
  const PanelContent content = content_for(axes.up);
  const std::vector<PlacedLabel> captions = Captions(spec, o.env.seed, content, st, h);
  // the detail view: 259 x 216 at the design size, scaled as the text
  const int dw = static_cast<int>(std::lround(0.36 * kDesignWidth * st.scale));
  const int dh = static_cast<int>(std::lround(0.4 * kDesignHeight * st.scale));
  const std::string where = "a " + std::to_string(w) + "x" + std::to_string(h) + " panel";
  const Detail detail = MakeDetail(gl, fetch, reset, o.view, content, st, dw, dh,
                                   "the fingers' detail view of " + where);

  // what the labels keep off: the markers, the ring, the anchor dots and (as far as they can)
  // the translucent spheres
  std::vector<ProjectedMarker> markers = ProjectMarkers(content.markers, main, st);
  const Ring ring = RingAround(content.detail_keep, main, st);
  std::vector<ProjectedMarker> obstacles = markers;
  obstacles.insert(obstacles.end(), ring.segments.begin(), ring.segments.end());
  std::vector<RectF> soft;
  for (const Geom& g : content.spheres) {
    const auto c = main.Project(g.at), edge = main.Project(Add(g.at, axes.up, g.radius));
    if (!c || !edge) continue;
    const double r = Distance(*c, *edge);
    soft.push_back({c->x - r, c->y - r, c->x + r, c->y + r});
  }
  const std::vector<std::vector<Pixel>> anchors = Anchors(content.labels, main);
  std::vector<Pixel> dots;
  for (size_t i = 0; i < anchors.size(); ++i) {
    if (content.labels[i].dot) dots.insert(dots.end(), anchors[i].begin(), anchors[i].end());
  }

  // the detail view is a label without text that points at the ring's centre: the few best
  // places for it alone are tried, each with the labels placed around it, and the cheapest
  // whole wins
  LabelRequest detail_request{"", {}, kWhite, 0, false};
  detail_request.box_size = {dw + 4.0, dh + 4.0};  // with its rim
  detail_request.clear = ring.radius;
  const std::vector<std::vector<Pixel>> detail_anchor = {
      ring.segments.empty() ? std::vector<Pixel>{} : std::vector<Pixel>{ring.centre}};
  std::optional<PlacedLabel> detail_place;
  std::vector<std::optional<PlacedLabel>> placed;
  double best_total = 0;
  for (const auto& [place, cost] : LabelPlacer({detail_request}, detail_anchor, captions, dots,
                                               obstacles, soft, st, w, h, where)
                                       .Alternatives(0, 12)) {
    std::vector<PlacedLabel> fixed = captions;
    fixed.push_back(place);
    LabelPlacer placer(content.labels, anchors, fixed, {}, obstacles, soft, st, w, h, where);
    std::vector<std::optional<PlacedLabel>> labels;
    try {
      labels = placer.Place();
    } catch (const RunError& e) {
      if (getenv("DBG")) fprintf(stderr, "fail %g %g %s\n", place.box.x0, place.box.y0, e.what());
      continue;  // no room for the labels around this one
    }
    const double total = cost + placer.TotalCost();
    if (getenv("DBG")) {
      fprintf(stderr, "alt %g %g cost %g total %g\n", place.box.x0, place.box.y0, cost, total);
      placer.Dump();
    }
    if (!detail_place || total < best_total) {
      best_total = total;
      detail_place = place;
      placed = std::move(labels);
    }
  }
  if (!detail_place) {
    // say which label lacks room when even without the detail view there is none
    LabelPlacer(content.labels, anchors, captions, {}, obstacles, soft, st, w, h, where).Place();
    throw RunError("anatomy card: no room for the fingers' detail view in " + where +
                   "; give a larger --width/--height");
  }

  // draw: the ring and the line from it to the detail view, the markers, the detail view with
  // a rim, the labels
  Canvas canvas(&main.rgb(), w, h);
  DrawMarkers(ring.segments, st, &canvas);
  const Pixel a = *detail_place->anchor, b = detail_place->attach;
  const double leave = std::min(1.0, ring.radius / std::max(1e-9, Distance(a, b)));
  DrawMarkers({{{"detail link", MarkerKind::kLine, {}, {}, kWhite, true},
                {a.x + leave * (b.x - a.x), a.y + leave * (b.y - a.y)},
                b,
                0}},
              st, &canvas);
  DrawMarkers(markers, st, &canvas);
  const int x0 = static_cast<int>(detail_place->box.x0) + 2;
  const int y0 = static_cast<int>(detail_place->box.y0) + 2;
  canvas.FillRect(x0 - 2, y0 - 2, dw + 4, dh + 4, kDark, 1.0);
  canvas.FillRect(x0 - 1, y0 - 1, dw + 2, dh + 2, kWhite, 1.0);
  for (int row = 0; row < dh; ++row) {
    std::copy_n(detail.view->rgb().data() + static_cast<size_t>(row) * dw * 3, dw * 3,
                main.rgb().data() + (static_cast<size_t>(y0 + row) * w + x0) * 3);
  }
  std::vector<PlacedLabel> labels = captions;
  for (const auto& l : placed) {
    if (l) labels.push_back(*l);
  }
  DrawLabels(labels, st, &canvas);

  Panel panel;
  panel.env_id = env_id;
  panel.camera = main.camera();
  panel.detail_camera = detail.view->camera();
  panel.detail_box = {double(x0), double(y0), double(x0 + dw), double(y0 + dh)};
  panel.markers = std::move(markers);
  panel.labels = std::move(labels);
  // the detail's markers (as far as it shows them) and labels, in the panel's pixels
  auto shift = [&](Pixel p) { return Pixel{p.x + x0, p.y + y0}; };
  for (ProjectedMarker m : detail.markers) {
    const auto shown = ClipSegment(m.a, m.b, {0, 0, double(dw), double(dh)});
    if (!shown) continue;
    m.a = shift(shown->first), m.b = shift(shown->second);
    panel.markers.push_back(m);
  }
  for (PlacedLabel l : detail.labels) {
    l.box = {l.box.x0 + x0, l.box.y0 + y0, l.box.x1 + x0, l.box.y1 + y0};
    if (l.anchor) l.anchor = shift(*l.anchor);
    l.attach = shift(l.attach);
    panel.labels.push_back(l);
  }
  panel.rgb = std::move(main.rgb());
  return panel;
}

nlohmann::json RgbJson(Rgb c) { return {c.r, c.g, c.b}; }

nlohmann::json BoxJson(const RectF& r, int left) {
  return {static_cast<int>(r.x0) + left, static_cast<int>(r.y0), static_cast<int>(r.x1 - r.x0),
          static_cast<int>(r.y1 - r.y0)};
}

const char* KindName(MarkerKind kind) {
  switch (kind) {
    case MarkerKind::kArrow:
      return "arrow";
    case MarkerKind::kLine:
      return "line";
    case MarkerKind::kBracket:
      return "bracket";
  }
  return "";
}

// Writes DIR/ch01_anatomy.png (Reach | Push) and DIR/ch01_anatomy_labels.json.
void WriteAnatomyCard(const std::string& dir, const CardOptions& o) {
  auto gl = CreateViewContext(o.view, ResolveGpuChoice(o.view));
  std::vector<Panel> panels;
  for (const char* id : {"FetchReach-v4", "FetchPush-v4"})
    panels.push_back(RenderPanel(id, o, *gl));
  const int w = o.view.width, h = o.view.height;
  const CardStyle st = StyleFor(w, h);
  const int card_width = w * static_cast<int>(panels.size());
  std::vector<uint8_t> card(static_cast<size_t>(card_width) * h * 3);
  nlohmann::json panels_json = nlohmann::json::array(), labels_json = nlohmann::json::array(),
                 markers_json = nlohmann::json::array();
  for (size_t p = 0; p < panels.size(); ++p) {
    const int left = static_cast<int>(p) * w;
    for (int row = 0; row < h; ++row) {
      std::copy_n(panels[p].rgb.data() + static_cast<size_t>(row) * w * 3, w * 3,
                  card.data() + (static_cast<size_t>(row) * card_width + left) * 3);
    }
    panels_json.push_back(
        {{"env_id", panels[p].env_id},
         {"seed", o.env.seed},
         {"assets", o.env.assets},
         {"camera", panels[p].camera},
         {"overlay", "none"},
         {"msaa", o.view.msaa},
         {"box", {left, 0, w, h}},
         {"detail",
          {{"camera", panels[p].detail_camera}, {"box", BoxJson(panels[p].detail_box, left)}}}});
    for (const PlacedLabel& l : panels[p].labels) {
      nlohmann::json label = {{"panel", p},
                              {"text", l.text},
                              {"color", RgbJson(l.color)},
                              {"box", BoxJson(l.box, left)}};
      label["anchor"] =
          l.anchor ? nlohmann::json{left + l.anchor->x, l.anchor->y} : nlohmann::json(nullptr);
      label["leader"] =
          l.anchor ? nlohmann::json{left + l.anchor->x, l.anchor->y, left + l.attach.x, l.attach.y}
                   : nlohmann::json(nullptr);
      labels_json.push_back(label);
    }
    for (const ProjectedMarker& m : panels[p].markers) {
      markers_json.push_back({{"panel", p},
                              {"name", m.marker.name},
                              {"kind", KindName(m.marker.kind)},
                              {"color", RgbJson(m.marker.color)},
                              {"from", {left + m.a.x, m.a.y}},
                              {"to", {left + m.b.x, m.b.y}},
                              {"from_world", m.marker.from},
                              {"to_world", m.marker.to}});
    }
  }
  const std::string png = (std::filesystem::path(dir) / "ch01_anatomy.png").string();
  const std::string sidecar = (std::filesystem::path(dir) / "ch01_anatomy_labels.json").string();
  WritePng(png, card_width, h, 3, 8, card.data());
  WriteJson(sidecar, {{"image", "ch01_anatomy.png"},
                      {"width", card_width},
                      {"height", h},
                      {"text_pixels", st.text_pixels},
                      {"line_width", st.leader},
                      {"panels", panels_json},
                      {"labels", labels_json},
                      {"markers", markers_json}});
  std::printf("wrote %s\nwrote %s\n", png.c_str(), sidecar.c_str());
}

struct AnatomyOptions {
  EnvOptions env;
  std::string out = "results";
  CardOptions card;
  bool no_card = false;
};

int RunAnatomy(AnatomyOptions o) {
  const EnvSpec& spec = FindEnvSpec(o.env.env_id);  // bad input fails before any file
  ParseSeed(o.env.seed);
  ParseMsaa(o.card.view.msaa);
  const std::string prefix = (std::filesystem::path(o.out) / "ch01").string();
  std::printf("D1 (describe, %s)\n", spec.id.c_str());
  DescribeOptions describe;
  describe.env = o.env;
  describe.json_out = prefix + "_env";
  RunDescribe(describe);
  std::printf("\nD2 (reward-check)\n");
  RewardCheckOptions check;
  check.env = o.env;
  check.json_out = prefix;
  const bool pass = RunRewardCheck(check);
  std::printf("\nD3 (random-episodes)\n");
  RandomEpisodesOptions random;
  random.env = o.env;
  random.json_out = prefix;
  if (const int status = RunRandomEpisodes(random); status != 0) return status;  // interrupted

  std::printf("\nD4 answers (%s)\n", spec.id.c_str());
  FetchEnv fetch(spec, ResolveAssets(o.env.assets));
  const nlohmann::json answers = DescribeJson(fetch)["answers"];
  for (const auto& [key, value] : answers.items()) {
    std::printf("  %-22s %s\n", key.c_str(),
                value.is_string() ? value.get<std::string>().c_str() : DumpJson(value, -1).c_str());
  }
  if (!o.no_card) {
    std::printf("\nanatomy card (FetchReach-v4 and FetchPush-v4)\n");
    o.card.env = o.env;
    WriteAnatomyCard(o.out, o.card);
  }
  if (!pass) {
    std::printf("\nD2 FAILED: see %s_reward_check.json\n", prefix.c_str());
    return 1;
  }
  return 0;
}

}  // namespace

Command AddAnatomy(CLI::App& app) {
  auto o = std::make_shared<AnatomyOptions>();
  o->card.view.width = 720;
  o->card.view.height = 540;
  CLI::App* sub = app.add_subcommand(
      "anatomy",
      "The chapter's deliverables in one go: OUT/ch01_env_describe.json (D1), "
      "OUT/ch01_reward_check.json (D2), OUT/ch01_random_metrics.json (D3), the D4 answers, and "
      "the anatomy card OUT/ch01_anatomy.png (labelled Reach and Push frames) with "
      "OUT/ch01_anatomy_labels.json (each label's text, box and leader line and each marker's "
      "ends, "
      "in pixels)");
  AddEnvOptions(sub, &o->env);
  sub->add_option("--out", o->out, "Folder for the files (created if missing)")
      ->capture_default_str();
  // below 480 x 360 the labels would need text under 10 px, too small to read
  sub->add_option("--width", o->card.view.width,
                  "Width of each of the card's two frames, pixels (480 to 4096; text, lines and "
                  "arrows scale with the frame)")
      ->capture_default_str()
      ->check(CLI::Range(kMinPanelWidth, kMaxPanelSize));
  sub->add_option("--height", o->card.view.height, "Height of the card, pixels (360 to 4096)")
      ->capture_default_str()
      ->check(CLI::Range(kMinPanelHeight, kMaxPanelSize));
  sub->add_option("--backend", o->card.view.backend,
                  "auto (EGL, then OSMesa), egl or osmesa; default: $MUJOCO_GL, else auto");
  sub->add_option("--msaa", o->card.view.msaa, "Anti-aliasing samples of the card, as render's")
      ->capture_default_str();
  sub->add_flag("--no-card", o->no_card, "Skip the anatomy card (no rendering, no GL needed)");
  return {sub, [o] { return RunAnatomy(*o); }};
}

}  // namespace fetchscope::cli
