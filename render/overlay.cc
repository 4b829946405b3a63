#include "render/overlay.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "base/errors.h"
#include "base/number_format.h"
#include "base/suggest.h"

namespace fetchscope {
namespace {

// Colours (rgba).
constexpr float kGoalRed[4] = {1.0f, 0.0f, 0.0f, 1.0f};       // as target0
constexpr float kGoalShell[4] = {1.0f, 0.15f, 0.15f, 0.18f};  // translucent
constexpr float kSuccessGreen[4] = {0.1f, 0.85f, 0.2f, 1.0f};
constexpr float kMissOrange[4] = {1.0f, 0.55f, 0.0f, 1.0f};
constexpr float kArrowYellow[4] = {1.0f, 0.85f, 0.0f, 1.0f};
constexpr float kTrailCyan[4] = {0.0f, 0.75f, 1.0f, 1.0f};
// a dataset's own achieved goal: opaque blue, a hue no other marker uses (not the goal's red or
// its pink shell, the trail's cyan, HER's green and red)
constexpr float kGhostBlue[4] = {0.15f, 0.25f, 1.0f, 1.0f};
// the contacts, by pair: hues none of the markers above uses (magenta, near-black, purple, grey)
constexpr float kContactFingerObject[4] = {1.0f, 0.1f, 0.75f, 1.0f};
constexpr float kContactObjectTable[4] = {0.08f, 0.08f, 0.08f, 1.0f};
constexpr float kContactFingerTable[4] = {0.55f, 0.2f, 0.85f, 1.0f};
constexpr float kContactOther[4] = {0.6f, 0.6f, 0.6f, 1.0f};
constexpr double kContactRadius = 0.006;      // m: the contact point
constexpr double kContactArrowWidth = 0.004;  // m

const float* ContactRgba(ContactPair pair) {
  switch (pair) {
    case ContactPair::kFingerObject:
      return kContactFingerObject;
    case ContactPair::kObjectTable:
      return kContactObjectTable;
    case ContactPair::kFingerTable:
      return kContactFingerTable;
    case ContactPair::kOther:
      break;
  }
  return kContactOther;
}

constexpr double kTargetRadius = 0.02;     // target0's size in the Fetch XMLs
constexpr double kAchievedRadius = 0.012;  // opaque core
constexpr double kAchievedHalo = 0.032;    // translucent halo: shows even around the 5 cm block
constexpr double kGhostArm = 0.03;         // the ghost's cross: arms 3 cm each way (past the halo)
constexpr double kGhostBar = 0.003;        // and 3 mm thick: a few pixels at 480x480
constexpr double kArrowWidth = 0.008;      // m
constexpr double kLineWidth = 2.0;         // pixels for mjGEOM_LINE

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

}  // namespace

namespace {

// Every --overlay item, once: the parser, its "did you mean", the accepted list in its message,
// --help and the bash completion all read this table (OverlayNames).
struct OverlayItem {
  const char* name;
  void (*apply)(OverlaySet*);
};
const OverlayItem kOverlayItems[] = {
    {"goal", [](OverlaySet* s) { s->goal = true; }},
    // a dataset's ghost goes with the achieved marker
    {"achieved", [](OverlaySet* s) { s->achieved = s->ghost = true; }},
    {"hud", [](OverlaySet* s) { s->hud = true; }},
    {"action", [](OverlaySet* s) { s->action = true; }},
    {"trail", [](OverlaySet* s) { s->trail = true; }},
    {"labels", [](OverlaySet* s) { s->labels = true; }},
    {"hindsight", [](OverlaySet* s) { s->hindsight = true; }},
    {"ghost", [](OverlaySet* s) { s->ghost = true; }},
    {"contacts", [](OverlaySet* s) { s->contacts = true; }},
    {"default",
     [](OverlaySet* s) { s->goal = s->achieved = s->hud = s->labels = s->ghost = true; }},
    {"all",
     [](OverlaySet* s) { *s = OverlaySet{true, true, true, true, true, true, true, true, true}; }},
};

std::string AcceptedOverlays() {
  std::string items;
  for (const OverlayItem& item : kOverlayItems) {
    const std::string name = item.name;
    if (name != "default" && name != "all") items += (items.empty() ? "" : ", ") + name;
  }
  return "accepted: default, none, all, or a comma list of " + items;
}

}  // namespace

std::vector<std::string> OverlayNames() {
  std::vector<std::string> names = {"default", "none", "all"};
  for (const OverlayItem& item : kOverlayItems) {
    const std::string name = item.name;
    if (name != "default" && name != "all") names.push_back(name);
  }
  return names;
}

OverlaySet ParseOverlays(const std::string& spec) {
  const std::string trimmed = TrimSpaces(spec);
  if (trimmed == "default") return OverlaySet{};
  OverlaySet set{false, false, false, false, false, false, false, false};
  if (trimmed == "none") return set;
  for (const std::string& token : SplitCommaList(spec)) {
    const OverlayItem* found = nullptr;
    for (const OverlayItem& item : kOverlayItems) {
      if (token == item.name) found = &item;
    }
    if (!found) {
      throw UsageError("overlay '" + token + "' in '" + spec + "' is not known" +
                       DidYouMean(token, OverlayNames()) + "; " + AcceptedOverlays());
    }
    found->apply(&set);
  }
  return set;
}

namespace {

// A colour (rgba in [0, 1]) as CSS: #rrggbb where opaque, rgba() where translucent.
std::string CssColor(const float rgba[4]) {
  const auto byte = [](float c) { return static_cast<int>(std::lround(255.0 * c)); };
  char text[48];
  if (rgba[3] >= 1.0f) {
    std::snprintf(text, sizeof(text), "#%02x%02x%02x", byte(rgba[0]), byte(rgba[1]), byte(rgba[2]));
  } else {
    std::snprintf(text, sizeof(text), "rgba(%d, %d, %d, %.2f)", byte(rgba[0]), byte(rgba[1]),
                  byte(rgba[2]), rgba[3]);
  }
  return text;
}

}  // namespace

std::string ContactPairColor(ContactPair pair) { return CssColor(ContactRgba(pair)); }

void SetContactInfo(const ContactSignals& signals, bool has_object, FrameInfo* info) {
  info->contacts.clear();
  for (const Contact& c : signals.contacts) {
    if (static_cast<int>(info->contacts.size()) >= kMaxContactMarks) break;
    info->contacts.push_back({c.position, c.push, c.normal_force, c.pair});
  }
  info->left_finger_force = signals.left_finger_force;
  info->right_finger_force = signals.right_finger_force;
  info->object_on_table = signals.object_on_table;
  info->has_object = has_object;
}

std::vector<OverlayLegendEntry> OverlayLegend(const OverlaySet& overlays, bool replay) {
  std::vector<OverlayLegendEntry> out;
  out.push_back({"goal", CssColor(kGoalRed), "the goal (the model's target0 sphere)"});
  if (overlays.goal) {
    out.push_back({"goal shell", CssColor(kGoalShell), "success radius around the goal"});
  }
  if (overlays.achieved) {
    out.push_back({"achieved (success)", CssColor(kSuccessGreen),
                   "achieved goal and its line to the goal, within the success radius"});
    out.push_back({"achieved (not yet)", CssColor(kMissOrange),
                   "achieved goal and its line to the goal, outside the success radius"});
  }
  if (overlays.action) {
    out.push_back({"action", CssColor(kArrowYellow), "arrow along the commanded displacement"});
  }
  if (overlays.trail) {
    out.push_back({"trail", CssColor(kTrailCyan), "recent achieved-goal positions"});
  }
  if (overlays.hindsight) {
    out.push_back(
        {"HER success", CssColor(kHindsightGreen), "a relabelled goal that counts as success"});
    out.push_back(
        {"HER failure", CssColor(kHindsightRed), "a relabelled goal that does not count"});
  }
  if (overlays.contacts) {
    const char* scale = "; arrows: the normal force, 1 cm = 20 N (at most 15 cm)";
    out.push_back({"contact finger-object", CssColor(kContactFingerObject),
                   std::string("a gripper finger touching the object") + scale});
    out.push_back({"contact object-table", CssColor(kContactObjectTable),
                   std::string("the object resting on the table") + scale});
    out.push_back({"contact finger-table", CssColor(kContactFingerTable),
                   std::string("a gripper finger touching the table") + scale});
    out.push_back({"contact other", CssColor(kContactOther),
                   std::string("any other active contact (the robot's links, the floor)") + scale});
  }
  if (overlays.ghost && replay) {
    out.push_back({"ghost", CssColor(kGhostBlue),
                   "the dataset's own achieved goal (blue cross, with a line to the replayed "
                   "one; the HUD row: how far apart)"});
  }
  return out;
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

std::vector<HindsightPin> HindsightPins(const FrameInfo& info) {
  std::vector<HindsightPin> pins;
  const double clear = 2 * kHindsightBeadRadius + 0.001;  // beads nearer than this overlap
  for (const FrameInfo::Relabel& r : info.relabelled) {
    HindsightPin pin;
    pin.base = r.goal;
    pin.success = r.success;
    // out along the stem until the bead clears every bead placed before: identical goals
    // string their beads kHindsightBeadSpacing apart on one stem (the steps are exact
    // multiples of half the spacing, so each length is computed afresh, never accumulated)
    for (int half_steps = 0;; ++half_steps) {
      const double length = kHindsightPinLength + half_steps * (kHindsightBeadSpacing / 2);
      for (int k = 0; k < 3; ++k) pin.head[k] = r.goal[k] + length * kHindsightPinDirection[k];
      bool overlaps = false;
      for (const HindsightPin& other : pins) {
        const double dx = pin.head[0] - other.head[0], dy = pin.head[1] - other.head[1],
                     dz = pin.head[2] - other.head[2];
        overlaps = overlaps || dx * dx + dy * dy + dz * dz < clear * clear;
      }
      if (!overlaps) break;
    }
    pins.push_back(pin);
  }
  return pins;
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
    for (const HindsightPin& pin : HindsightPins(info)) {
      const float* rgba = pin.success ? kHindsightGreen : kHindsightRed;
      AddSphere(scene, pin.head, kHindsightBeadRadius, rgba);
      AddConnector(scene, mjGEOM_CAPSULE, kHindsightStemRadius, pin.base, pin.head, rgba);
      AddSphere(scene, pin.base, kHindsightFootRadius, rgba);
    }
  }
  if (overlays.trail) {
    const auto& points = trail.points();
    for (size_t i = 1; i < points.size(); ++i) {
      AddConnector(scene, mjGEOM_LINE, kLineWidth, points[i - 1], points[i], kTrailCyan);
    }
  }
  if (overlays.ghost && info.ghost) {  // a cross: it shows through and around the replayed marker
    const auto& g = *info.ghost;
    for (int axis = 0; axis < 3; ++axis) {
      std::array<double, 3> from = g, to = g;
      from[axis] -= kGhostArm;
      to[axis] += kGhostArm;
      AddConnector(scene, mjGEOM_CAPSULE, kGhostBar, from, to, kGhostBlue);
    }
    AddConnector(scene, mjGEOM_LINE, kLineWidth, g, info.achieved, kGhostBlue);
  }
  if (overlays.contacts) {
    for (const ContactMark& c : info.contacts) {
      AddSphere(scene, c.position, kContactRadius, ContactRgba(c.pair));
      const double length = std::min(kContactArrowMax, c.force * kContactMetresPerNewton);
      if (length < kContactRadius) continue;  // within the point: no arrow
      // the arrow ends at the contact point, on the side the force comes from
      const std::array<double, 3> tail = {c.position[0] - length * c.push[0],
                                          c.position[1] - length * c.push[1],
                                          c.position[2] - length * c.push[2]};
      AddConnector(scene, mjGEOM_ARROW, kContactArrowWidth, tail, c.position, ContactRgba(c.pair));
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
  FormatHud(info, overlays, &hud);
  return hud;
}

void FormatHud(const FrameInfo& info, const OverlaySet& overlays, HudText* out) {
  HudText& hud = *out;
  hud.title.assign(info.title);  // assign, clear and append keep the strings' memory
  hud.labels.clear();
  hud.values.clear();
  auto line = [&](std::string_view label, std::string_view value) {
    hud.labels.append(label);
    hud.labels.push_back('\n');
    hud.values.append(value);
    hud.values.push_back('\n');
  };
  char text[96];  // a value formatted in place (std::to_string and friends may allocate)
  // a step Gymnasium's TimeLimit would not give (--steps beyond it) says so
  if (info.past_time_limit > 0) {
    std::snprintf(text, sizeof(text), "%d past limit %d", info.step, info.past_time_limit);
  } else {
    std::snprintf(text, sizeof(text), "%d", info.step);
  }
  line("step", text);
  // PictureNumber: a sparse reward of -0.0 shows as 0.0000, an action of -0.001 as +0.00
  line("reward", std::isnan(info.reward) ? "-" : PictureNumber("%.4f", info.reward));
  line("distance", PictureNumber("%.4f m", info.distance));
  line("success", info.success ? "yes" : "no");
  hud.labels.append("action\n");
  if (info.has_action) {
    for (size_t i = 0; i < info.action.size(); ++i) {
      if (i > 0) hud.values.push_back(' ');
      hud.values.append(PictureNumber("%+.2f", info.action[i]));
    }
    hud.values.push_back('\n');
  } else {
    hud.values.append("-\n");
  }
  if (overlays.action) {
    std::snprintf(text, sizeof(text), "x%.0f of 0.05 m/unit", kActionArrowScale);
    line("arrow", text);
  }
  if (overlays.hindsight) {
    // on every frame, so that the box keeps its height ("-": no transition ends here)
    if (info.relabelled_successes < 0) {
      line("HER", "-");
    } else {
      std::snprintf(text, sizeof(text), "%d/%zu successes", info.relabelled_successes,
                    info.relabelled.size());
      line("HER", text);
    }
  }
  if (overlays.ghost && info.ghost) {  // the ghost marker's legend: how far the replay is off
    const auto& g = *info.ghost;
    const double dx = g[0] - info.achieved[0], dy = g[1] - info.achieved[1],
                 dz = g[2] - info.achieved[2];
    std::snprintf(text, sizeof(text), "%.1f mm off (blue +)",
                  1000 * std::sqrt(dx * dx + dy * dy + dz * dz));
    line("ghost", text);
  }
  hud.labels.pop_back();  // no trailing newline
  hud.values.pop_back();
}

}  // namespace fetchscope
