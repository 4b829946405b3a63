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

#include "src/contacts.h"

namespace fetchscope {

/// Which overlays to draw. Default: goal, achieved, hud. The goal marker itself (the model's
/// red target0 sphere, moved to the goal as Gymnasium does) is part of the scene, not an
/// overlay: it shows with every set, "none" included.
struct OverlaySet {
  bool goal = true;        ///< translucent shell of radius distance_threshold around the goal
  bool achieved = true;    ///< achieved-goal marker (green on success, else orange) + line to goal
  bool hud = true;         ///< text: title, step, reward, distance, success, action
  bool action = false;     ///< arrow from the grip site along the commanded displacement
  bool trail = false;      ///< polyline of recent achieved-goal positions
  bool labels = true;      ///< tiled cameras: each tile labelled with its camera name
  bool hindsight = false;  ///< goals HER's `future` strategy relabels this transition with
  /// record --from DATASET: the dataset's own achieved goal (FrameInfo::ghost) as an opaque
  /// blue cross with a line to the replayed one, and a HUD row with their distance; on with
  /// `achieved` (so by default) or alone as `ghost`
  bool ghost = true;
  /// the active contacts: a point each, an arrow along its normal force (kContactCmPerNewton),
  /// coloured by pair (finger-object, object-table, finger-table, other), and a HUD row with the
  /// fingers' forces on the object; off by default, on with `contacts` or `all`
  bool contacts = false;
};

/// Where the HUD box sits in the frame (in the tile at that corner).
enum class HudPosition { kTopLeft, kTopRight, kBottomLeft, kBottomRight };

/// The --hud-position spelling of `position`.
const char* HudPositionName(HudPosition position);

/// Throws UsageError naming the bad token and listing the accepted ones.
/// Parses --overlay: "default", "none", "all", or a comma list of
/// goal|achieved|hud|action|trail|labels|hindsight|ghost|contacts|default|all (spaces around
/// items are ignored). Throws UsageError naming the bad token, the nearest accepted one and listing
/// the accepted ones.
OverlaySet ParseOverlays(const std::string& spec);

/// Every name --overlay accepts ("default", "none", "all", then each item), from the parser's
/// own table: completion and help read it, so they cannot drift from the parser.
std::vector<std::string> OverlayNames();

/// One contact as the contacts overlay draws it.
struct ContactMark {
  std::array<double, 3> position{};  ///< m, world
  std::array<double, 3> push{};      ///< unit: the direction of the force drawn (Contact::push)
  double force = 0;                  ///< N, the normal force
  ContactPair pair = ContactPair::kOther;
};

/// The contacts overlay's scale: an arrow is this many metres long per newton (1 cm = 20 N),
/// up to kContactArrowMax.
inline constexpr double kContactMetresPerNewton = 0.01 / 20.0;
inline constexpr double kContactArrowMax = 0.15;  ///< m: longer forces are drawn this long
/// The most contacts the overlay draws (MuJoCo's d->contact order; Fetch states have 3 to 15).
inline constexpr int kMaxContactMarks = 24;

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
  /// The dataset's achieved goal at this step (record --from DATASET); unset otherwise.
  std::optional<std::array<double, 3>> ghost;
  /// The env's max_episode_steps when `step` is past it (--steps beyond the TimeLimit): the
  /// HUD's step row says so; 0 for every step within it.
  int past_time_limit = 0;
  /// The contacts overlay: the renderer fills these from the state it draws (ContactsInfo).
  std::vector<ContactMark> contacts;
  double left_finger_force = 0;   ///< N, on the object
  double right_finger_force = 0;  ///< N, on the object
  bool object_on_table = false;
  bool has_object = false;  ///< the task has an object (its HUD row says where it is)
};

/// Fills `info`'s contact fields from `signals` (the state's ReadContacts).
void SetContactInfo(const ContactSignals& signals, bool has_object, FrameInfo* info);

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

/// The hindsight overlay draws each relabelled goal g' as a pin: a thin stem from g' out to a
/// bead, so that it shows even where g' lies inside the block (a failed episode's block often
/// never moves, and then every g' is where it stands) or inside the gripper that carries it.
/// The stem leans 45 degrees from the vertical toward +x+y, away from the robot (which stands
/// at -x) and across Gymnasium's default view, so that the gripper above the block does not
/// hide it. A bead that would overlap one placed before (identical g' give identical pins)
/// goes further out along its stem: k identical goals show k beads on one stem.
struct HindsightPin {
  std::array<double, 3> base{};  ///< g'
  std::array<double, 3> head{};  ///< the bead's centre
  bool success = false;          ///< relabelled reward counts as success: green, else red
};
inline constexpr double kHindsightPinDirection[3] = {0.5, 0.5, 0.70710678118654752};  ///< unit
inline constexpr double kHindsightPinLength = 0.10;     ///< m from g' to the nearest bead
inline constexpr double kHindsightBeadRadius = 0.014;   ///< m
inline constexpr double kHindsightBeadSpacing = 0.032;  ///< m between beads on one stem
inline constexpr double kHindsightStemRadius = 0.0025;  ///< m
inline constexpr double kHindsightFootRadius = 0.007;   ///< m, the sphere at g' itself

/// The pins of `info.relabelled`, in its order (deterministic).
std::vector<HindsightPin> HindsightPins(const FrameInfo& info);

/// Bead colours (rgba): relabelled success and failure.
inline constexpr float kHindsightGreen[4] = {0.0f, 0.9f, 0.25f, 1.0f};
inline constexpr float kHindsightRed[4] = {0.95f, 0.1f, 0.1f, 1.0f};

/// One marker of a run's frames, for the report's legend: its name, its colour as CSS
/// ("#rrggbb", or "rgba(r, g, b, a)" where translucent, as drawn) and what it shows.
struct OverlayLegendEntry {
  std::string name;
  std::string color;
  std::string meaning;
};

/// The markers `overlays` draws in a run's frames, each in the colour it is drawn with: the
/// goal (always), then those of the set that show markers. The ghost only where `replay` (record
/// --from DATASET: the frames have a dataset's achieved goal to show).
std::vector<OverlayLegendEntry> OverlayLegend(const OverlaySet& overlays, bool replay);

/// Geoms the overlays may add at most (so the scene can reserve room for them): 3 per
/// hindsight pin, up to 16 pins; 2 per contact.
inline constexpr int kMaxOverlayGeoms =
    10 + 3 * 16 + static_cast<int>(Trail::kMaxPoints) + 2 * kMaxContactMarks;

/// The contacts overlay's colour of `pair`, as CSS ("#rrggbb"): the legend's, the HUD's and the
/// report's.
std::string ContactPairColor(ContactPair pair);

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

/// The HUD's text: a title line (the env id) over two columns, labels and values, one line each.
struct HudText {
  std::string title;   ///< across the box; empty for none
  std::string labels;  ///< '\n'-separated, one per row
  std::string values;  ///< '\n'-separated, as many as labels
};

/// Formats the HUD for `info`. The rows depend on `overlays` only (never on the frame): with
/// `hindsight` the HER row is there on every frame ("-" where the frame has no transition).
HudText FormatHud(const FrameInfo& info, const OverlaySet& overlays);
/// FormatHud into `hud`, whose strings keep their memory from frame to frame (the renderer
/// formats every frame's HUD this way without allocating).
void FormatHud(const FrameInfo& info, const OverlaySet& overlays, HudText* hud);

/// A rectangle of an RGB image, row 0 at the top.
struct PixelRect {
  int x = 0, y = 0, width = 0, height = 0;
};

/// Views (tiles) narrower or lower than this get no HUD: text that fits them cannot be read.
inline constexpr int kHudMinTileWidth = 320;
inline constexpr int kHudMinTileHeight = 240;
/// The smallest HUD and tile-label text: DejaVu Sans at a 10-pixel em (13-pixel lines).
inline constexpr int kHudMinTextPixels = 10;
/// The most of a view the HUD box covers, in any view it is drawn in: this share of the view's
/// width and of its height (tests/camera_test.cc checks every row the HUD can have).
inline constexpr double kHudMaxWidthShare = 0.6;
inline constexpr double kHudMaxHeightShare = 0.5;

/// Em size in pixels of frame text (the HUD, tile labels) in a view of `tile_width` x
/// `tile_height`: 2.7 % of the shorter side, rounded (13 at 480, 26 at 960, 29 at 1080), and at
/// least kHudMinTextPixels.
int FrameTextPixels(int tile_width, int tile_height);

/// FrameTextPixels for the HUD, or 0 where the view is smaller than kHudMinTileWidth x
/// kHudMinTileHeight and the HUD is left out. The view's size alone decides, never the text:
/// the HUD is on every frame of a run or on none.
int HudTextPixels(int tile_width, int tile_height);

/// How a frame is shown: `drawn` of its pixels become `shown` pixels ({1, 1}: as drawn). A GIF
/// 320 wide of 480-wide frames is {320, 480}: its frame text is sized for the 320-pixel view it
/// becomes and drawn 1.5 times larger into the 480-pixel frame, so that once scaled down it
/// reads as in a 320-pixel video (10 px, not the 8.7 px that 13 px text shrinks to).
struct ShownScale {
  int shown = 1;  ///< pixels on screen ...
  int drawn = 1;  ///< ... per this many pixels drawn
};

/// FrameTextPixels of the view that a `tile_width` x `tile_height` tile becomes when shown at
/// `scale`, in drawn pixels (rounded).
int FrameTextPixels(int tile_width, int tile_height, ShownScale scale);

/// HudTextPixels likewise: 0 where the shown view is too small for the HUD (a GIF 320 wide of
/// two 480-pixel views side by side shows each at 160 x 160: no HUD).
int HudTextPixels(int tile_width, int tile_height, ShownScale scale);

/// Below this --hud-opacity (the box then dims the scene by less than half) HUD and tile-label
/// text gets a 1-pixel black outline, so that it reads on white; at and above it (the default
/// 0.6 included) the text is drawn without one.
inline constexpr double kHudOutlineBelowOpacity = 0.5;

/// Where the HUD box of `hud` goes in `tile` at `position`, or nullopt where the tile is too
/// small for it (HudTextPixels is 0). The box's size depends on the tile and on which rows
/// `hud` has, not on the values in them: a value wider than its column is cut with "...".
/// With `scale`, the HUD is sized for the tile as shown (HudTextPixels(..., scale)).
std::optional<PixelRect> PlaceHud(const HudText& hud, const PixelRect& tile, HudPosition position,
                                  ShownScale scale = {});

/// Draws `hud` into `rgb` (`width` x `height` RGB24, row 0 on top) inside `tile` at `position`:
/// a black box blended at `opacity` and the text over it (outlined in black below
/// kHudOutlineBelowOpacity). Returns false (nothing drawn) where
/// the tile is too small for it.
bool DrawHud(uint8_t* rgb, int width, int height, const PixelRect& tile, const HudText& hud,
             HudPosition position, double opacity, ShownScale scale = {});

/// Draws the camera name `label` at the top centre of `tile` (the bottom centre where that
/// would overlap `avoid`, the HUD box) on a box blended at `opacity`, its text sized for the tile
/// as shown at `scale`; nothing where the tile is too small. Returns whether it was drawn.
bool DrawTileLabel(uint8_t* rgb, int width, int height, const PixelRect& tile,
                   const std::string& label, double opacity, const std::optional<PixelRect>& avoid,
                   ShownScale scale = {});

/// The contacts overlay's line: the left and right fingers' forces on the object, the grasp, where
/// the object is, and the arrows' scale ("L 747 N  R 781 N  grasp  off table  |  1 cm = 20 N").
std::string ContactLabel(const FrameInfo& info);

/// Draws ContactLabel(info) at the bottom centre of `tile` (the top where that would overlap
/// `avoid`, the HUD box) on a box of `opacity`; nothing in a view too small for the HUD
/// (HudTextPixels) or too narrow for the line. Returns whether it was drawn.
bool DrawContactLabel(uint8_t* rgb, int width, int height, const PixelRect& tile,
                      const FrameInfo& info, double opacity, const std::optional<PixelRect>& avoid,
                      ShownScale scale = {});

}  // namespace fetchscope
