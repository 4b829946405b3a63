#include "render/overlay.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "src/errors.h"
#include "src/suggest.h"

namespace fetchscope {
namespace {

constexpr char kAcceptedOverlays[] =
    "accepted: default, none, all, or a comma list of goal, achieved, hud, action, trail";

// Colours (rgba).
constexpr float kGoalRed[4] = {1.0f, 0.0f, 0.0f, 1.0f};       // as target0
constexpr float kGoalShell[4] = {1.0f, 0.15f, 0.15f, 0.18f};  // translucent
constexpr float kSuccessGreen[4] = {0.1f, 0.85f, 0.2f, 1.0f};
constexpr float kMissOrange[4] = {1.0f, 0.55f, 0.0f, 1.0f};
constexpr float kArrowYellow[4] = {1.0f, 0.85f, 0.0f, 1.0f};
constexpr float kTrailCyan[4] = {0.0f, 0.75f, 1.0f, 1.0f};

constexpr double kTargetRadius = 0.02;     // target0's size in the Fetch XMLs
constexpr double kAchievedRadius = 0.012;  // opaque core
constexpr double kAchievedHalo = 0.032;    // translucent halo: shows even around the 5 cm block
constexpr double kArrowWidth = 0.008;      // m
constexpr double kLineWidth = 2.0;         // pixels for mjGEOM_LINE

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
  if (g) mjv_makeConnector(g, type, width, a[0], a[1], a[2], b[0], b[1], b[2]);
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
  OverlaySet set{false, false, false, false, false};
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
    } else if (token == "default") {
      set.goal = set.achieved = set.hud = true;
    } else if (token == "all") {
      set = OverlaySet{true, true, true, true, true};
    } else {
      const std::string suggestion = DidYouMean(
          token, {"goal", "achieved", "hud", "action", "trail", "default", "none", "all"});
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
  // mjr_overlay wants no trailing newline
  hud.labels.pop_back();
  hud.values.pop_back();
  return hud;
}

}  // namespace fetchscope
