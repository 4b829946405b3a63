// fetchscope anatomy: the chapter's deliverables in one command (D1 describe, D2 reward check,
// D3 random baseline, the D4 answers) and the anatomy card: a labelled Reach frame and a
// labelled Push frame that show where each observation slice and each action component lives.
//
// Markers are MuJoCo scene geoms added after mjv_updateScene (Renderer's extra_geoms hook);
// labels are drawn in 2D after projecting their 3D anchor to pixels (render/projection.h).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <optional>

#include "cli/chapter.h"
#include "cli/common.h"
#include "cli/render_common.h"
#include "render/text.h"
#include "render/png_io.h"
#include "render/projection.h"
#include "render/renderer.h"
#include "src/episode.h"
#include "src/errors.h"
#include "src/json_util.h"
#include "src/policy.h"

namespace fetchscope::cli {
namespace {

// ---- text: the one place that draws and measures label text -----------------------------------
// (DejaVu Sans through FreeType, render/text.h)

constexpr int kTextPixels = 15;  // em size: about 9 px per character, 18 px per line

struct TextSize {
  int width;
  int height;
};

TextSize MeasureText(const std::string& text) {
  const TextMetrics m = Font::Default().Measure(text, kTextPixels);
  return {m.width, m.height};
}

void DrawLabelText(std::vector<uint8_t>* rgb, int width, int height, int x, int y,
                   const std::string& text, Rgb color) {
  TextStyle style;
  style.pixel_size = kTextPixels;
  style.color = color;
  Font::Default().Draw(rgb->data(), width, height, x, y, text, style);
}

// ---- 2D drawing on RGB24 frames (row 0 = top) --------------------------------------------------

void BlendPixel(std::vector<uint8_t>* rgb, int width, int height, int x, int y, Rgb c,
                double alpha) {
  if (x < 0 || y < 0 || x >= width || y >= height) return;
  uint8_t* p = rgb->data() + (static_cast<size_t>(y) * width + x) * 3;
  const uint8_t src[3] = {c.r, c.g, c.b};
  for (int k = 0; k < 3; ++k) {
    p[k] = static_cast<uint8_t>(std::lround((1 - alpha) * p[k] + alpha * src[k]));
  }
}

void FillRect(std::vector<uint8_t>* rgb, int width, int height, int x, int y, int w, int h, Rgb c,
              double alpha) {
  for (int row = y; row < y + h; ++row) {
    for (int col = x; col < x + w; ++col) BlendPixel(rgb, width, height, col, row, c, alpha);
  }
}

// A line `thickness` pixels wide (square brush), endpoints included.
void DrawLine(std::vector<uint8_t>* rgb, int width, int height, Pixel a, Pixel b, Rgb c,
              int thickness) {
  const double dx = b.x - a.x, dy = b.y - a.y;
  const int steps = std::max(1, static_cast<int>(std::ceil(std::max(std::abs(dx), std::abs(dy)))));
  for (int i = 0; i <= steps; ++i) {
    const int x = static_cast<int>(std::lround(a.x + dx * i / steps));
    const int y = static_cast<int>(std::lround(a.y + dy * i / steps));
    FillRect(rgb, width, height, x - thickness / 2, y - thickness / 2, thickness, thickness, c, 1.0);
  }
}

// ---- scene markers (decor geoms, as render/overlay.cc adds its own) ----------------------------

using Vec3 = std::array<double, 3>;

struct Rgba {
  float r, g, b, a;
};

mjvGeom* NewGeom(mjvScene* scene, int type, const Vec3& size, const Vec3& pos, Rgba c) {
  if (scene->ngeom >= scene->maxgeom) return nullptr;
  mjvGeom* g = scene->geoms + scene->ngeom++;
  const mjtNum s[3] = {size[0], size[1], size[2]}, p[3] = {pos[0], pos[1], pos[2]};
  const float rgba[4] = {c.r, c.g, c.b, c.a};
  mjv_initGeom(g, type, s, p, nullptr, rgba);
  g->category = mjCAT_DECOR;
  g->objtype = mjOBJ_UNKNOWN;
  g->objid = -1;
  g->segid = -1;
  return g;
}

void AddSphere(mjvScene* scene, const Vec3& at, double radius, Rgba c) {
  NewGeom(scene, mjGEOM_SPHERE, {radius, radius, radius}, at, c);
}

// mjGEOM_ARROW (width in m) or mjGEOM_LINE (width in pixels) from a to b.
void AddConnector(mjvScene* scene, int type, double width, const Vec3& a, const Vec3& b, Rgba c) {
  const double length = std::hypot(b[0] - a[0], b[1] - a[1], b[2] - a[2]);
  if (length < 1e-6) return;
  mjvGeom* g = NewGeom(scene, type, {0, 0, 0}, {0, 0, 0}, c);
  if (!g) return;
  mjv_makeConnector(g, type, width, a[0], a[1], a[2], b[0], b[1], b[2]);
  // MuJoCo 2.2's renderer draws an arrow over half of size[2] (shaft to size/3, cone to size/2),
  // while the connector sets size[2] to the whole length: double it so the tip lands on b
  if (type == mjGEOM_ARROW) g->size[2] *= 2;
}

Vec3 Add(const Vec3& a, const Vec3& b, double scale = 1.0) {
  return {a[0] + scale * b[0], a[1] + scale * b[1], a[2] + scale * b[2]};
}

Vec3 Mid(const Vec3& a, const Vec3& b) { return Add(a, Add(b, a, -1.0), 0.5); }

// ---- the card -----------------------------------------------------------------------------------

// label colours (text on a dark box) and their marker colours
constexpr Rgb kWhite{255, 255, 255}, kRed{255, 90, 90}, kGreen{110, 230, 110},
    kBlue{120, 170, 255}, kYellow{255, 220, 60}, kOrange{255, 160, 40}, kCyan{80, 220, 255},
    kMagenta{255, 110, 255};
constexpr Rgb kBoxColor{20, 20, 28};
constexpr double kBoxAlpha = 0.78;
constexpr int kPadding = 4;

Rgba Opaque(Rgb c) { return {c.r / 255.0f, c.g / 255.0f, c.b / 255.0f, 1.0f}; }
Rgba Translucent(Rgb c, float alpha) { return {c.r / 255.0f, c.g / 255.0f, c.b / 255.0f, alpha}; }

// What a label says and which 3D point it names (none: a caption, placed at `caption_at`).
struct LabelRequest {
  std::string text;
  std::optional<Vec3> at;
  Rgb color;
  Pixel offset;       // preferred box position relative to the anchor (sign gives the side)
  Pixel caption_at{};  // top-left corner for captions
};

struct PlacedLabel {
  std::string text;
  Rgb color;
  std::optional<Pixel> anchor;
  int x, y, w, h;  // the box, pixels, row 0 = top
};

// A rectangle in pixels (row 0 = top) that a label should not cover.
struct Rect {
  int x, y, w, h;
};

long OverlapArea(const Rect& a, const Rect& b) {
  const long w = std::min(a.x + a.w, b.x + b.w) - std::max(a.x, b.x);
  const long h = std::min(a.y + a.h, b.y + b.h) - std::max(a.y, b.y);
  return w > 0 && h > 0 ? w * h : 0;
}

// Places each label's box near its anchor, inside the frame, off the other labels and as far
// as it can off the obstacles (the anchors and the markers' lines): the candidate positions
// around the anchor, nearest first, are scored by how much they cover.
std::vector<PlacedLabel> PlaceLabels(const std::vector<LabelRequest>& requests,
                                     const std::vector<std::optional<Pixel>>& anchors,
                                     const std::vector<Rect>& obstacles, int width, int height) {
  std::vector<PlacedLabel> placed;
  for (size_t i = 0; i < requests.size(); ++i) {
    const LabelRequest& r = requests[i];
    const TextSize size = MeasureText(r.text);
    const int w = size.width + 2 * kPadding, h = size.height + 2 * kPadding;
    if (!r.at) {
      placed.push_back({r.text, r.color, std::nullopt, static_cast<int>(r.caption_at.x),
                        static_cast<int>(r.caption_at.y), w, h});
      continue;
    }
    if (!anchors[i]) continue;  // behind the camera: nothing to point at
    const Pixel a = *anchors[i];
    double best_score = 1e300;
    Rect best{0, 0, w, h};
    const double base = std::hypot(r.offset.x, r.offset.y);
    const double preferred = std::atan2(r.offset.y, r.offset.x);
    for (double reach : {1.0, 1.5, 2.2, 3.0, 4.0}) {
      for (int k = 0; k < 16; ++k) {
        const double angle = preferred + k * (2 * M_PI / 16);
        const double ox = std::cos(angle) * base * reach, oy = std::sin(angle) * base * reach;
        // the box hangs off the anchor on the offset's side, centred when nearly vertical
        int x = static_cast<int>(std::lround(ox >= 0 ? a.x + ox : a.x + ox - w));
        if (std::abs(ox) < 0.3 * base * reach) x = static_cast<int>(std::lround(a.x + ox - w / 2.0));
        const int y = static_cast<int>(std::lround(oy >= 0 ? a.y + oy : a.y + oy - h));
        if (x < 0 || y < 0 || x + w > width || y + h > height) continue;
        const Rect box{x, y, w, h};
        double score = reach * 200 + (k == 0 ? 0 : 100);
        for (const PlacedLabel& p : placed) score += 50.0 * OverlapArea(box, {p.x, p.y, p.w, p.h});
        for (const Rect& o : obstacles) score += 5.0 * OverlapArea(box, o);
        if (score < best_score) best_score = score, best = box;
      }
    }
    placed.push_back({r.text, r.color, a, best.x, best.y, best.w, best.h});
  }
  return placed;
}

void DrawLabels(const std::vector<PlacedLabel>& labels, std::vector<uint8_t>* rgb, int width,
                int height) {
  // leader lines first, so that no line crosses a box
  for (const PlacedLabel& l : labels) {
    if (!l.anchor) continue;
    const Pixel a = *l.anchor;
    const Pixel to{std::clamp(a.x, double(l.x), double(l.x + l.w - 1)),
                   std::clamp(a.y, double(l.y), double(l.y + l.h - 1))};
    DrawLine(rgb, width, height, a, to, kBoxColor, 4);
    DrawLine(rgb, width, height, a, to, l.color, 2);
    FillRect(rgb, width, height, int(a.x) - 3, int(a.y) - 3, 7, 7, kBoxColor, 1.0);
    FillRect(rgb, width, height, int(a.x) - 2, int(a.y) - 2, 5, 5, l.color, 1.0);
  }
  for (const PlacedLabel& l : labels) {
    FillRect(rgb, width, height, l.x, l.y, l.w, l.h, kBoxColor, kBoxAlpha);
    DrawLabelText(rgb, width, height, l.x + kPadding, l.y + kPadding, l.text, l.color);
  }
}

struct CardOptions {
  EnvOptions env;       // assets and seed of the frames
  ViewOptions view;     // width, height (per panel), backend, gpu, msaa
};

struct Panel {
  std::string env_id;
  std::string camera;  // as `render --camera` takes it
  std::vector<uint8_t> rgb;
  std::vector<PlacedLabel> labels;
};

std::string Fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

// The markers and labels of one panel, from the reset observation.
struct PanelContent {
  std::function<void(mjvScene*)> geoms;
  std::vector<LabelRequest> labels;
  std::vector<Vec3> points;  // what the camera must show
  std::vector<std::pair<Vec3, Vec3>> lines;  // the markers' arrows and lines, kept clear of labels
};

// Where body `name` is in `env`'s current state; `fallback` when the model lacks it.
Vec3 BodyPosition(const FetchEnv& env, const char* name, const Vec3& fallback) {
  const int id = mj_name2id(env.model(), mjOBJ_BODY, name);
  const mjtNum* x = env.data()->xpos;
  return id < 0 ? fallback : Vec3{x[3 * id], x[3 * id + 1], x[3 * id + 2]};
}

PanelContent ReachContent(const FetchEnv& env, const StepRecord& s) {
  const bool obj = false;
  const Vec3 grip = {s.obs.observation[0], s.obs.observation[1], s.obs.observation[2]};
  const Vec3 goal = s.obs.desired_goal;
  const Vec3 right = BodyPosition(env, "robot0:r_gripper_finger_link", grip);
  const Vec3 left = BodyPosition(env, "robot0:l_gripper_finger_link", grip);
  const double threshold = env.spec().distance_threshold;
  constexpr double kArrowLength = 0.25;  // drawn 5x the 0.05 m a unit action moves the target
  const Vec3 ax = Add(grip, {kArrowLength, 0, 0}), ay = Add(grip, {0, kArrowLength, 0}),
             az = Add(grip, {0, 0, kArrowLength});
  // a[3] would move each finger along the line between them: outward = open
  Vec3 open_dir = Add(left, right, -1.0);
  const double span = std::max(1e-6, std::hypot(open_dir[0], open_dir[1], open_dir[2]));
  open_dir = {open_dir[0] / span, open_dir[1] / span, open_dir[2] / span};
  const Vec3 left_tip = Add(left, open_dir, 0.05), right_tip = Add(right, open_dir, -0.05);
  const Vec3 shell_edge = Add(goal, {0, 0, threshold});
  PanelContent c;
  c.geoms = [=](mjvScene* scene) {
    AddSphere(scene, grip, 0.012, Opaque(kCyan));
    AddConnector(scene, mjGEOM_ARROW, 0.008, grip, ax, Opaque(kRed));
    AddConnector(scene, mjGEOM_ARROW, 0.008, grip, ay, Opaque(kGreen));
    AddConnector(scene, mjGEOM_ARROW, 0.008, grip, az, Opaque(kBlue));
    AddConnector(scene, mjGEOM_ARROW, 0.006, left, left_tip, Opaque(kMagenta));
    AddConnector(scene, mjGEOM_ARROW, 0.006, right, right_tip, Opaque(kMagenta));
    AddConnector(scene, mjGEOM_LINE, 3, left, right, Opaque(kYellow));
    AddConnector(scene, mjGEOM_LINE, 2, goal, shell_edge, Opaque(kWhite));
    AddSphere(scene, goal, threshold, Translucent(kRed, 0.22f));
  };
  c.labels = {
      {"grip_pos " + ObservationSlice(obj, "grip_pos") + "\n= achieved_goal", grip, kCyan,
       {-40, 40}},
      {"a[0] +x: target +0.05 m\nper unit (drawn x5)", ax, kRed, {-20, 20}},
      {"a[1] +y: target +0.05 m", ay, kGreen, {30, -20}},
      {"a[2] +z: target +0.05 m", az, kBlue, {30, -30}},
      {"a[3] gripper: >0 opens\n(PickAndPlace; ignored here)", left_tip, kMagenta, {40, 30}},
      {"finger width: obs[3] r\n+ obs[4] l (joint pos)", Mid(left, right), kYellow, {40, 60}},
      {"desired_goal (goal)", goal, kRed, {40, 30}},
      {"success shell\nr = " + Fixed(threshold, 2) + " m", shell_edge, kWhite, {40, -30}},
  };
  c.points = {grip, goal, ax, ay, az};
  c.lines = {{grip, ax}, {grip, ay}, {grip, az}, {left, left_tip}, {right, right_tip},
             {goal, shell_edge}};
  return c;
}

PanelContent PushContent(const FetchEnv& env, const StepRecord& s) {
  const bool obj = true;
  const auto& o = s.obs.observation;
  const Vec3 grip = {o[0], o[1], o[2]};
  const Vec3 object = {o[3], o[4], o[5]};
  const Vec3 goal = s.obs.desired_goal;
  const Vec3 right = BodyPosition(env, "robot0:r_gripper_finger_link", grip);
  const Vec3 left = BodyPosition(env, "robot0:l_gripper_finger_link", grip);
  const double threshold = env.spec().distance_threshold;
  constexpr double kAxis = 0.09;
  const Vec3 ax = Add(grip, {kAxis, 0, 0}), ay = Add(grip, {0, kAxis, 0}),
             az = Add(grip, {0, 0, kAxis});
  const Vec3 shell_edge = Add(goal, {0, 0, threshold});
  const std::string grip_slice = ObservationSlice(obj, "grip_pos");
  PanelContent c;
  c.geoms = [=](mjvScene* scene) {
    AddSphere(scene, grip, 0.010, Opaque(kCyan));
    AddConnector(scene, mjGEOM_LINE, 4, grip, ax, Opaque(kRed));
    AddConnector(scene, mjGEOM_LINE, 4, grip, ay, Opaque(kGreen));
    AddConnector(scene, mjGEOM_LINE, 4, grip, az, Opaque(kBlue));
    AddConnector(scene, mjGEOM_ARROW, 0.007, grip, object, Opaque(kOrange));
    AddSphere(scene, object, 0.036, Translucent(kYellow, 0.35f));
    AddConnector(scene, mjGEOM_LINE, 3, left, right, Opaque(kMagenta));
    AddConnector(scene, mjGEOM_LINE, 2, goal, shell_edge, Opaque(kWhite));
    AddSphere(scene, goal, threshold, Translucent(kRed, 0.22f));
  };
  c.labels = {
      {"grip_pos " + grip_slice, grip, kCyan, {-40, -40}},
      {"x obs[0]", ax, kRed, {-20, 20}},
      {"y obs[1]", ay, kGreen, {20, 20}},
      {"z obs[2]", az, kBlue, {20, -20}},
      {"object_pos " + ObservationSlice(obj, "object_pos") + "\n= achieved_goal", object,
       kYellow, {40, 40}},
      {"object_rel_pos " + ObservationSlice(obj, "object_rel_pos") + "\n= object - grip",
       Mid(grip, object), kOrange, {40, -40}},
      {"finger width: obs[9] r\n+ obs[10] l (joint pos)", Mid(left, right), kMagenta, {-40, -60}},
      {"desired_goal (goal)", goal, kRed, {40, 30}},
      {"success shell\nr = " + Fixed(threshold, 2) + " m", shell_edge, kWhite, {40, -30}},
  };
  c.points = {grip, object, goal, az};
  c.lines = {{grip, ax}, {grip, ay}, {grip, az}, {grip, object}, {goal, shell_edge}};
  return c;
}

// A free camera that frames `points` from Gymnasium's side of the table, as a --camera spec
// (short decimals, so that `render --camera` reproduces it exactly).
std::string FramingCamera(const std::vector<Vec3>& points) {
  Vec3 lo = points[0], hi = points[0];
  for (const Vec3& p : points) {
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
  }
  const double span = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 0.25});
  char buf[200];
  std::snprintf(buf, sizeof(buf),
                "free:lookat=%.3f,%.3f,%.3f,distance=%.2f,azimuth=140,elevation=-24",
                0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2]),
                0.3 + 1.7 * span);
  return buf;
}

Panel RenderPanel(const std::string& env_id, const CardOptions& o, GlContext& gl) {
  const EnvSpec& spec = FindEnvSpec(env_id);
  FetchEnv fetch(spec, ResolveAssets(o.env.assets));
  PolicyContext context;
  context.seed = ParseSeed(o.env.seed);
  auto policy = MakePolicy("zero", spec, context);
  const EpisodeRecord episode = RunEpisode(fetch, *policy, 0, context.seed, 0);
  const StepRecord& reset = episode.steps.back();
  const PanelContent content =
      spec.has_object ? PushContent(fetch, reset) : ReachContent(fetch, reset);

  Panel panel;
  panel.env_id = env_id;
  panel.camera = FramingCamera(content.points);
  ViewOptions view = o.view;
  view.camera = panel.camera;
  view.overlay = "none";
  RenderOptions options = MakeRenderOptions(view, fetch.model());
  options.extra_geoms = content.geoms;
  Renderer renderer(gl, fetch.model(), options);
  const int w = view.width, h = view.height;
  panel.rgb.resize(static_cast<size_t>(w) * h * 3);
  renderer.Render(fetch.data(), MakeFrameInfo(fetch, reset), panel.rgb.data());

  auto project = [&](const Vec3& p) {
    return ProjectToPixel(renderer.scene(), renderer.tiles()[0], h, p);
  };
  std::vector<LabelRequest> requests = content.labels;
  std::vector<std::optional<Pixel>> anchors;
  std::vector<Rect> obstacles;
  for (const LabelRequest& r : requests) {
    anchors.push_back(r.at ? project(*r.at) : std::nullopt);
    if (anchors.back()) {
      obstacles.push_back({int(anchors.back()->x) - 14, int(anchors.back()->y) - 14, 28, 28});
    }
  }
  for (const auto& [from, to] : content.lines) {
    const auto a = project(from), b = project(to);
    if (!a || !b) continue;
    const int n = 1 + static_cast<int>(std::hypot(b->x - a->x, b->y - a->y) / 6);
    for (int i = 0; i <= n; ++i) {
      const double x = a->x + (b->x - a->x) * i / n, y = a->y + (b->y - a->y) * i / n;
      obstacles.push_back({int(x) - 5, int(y) - 5, 10, 10});
    }
  }
  // captions: the title at the top, the slices without a place in the scene at the bottom
  const int n = spec.has_object ? 25 : 10;
  requests.push_back({spec.id + " after reset(seed=" + o.env.seed + ")\nobservation[" +
                          std::to_string(n) + "], action[4]",
                      std::nullopt, kWhite, {}, {8, 8}});
  const std::string velocities =
      spec.has_object
          ? "obs[11:14] object_rot  obs[14:17] object_velp\n"
            "obs[17:20] object_velr  obs[20:23] grip_velp\n"
            "obs[23:25] finger vel  (velocities x dt: per step)"
          : "obs[5:8] grip_velp  obs[8:10] finger vel\n(velocities x dt: per step)";
  const TextSize footer = MeasureText(velocities);
  requests.push_back({velocities, std::nullopt, kWhite, {},
                      {8, static_cast<double>(h - footer.height - 2 * kPadding - 8)}});
  anchors.resize(requests.size());
  // the captions go first, so that the other labels keep clear of them
  std::vector<LabelRequest> ordered(requests.end() - 2, requests.end());
  std::vector<std::optional<Pixel>> ordered_anchors(anchors.end() - 2, anchors.end());
  ordered.insert(ordered.end(), requests.begin(), requests.end() - 2);
  ordered_anchors.insert(ordered_anchors.end(), anchors.begin(), anchors.end() - 2);
  panel.labels = PlaceLabels(ordered, ordered_anchors, obstacles, w, h);
  DrawLabels(panel.labels, &panel.rgb, w, h);
  return panel;
}

nlohmann::json RgbJson(Rgb c) { return {c.r, c.g, c.b}; }

// Writes DIR/ch01_anatomy.png (Reach | Push) and DIR/ch01_anatomy_labels.json.
void WriteAnatomyCard(const std::string& dir, const CardOptions& o) {
  auto gl = CreateViewContext(o.view, ResolveGpuChoice(o.view));
  std::vector<Panel> panels;
  for (const char* id : {"FetchReach-v4", "FetchPush-v4"}) panels.push_back(RenderPanel(id, o, *gl));
  const int w = o.view.width, h = o.view.height;
  const int card_width = w * static_cast<int>(panels.size());
  std::vector<uint8_t> card(static_cast<size_t>(card_width) * h * 3);
  nlohmann::json panels_json = nlohmann::json::array(), labels_json = nlohmann::json::array();
  for (size_t p = 0; p < panels.size(); ++p) {
    const int left = static_cast<int>(p) * w;
    for (int row = 0; row < h; ++row) {
      std::copy_n(panels[p].rgb.data() + static_cast<size_t>(row) * w * 3, w * 3,
                  card.data() + (static_cast<size_t>(row) * card_width + left) * 3);
    }
    panels_json.push_back({{"env_id", panels[p].env_id}, {"seed", o.env.seed},
                           {"assets", o.env.assets}, {"camera", panels[p].camera},
                           {"overlay", "none"}, {"msaa", o.view.msaa},
                           {"box", {left, 0, w, h}}});
    for (const PlacedLabel& l : panels[p].labels) {
      nlohmann::json label = {{"panel", p},
                              {"text", l.text},
                              {"color", RgbJson(l.color)},
                              {"box", {left + l.x, l.y, l.w, l.h}}};
      label["anchor"] = l.anchor ? nlohmann::json{left + l.anchor->x, l.anchor->y}
                                 : nlohmann::json(nullptr);
      labels_json.push_back(label);
    }
  }
  const std::string png = (std::filesystem::path(dir) / "ch01_anatomy.png").string();
  const std::string sidecar = (std::filesystem::path(dir) / "ch01_anatomy_labels.json").string();
  WritePng(png, card_width, h, 3, 8, card.data());
  WriteJson(sidecar, {{"image", "ch01_anatomy.png"},
                      {"width", card_width},
                      {"height", h},
                      {"text_pixels", kTextPixels},
                      {"panels", panels_json},
                      {"labels", labels_json}});
  std::printf("wrote %s\nwrote %s\n", png.c_str(), sidecar.c_str());
}

struct AnatomyOptions {
  EnvOptions env;
  std::string out = "results";
  CardOptions card;
  bool no_card = false;
};

void RunAnatomy(AnatomyOptions o) {
  const EnvSpec& spec = FindEnvSpec(o.env.env_id);  // bad input fails before any file
  ParseSeed(o.env.seed);
  ParseMsaa(o.card.view.msaa);
  const std::string prefix = (std::filesystem::path(o.out) / "ch01").string();
  std::printf("D1 (describe, %s)\n", spec.id.c_str());
  RunDescribe(o.env, prefix + "_env");
  std::printf("\nD2 (reward-check)\n");
  RewardCheckOptions check;
  check.env = o.env;
  check.json_out = prefix;
  const bool pass = RunRewardCheck(check);
  std::printf("\nD3 (random-episodes)\n");
  RandomEpisodesOptions random;
  random.env = o.env;
  random.json_out = prefix;
  RunRandomEpisodes(random);
  if (ExitStatus() != 0) return;  // interrupted

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
    ExitStatus() = 1;
  }
}

}  // namespace

void RegisterAnatomy(CLI::App& app) {
  auto o = std::make_shared<AnatomyOptions>();
  o->card.view.width = 720;
  o->card.view.height = 540;
  CLI::App* sub = app.add_subcommand(
      "anatomy",
      "The chapter's deliverables in one go: OUT/ch01_env_describe.json (D1), "
      "OUT/ch01_reward_check.json (D2), OUT/ch01_random_metrics.json (D3), the D4 answers, and "
      "the anatomy card OUT/ch01_anatomy.png (labelled Reach and Push frames) with "
      "OUT/ch01_anatomy_labels.json (each label's text and pixel box)");
  AddEnvOptions(sub, &o->env);
  sub->add_option("--out", o->out, "Folder for the files (created if missing)")
      ->capture_default_str();
  sub->add_option("--width", o->card.view.width, "Width of each of the card's two frames, pixels")
      ->capture_default_str()
      ->check(CLI::Range(320, 4096));
  sub->add_option("--height", o->card.view.height, "Height of the card, pixels")
      ->capture_default_str()
      ->check(CLI::Range(240, 4096));
  sub->add_option("--backend", o->card.view.backend,
                  "auto (EGL, then OSMesa), egl or osmesa; default: $MUJOCO_GL, else auto");
  sub->add_option("--msaa", o->card.view.msaa, "Anti-aliasing samples of the card, as render's")
      ->capture_default_str();
  sub->add_flag("--no-card", o->no_card, "Skip the anatomy card (no rendering, no GL needed)");
  sub->callback([o]() { RunAnatomy(*o); });
}

}  // namespace fetchscope::cli
