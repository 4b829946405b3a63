// Overlays: goal shell, achieved-goal marker, action arrow, trail (extra MuJoCo scene geoms,
// added after mjv_updateScene, so they show in every camera and in golden images) and the
// HUD text. None of them touches the simulation.
#pragma once

#include <mujoco/mujoco.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

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
  bool labels = true;    ///< tiled cameras: each tile labelled with its camera name
  bool hindsight = false;  ///< goals HER's `future` strategy relabels this transition with
};

/// Where the HUD box sits in the frame (in the tile at that corner).
enum class HudPosition { kTopLeft, kTopRight, kBottomLeft, kBottomRight };

/// Parses --hud-position: top-left, top-right, bottom-left or bottom-right. Throws UsageError
/// naming the value and listing the accepted ones.
HudPosition ParseHudPosition(const std::string& text);

/// The --hud-position spelling of `position`.
const char* HudPositionName(HudPosition position);

/// Checks --hud-opacity (0 = no box behind the text, 1 = opaque); throws UsageError naming
/// the value and the accepted range when it is outside [0, 1] or not a number.
double CheckHudOpacity(double opacity);


/// Throws UsageError naming the bad token and listing the accepted ones.
/// Parses --overlay: "default", "none", "all", or a comma list of
/// goal|achieved|hud|action|trail|labels|hindsight|default|all (spaces around items are
/// ignored). Throws UsageError naming the bad token, the nearest accepted one and listing the
/// accepted ones.
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
  /// Hindsight overlay: the goals HER's `future` strategy relabels this transition with, and
  /// whether the relabelled reward counts as success (green marker) or not (red).
  struct Relabel {
    std::array<double, 3> goal{};
    bool success = false;
  };
  std::vector<Relabel> relabelled;
  int relabelled_successes = -1;  ///< shown by the HUD when >= 0 (this transition's count)
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
inline constexpr int kMaxOverlayGeoms = 8 + 16 + static_cast<int>(Trail::kMaxPoints);

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

/// A rectangle of an RGB image, row 0 at the top.
struct PixelRect {
  int x = 0, y = 0, width = 0, height = 0;
};

/// Line height in pixels of HUD text in a tile of `tile_width` x `tile_height`: it grows with
/// the tile (10 px up to 599 px, 20 px from 600, ...), so the HUD keeps its share of the frame.
int HudLineHeight(int tile_width, int tile_height);

/// Where the HUD box of `hud` goes in `tile` at `position`, or nullopt where it would not fit
/// (the tile is too small for text that can still be read: the HUD is dropped).
std::optional<PixelRect> PlaceHud(const HudText& hud, const PixelRect& tile, HudPosition position);

/// Draws `hud` into `rgb` (`width` x `height` RGB24, row 0 on top) inside `tile` at `position`:
/// a black box blended at `opacity` and the text over it. Returns false (nothing drawn) where
/// the tile is too small for it.
bool DrawHud(uint8_t* rgb, int width, int height, const PixelRect& tile, const HudText& hud,
             HudPosition position, double opacity);

/// Draws the camera name `label` at the top centre of `tile` (the bottom centre where that
/// would overlap `avoid`, the HUD box) on a box blended at `opacity`; nothing where the tile is
/// too small. Returns whether it was drawn.
bool DrawTileLabel(uint8_t* rgb, int width, int height, const PixelRect& tile,
                   const std::string& label, double opacity, const std::optional<PixelRect>& avoid);

}  // namespace fetchscope
