// Overlays: goal shell, achieved-goal marker, action arrow, trail (extra MuJoCo scene geoms,
// added after mjv_updateScene, so they show in every camera and in golden images) and the
// HUD text. None of them touches the simulation.
#pragma once

#include <mujoco/mujoco.h>

#include <array>
#include <cmath>
#include <deque>
#include <string>

namespace fetchscope {

/// Which overlays to draw. Default: goal, achieved, hud. The goal marker itself (the model's
/// red target0 sphere, moved to the goal as Gymnasium does) is part of the scene, not an
/// overlay: it shows with every set, "none" included.
struct OverlaySet {
  bool goal = true;      ///< translucent shell of radius distance_threshold around the goal
  bool achieved = true;  ///< achieved-goal marker (green on success, else orange) + line to goal
  bool hud = true;       ///< text: title, step, reward, distance, success, action
  bool action = false;   ///< arrow from the grip site along the commanded displacement
  bool trail = false;    ///< polyline of recent achieved-goal positions
};

/// Parses --overlay: "default", "none", "all", or a comma list of
/// goal|achieved|hud|action|trail|default|all (spaces around items are ignored). Throws
/// UsageError naming the bad token, the nearest accepted one and listing the accepted ones.
OverlaySet ParseOverlays(const std::string& spec);

/// What the overlays show for one frame (the environment fills it).
struct FrameInfo {
  int step = 0;                      ///< env step (0 = reset)
  double reward = NAN;               ///< NAN at reset
  double distance = 0;               ///< |achieved - goal| (m)
  bool success = false;              ///< is_success
  bool has_action = false;           ///< false at reset
  std::array<double, 4> action{};    ///< the action that led here (dx, dy, dz, grip)
  std::array<double, 3> goal{};      ///< desired goal (m, world)
  std::array<double, 3> achieved{};  ///< achieved goal (m, world)
  double distance_threshold = 0.05;  ///< success radius (m)
  std::string title;                 ///< e.g. the env id, first HUD line
};

/// The env moves the mocap by 0.05 m per unit action; the arrow is drawn this many times
/// longer than that displacement so that it shows beside the gripper.
inline constexpr double kActionArrowScale = 4.0;

/// Recent achieved-goal positions, one per env step, for the trail overlay.
class Trail {
 public:
  /// Records the position for `step`: step 0 starts a new episode; the same step twice
  /// replaces its point, so rendering a frame again does not grow the trail.
  void Add(int step, const std::array<double, 3>& position);
  /// Forgets all points.
  void Clear() { points_.clear(); }
  /// Oldest first.
  const std::deque<std::array<double, 3>>& points() const { return points_; }

  static constexpr size_t kMaxPoints = 250;  ///< older points are dropped

 private:
  std::deque<std::array<double, 3>> points_;
  int last_step_ = -1;
};

/// Geoms the overlays may add at most (so the scene can reserve room for them).
inline constexpr int kMaxOverlayGeoms = 8 + static_cast<int>(Trail::kMaxPoints);

/// Moves the scene geom of site `site_id` (the target0 marker) to `goal`, as Gymnasium's
/// _render_callback does through site_pos + mj_forward, but without touching mjData.
/// Returns false when the scene holds no such geom.
bool PlaceSiteGeom(mjvScene* scene, int site_id, const std::array<double, 3>& goal);

/// Appends the geoms of `overlays` for `info` to `scene`, skipping what does not fit in
/// scene->maxgeom. `grip` is the grip site's position (for the action arrow); `add_goal_sphere`
/// draws a red goal sphere too (for models without a target0 site).
void AddOverlayGeoms(const OverlaySet& overlays, const FrameInfo& info,
                     const std::array<double, 3>& grip, const Trail& trail, bool add_goal_sphere,
                     mjvScene* scene);

/// The HUD as two columns for mjr_overlay: labels and values, one line each.
struct HudText {
  std::string labels;
  std::string values;
};

/// Formats the HUD for `info`.
HudText FormatHud(const FrameInfo& info, const OverlaySet& overlays);

}  // namespace fetchscope
