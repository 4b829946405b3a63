#include "inspect/anatomy_card.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "base/atomic_file.h"
#include "base/errors.h"
#include "base/json_util.h"
#include "encode/png_io.h"
#include "inspect/anatomy_content.h"
#include "render/camera.h"
#include "render/canvas.h"
#include "render/label_placer.h"
#include "render/overlay.h"
#include "render/projection.h"
#include "src/env_spec.h"
#include "src/episode.h"
#include "src/observation_layout.h"
#include "src/policy.h"

namespace fetchscope {
namespace {

// The card is designed at 720 x 540 per panel, with 15 px text.
constexpr int kDesignWidth = 720, kDesignHeight = 540, kDesignTextPixels = 15;
constexpr double kBoxAlpha = 0.8;  // label boxes: kCardDark at this opacity

// Label sizes (LabelStyle: text, padding, gap, leader, outline, dot) and the markers' own.
struct CardStyle : LabelStyle {
  double shaft;        // arrow shaft width
  double head_length;  // arrow head, along the arrow
  double head_width;   // arrow head, across
  double thin;         // bracket and extension line width
  double tick;         // bracket end tick, half length
};

// A marker and where it is in the pixels.
struct ProjectedMarker {
  CardMarker marker;
  Pixel a, b;
  double half_width;  // how far from the segment it draws, rim included
};

// The markers as what labels keep off.
std::vector<LabelObstacle> Obstacles(const std::vector<ProjectedMarker>& markers) {
  std::vector<LabelObstacle> out;
  for (const ProjectedMarker& m : markers) out.push_back({m.a, m.b, m.half_width});
  return out;
}

// The placer's requests for `labels` (their anchors come separately).
std::vector<LabelRequest> Requests(const std::vector<CardLabel>& labels) {
  std::vector<LabelRequest> out;
  for (const CardLabel& l : labels) {
    LabelRequest r;
    r.text = l.text;
    r.color = l.color;
    r.direction = l.direction;
    r.dot = l.dot;
    out.push_back(r);
  }
  return out;
}

// A RunError of the placer as the card's: what to do about it.
[[noreturn]] void ThrowNoRoom(const RunError& e) {
  throw RunError(std::string("anatomy card: ") + e.what() + "; give a larger --width/--height");
}

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

// Draws the markers: all the dark rims first, then the colours, so that lines that meet merge.
void DrawMarkers(const std::vector<ProjectedMarker>& markers, const CardStyle& st, Canvas* canvas) {
  for (int pass = 0; pass < 2; ++pass) {
    const double rim = pass == 0 ? st.outline : 0;
    for (const ProjectedMarker& pm : markers) {
      const CardMarker& m = pm.marker;
      const Rgb c = pass == 0 ? kCardDark : m.color;
      const Pixel a = pm.a, b = pm.b;
      const double len = Distance(a, b);
      if (len < 1e-6) continue;
      const double ux = (b.x - a.x) / len, uy = (b.y - a.y) / len;
      switch (m.kind) {
        case CardMarkerKind::kLine:
          canvas->Capsule(a, b, (m.thin ? std::max(1.5, st.thin * 0.75) : st.thin) + 2 * rim, c);
          break;
        case CardMarkerKind::kBracket: {
          canvas->Capsule(a, b, st.thin + 2 * rim, c);
          for (const Pixel& end : {a, b}) {
            canvas->Capsule({end.x - uy * st.tick, end.y + ux * st.tick},
                            {end.x + uy * st.tick, end.y - ux * st.tick}, st.thin + 2 * rim, c);
          }
          break;
        }
        case CardMarkerKind::kArrow: {
          canvas->Arrow(a, b, {st.shaft, st.head_length, st.head_width}, rim, c);
          break;
        }
      }
    }
  }
}

// One panel: its pixels, cameras, and what was drawn where.
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
  View(GlContext& gl, FetchEnv& fetch, const StepRecord& reset, int msaa_samples,
       const std::string& camera, int width, int height, const std::vector<CardSphere>& spheres,
       bool show_goal = true)
      : camera_(camera), width_(width), height_(height) {
    // as `render --camera CAMERA --overlay none` renders it
    RenderOptions options;
    options.width = width;
    options.height = height;
    options.cameras = ParseCameraList(camera, fetch.model());
    options.overlays = ParseOverlays("none");
    options.msaa_samples = msaa_samples;
    options.extra_geoms = [spheres](mjvScene* scene) {
      for (const CardSphere& g : spheres) {
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
    // no overlay is drawn: the goal (where the target0 marker goes) and the achieved goal are
    // all the renderer reads of the frame's description
    FrameInfo info;
    info.step = reset.t;
    info.goal = reset.obs.desired_goal;
    info.achieved = reset.obs.achieved_goal;
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
std::vector<ProjectedMarker> ProjectMarkers(const std::vector<CardMarker>& markers,
                                            const View& view, const CardStyle& st,
                                            Pixel offset = {0, 0}) {
  std::vector<ProjectedMarker> out;
  for (const CardMarker& m : markers) {
    const auto a = view.Project(m.from), b = view.Project(m.to);
    if (!a || !b) continue;
    const double half = m.kind == CardMarkerKind::kArrow ? 0.5 * std::max(st.shaft, st.head_width)
                        : m.kind == CardMarkerKind::kBracket ? st.tick
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
                                  const CardContent& content, const CardStyle& st, int h) {
  const std::string title = spec.id + " after reset(seed=" + seed + ")\nobservation[" +
                            std::to_string(ObservationSize(spec.has_object)) + "], action[4]\n" +
                            content.action_note;
  RectF footer = TextBox(content.footer, st, st.gap, 0);
  footer = {footer.x0, h - st.gap - footer.y1, footer.x1, h - st.gap - 0.0};
  return {{title, kCardWhite, std::nullopt, {}, false, TextBox(title, st, st.gap, st.gap)},
          {content.footer, kCardWhite, std::nullopt, {}, false, footer}};
}

// Where each label's candidate anchors are in `view` (none for those out of view).
std::vector<std::vector<Pixel>> Anchors(const std::vector<CardLabel>& labels, const View& view) {
  std::vector<std::vector<Pixel>> anchors;
  for (const CardLabel& r : labels) {
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

Detail MakeDetail(GlContext& gl, FetchEnv& fetch, const StepRecord& reset, int msaa_samples,
                  const CardContent& content, const CardStyle& st, int dw, int dh,
                  const std::string& where) {
  Detail d;
  d.view = std::make_unique<View>(
      gl, fetch, reset, msaa_samples,
      DetailCamera(content.detail_at, content.detail_distance, content.detail_across), dw, dh,
      std::vector<CardSphere>{},
      /*show_goal=*/false);  // the goal beyond the fingers is no part of them
  Canvas canvas(d.view->rgb().data(), dw, dh);
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
  LabelPlacer placer(Requests(content.detail_labels), Anchors(content.detail_labels, *d.view), {},
                     {}, Obstacles(d.markers), fingers, st, dw, dh, where);
  std::vector<std::optional<PlacedLabel>> placed;
  try {
    placed = placer.Place();
  } catch (const RunError& e) {
    ThrowNoRoom(e);
  }
  for (const auto& l : placed) {
    if (l) d.labels.push_back(*l);
  }
  DrawLabels(d.labels, st, kCardDark, kBoxAlpha, &canvas);
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
    ring.segments.push_back({{"detail ring", CardMarkerKind::kLine, {}, {}, kCardWhite, true},
                             {c.x + r * std::cos(a0), c.y + r * std::sin(a0)},
                             {c.x + r * std::cos(a1), c.y + r * std::sin(a1)},
                             0.5 * st.thin + st.outline});
  }
  return ring;
}

// What a panel's labels are placed among: the markers, the ring, the anchor dots and (as far as
// they can) the translucent spheres, and the labels' requests and anchors.
struct PanelLayout {
  std::vector<ProjectedMarker> markers;
  Ring ring;
  std::vector<LabelObstacle> obstacles;
  std::vector<RectF> soft;
  std::vector<LabelRequest> requests;
  std::vector<std::vector<Pixel>> anchors;
  std::vector<Pixel> dots;
};

PanelLayout LayOut(const CardContent& content, const View& main, const CameraAxes& axes,
                   const CardStyle& st) {
  PanelLayout in;
  in.markers = ProjectMarkers(content.markers, main, st);
  in.ring = RingAround(content.detail_keep, main, st);
  in.obstacles = Obstacles(in.markers);
  for (const LabelObstacle& o : Obstacles(in.ring.segments)) in.obstacles.push_back(o);
  for (const CardSphere& g : content.spheres) {
    const auto c = main.Project(g.at), edge = main.Project(Add(g.at, axes.up, g.radius));
    if (!c || !edge) continue;
    const double r = Distance(*c, *edge);
    in.soft.push_back({c->x - r, c->y - r, c->x + r, c->y + r});
  }
  in.requests = Requests(content.labels);
  in.anchors = Anchors(content.labels, main);
  for (size_t i = 0; i < in.anchors.size(); ++i) {
    if (content.labels[i].dot) {
      in.dots.insert(in.dots.end(), in.anchors[i].begin(), in.anchors[i].end());
    }
  }
  return in;
}

// The detail view is a label without text that points at the ring's centre: the few best
// places for it alone are tried, each with the labels placed around it, and the cheapest whole
// wins. Returns its place; `placed` gets the labels'.
PlacedLabel PlaceDetail(const PanelLayout& in, const std::vector<PlacedLabel>& captions,
                        const CardStyle& st, int dw, int dh, int w, int h, const std::string& where,
                        std::vector<std::optional<PlacedLabel>>* placed) {
  LabelRequest detail_request;
  detail_request.color = kCardWhite;
  detail_request.dot = false;
  detail_request.name = "the fingers' detail view";
  detail_request.box_size = {dw + 4.0, dh + 4.0};  // with its rim
  detail_request.clear = in.ring.radius;
  const std::vector<std::vector<Pixel>> detail_anchor = {
      in.ring.segments.empty() ? std::vector<Pixel>{} : std::vector<Pixel>{in.ring.centre}};
  std::optional<PlacedLabel> detail_place;
  double best_total = 0;
  for (const auto& [place, cost] : LabelPlacer({detail_request}, detail_anchor, captions, in.dots,
                                               in.obstacles, in.soft, st, w, h, where)
                                       .Alternatives(0, 12)) {
    std::vector<PlacedLabel> fixed = captions;
    fixed.push_back(place);
    LabelPlacer placer(in.requests, in.anchors, fixed, {}, in.obstacles, in.soft, st, w, h, where);
    std::vector<std::optional<PlacedLabel>> labels;
    try {
      labels = placer.Place();
    } catch (const RunError&) {
      continue;  // no room for the labels around this one
    }
    const double total = cost + placer.TotalCost();
    if (!detail_place || total < best_total) {
      best_total = total;
      detail_place = place;
      *placed = std::move(labels);
    }
  }
  if (!detail_place) {
    // say which label lacks room when even without the detail view there is none
    try {
      LabelPlacer(in.requests, in.anchors, captions, {}, in.obstacles, in.soft, st, w, h, where)
          .Place();
    } catch (const RunError& e) {
      ThrowNoRoom(e);
    }
    throw RunError("anatomy card: no room for the fingers' detail view in " + where +
                   "; give a larger --width/--height");
  }
  return *detail_place;
}

// Draws the ring and the line from it to the detail view, the markers, the detail view with a
// rim and the labels on the main view; the panel with what was drawn where, in its pixels.
Panel DrawPanel(const std::string& env_id, View& main, const Detail& detail, PanelLayout in,
                const std::vector<PlacedLabel>& captions, const PlacedLabel& detail_place,
                const std::vector<std::optional<PlacedLabel>>& placed, const CardStyle& st, int dw,
                int dh) {
  Canvas canvas(main.rgb().data(), main.width(), main.height());
  DrawMarkers(in.ring.segments, st, &canvas);
  const Pixel a = *detail_place.anchor, b = detail_place.attach;
  const double leave = std::min(1.0, in.ring.radius / std::max(1e-9, Distance(a, b)));
  DrawMarkers({{{"detail link", CardMarkerKind::kLine, {}, {}, kCardWhite, true},
                {a.x + leave * (b.x - a.x), a.y + leave * (b.y - a.y)},
                b,
                0}},
              st, &canvas);
  DrawMarkers(in.markers, st, &canvas);
  const int x0 = static_cast<int>(detail_place.box.x0) + 2;
  const int y0 = static_cast<int>(detail_place.box.y0) + 2;
  canvas.FillRect(x0 - 2, y0 - 2, dw + 4, dh + 4, kCardDark, 1.0);
  canvas.FillRect(x0 - 1, y0 - 1, dw + 2, dh + 2, kCardWhite, 1.0);
  canvas.Paste(detail.view->rgb().data(), dw, dh, x0, y0);
  std::vector<PlacedLabel> labels = captions;
  for (const auto& l : placed) {
    if (l) labels.push_back(*l);
  }
  DrawLabels(labels, st, kCardDark, kBoxAlpha, &canvas);

  Panel panel;
  panel.env_id = env_id;
  panel.camera = main.camera();
  panel.detail_camera = detail.view->camera();
  panel.detail_box = {double(x0), double(y0), double(x0 + dw), double(y0 + dh)};
  panel.markers = std::move(in.markers);
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

Panel RenderPanel(const std::string& env_id, const AnatomyCardOptions& o, GlContext& gl) {
  const EnvSpec& spec = FindEnvSpec(env_id);
  FetchEnv fetch(spec, ResolveAssets(o.assets));
  PolicyContext context;
  context.seed = o.seed;
  auto policy = MakePolicy("zero", spec, context);
  const EpisodeRecord episode = RunEpisode(fetch, *policy, 0, context.seed, 0);
  const StepRecord& reset = episode.steps.back();
  auto content_for = [&](const Vec3& view_up) { return PanelContentFor(fetch, reset, view_up); };
  const int w = o.width, h = o.height;
  const CardStyle st = StyleFor(w, h);

  // the main view; then the content again, now that the camera's up is known
  const CardContent framing = content_for({0, 0, 1});
  View main(gl, fetch, reset, o.msaa_samples, FramingCamera(framing.points, w, h), w, h,
            framing.spheres);
  const CameraAxes axes = main.axes();
  const CardContent content = content_for(axes.up);
  const std::vector<PlacedLabel> captions = Captions(spec, o.seed_text, content, st, h);
  // the detail view: 259 x 216 at the design size, scaled as the text
  const int dw = static_cast<int>(std::lround(0.36 * kDesignWidth * st.scale));
  const int dh = static_cast<int>(std::lround(0.4 * kDesignHeight * st.scale));
  const std::string where = "a " + std::to_string(w) + "x" + std::to_string(h) + " panel";
  const Detail detail = MakeDetail(gl, fetch, reset, o.msaa_samples, content, st, dw, dh,
                                   "the fingers' detail view of " + where);

  PanelLayout in = LayOut(content, main, axes, st);
  std::vector<std::optional<PlacedLabel>> placed;
  const PlacedLabel detail_place = PlaceDetail(in, captions, st, dw, dh, w, h, where, &placed);
  return DrawPanel(env_id, main, detail, std::move(in), captions, detail_place, placed, st, dw, dh);
}

nlohmann::json RgbJson(Rgb c) { return {c.r, c.g, c.b}; }

nlohmann::json BoxJson(const RectF& r, int left) {
  return {static_cast<int>(r.x0) + left, static_cast<int>(r.y0), static_cast<int>(r.x1 - r.x0),
          static_cast<int>(r.y1 - r.y0)};
}

const char* KindName(CardMarkerKind kind) {
  switch (kind) {
    case CardMarkerKind::kArrow:
      return "arrow";
    case CardMarkerKind::kLine:
      return "line";
    case CardMarkerKind::kBracket:
      return "bracket";
  }
  return "";
}

}  // namespace

void WriteAnatomyCard(const std::string& dir, const AnatomyCardOptions& o, GlContext& gl) {
  std::vector<Panel> panels;
  for (const char* id : {"FetchReach-v4", "FetchPush-v4"}) panels.push_back(RenderPanel(id, o, gl));
  const int w = o.width, h = o.height;
  const CardStyle st = StyleFor(w, h);
  const int card_width = w * static_cast<int>(panels.size());
  std::vector<uint8_t> card(static_cast<size_t>(card_width) * h * 3);
  Canvas canvas(card.data(), card_width, h);
  nlohmann::json panels_json = nlohmann::json::array(), labels_json = nlohmann::json::array(),
                 markers_json = nlohmann::json::array();
  for (size_t p = 0; p < panels.size(); ++p) {
    const int left = static_cast<int>(p) * w;
    canvas.Paste(panels[p].rgb.data(), w, h, left, 0);
    panels_json.push_back(
        {{"env_id", panels[p].env_id},
         {"seed", o.seed_text},
         {"assets", o.assets},
         {"camera", panels[p].camera},
         {"overlay", "none"},
         {"msaa", o.msaa},
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
  const nlohmann::json labels = {
      {"image", "ch01_anatomy.png"},   {"width", card_width},     {"height", h},
      {"text_pixels", st.text_pixels}, {"line_width", st.leader}, {"panels", panels_json},
      {"labels", labels_json},         {"markers", markers_json}};
  WriteJson(sidecar, labels);
  std::printf("wrote %s\nwrote %s\n", png.c_str(), sidecar.c_str());
}

}  // namespace fetchscope
