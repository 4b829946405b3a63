// The report's episode viewer (web/src/viewer.js): per episode, every per-step signal it plots on
// one step axis, computed here once from the episode's trajectory: distance to the goal, reward,
// the action, commanded versus achieved gripper displacement, finger width and gripper command,
// object height and object-goal distance, the hindsight relabelled rewards; and where the first
// and last frame lie in the episode's contact sheet, for the episode table's thumbnails.
#pragma once

#include <array>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "inspect/report.h"
#include "run/manifest.h"
#include "src/env_spec.h"
#include "src/trajectory.h"

namespace fetchscope {

/// Metres the mocap target moves per unit of a[0:3] (Fetch's _set_action: pos *= 0.05).
inline constexpr double kActionScale = 0.05;

/// The per-step signals of one episode of `spec`, each a list with one value per frame (t = 0 ..
/// T; null where a step has none, such as the reset's action, or the value is not finite):
/// "distance" (achieved to desired goal), "reward", "action" (4 lists, as given), "commanded"
/// (3 lists: kActionScale x the action clipped to [-1, 1]), "achieved" (3 lists: grip_pos[t] -
/// grip_pos[t-1]), "finger_width" (gripper_state.right + .left), "gripper_command" (the clipped
/// a[3]; only where the gripper is not blocked), "object_height" (object_pos.z) and
/// "object_goal_distance" (object_pos to the desired goal) with an object; the indices are
/// src/observation_layout.h's; "her" when `hindsight_seed` is given: per transition the kHindsightK
/// relabelled rewards ("rewards", k lists) and how many count as success ("successes"), as record's
/// hindsight overlay samples them for that seed (HindsightSeed(run seed, episode)); "contacts"
/// where the steps carry them (--signals contacts): "left_finger_force" and "right_finger_force"
/// (N, on the object), "grasped" (both press it) and "object_on_table", one per step, and the
/// pairs' "colors" as the contacts overlay draws them.
nlohmann::json EpisodeSignals(const EnvSpec& spec, const std::vector<TrajectoryStep>& steps,
                              std::optional<uint64_t> hindsight_seed = std::nullopt);

/// Where two tiles of a contact sheet lie, in sheet pixels.
struct SheetThumbs {
  int sheet_width = 0;   ///< the whole sheet
  int sheet_height = 0;  ///< the whole sheet
  int tile_width = 0;    ///< each tile's picture (without its label bar)
  int tile_height = 0;
  std::array<int, 2> first{};  ///< top-left corner of the first tile (frame 0)
  std::array<int, 2> last{};   ///< top-left corner of the last tile (the last frame)
};

/// The first and last tiles of a contact sheet of `sheet_width` x `sheet_height` pixels holding
/// `tiles` tiles laid out by MakeContactSheet (default columns, any tile width); nullopt when no
/// layout of that many tiles has that size.
std::optional<SheetThumbs> LocateSheetThumbs(int sheet_width, int sheet_height, int tiles);

/// How many tiles record put on the sheet of an episode of `frames` frames in a run of
/// `steps_requested` steps per episode with --sheet-every `every` (the planned frames it reached,
/// and its last frame always).
int SheetTileCount(int frames, int steps_requested, int every);

/// {width, height} from a PNG file's header; nullopt when it is not a readable PNG.
std::optional<std::pair<int, int>> PngSize(const std::filesystem::path& path);

/// One lazily parsed data block of a page: its element id and its JSON text.
using PageBlock = std::pair<std::string, std::string>;

/// The viewer's part of the report of the run in `dir` described by `manifest` (the episodes'
/// trajectories read with ReadTrajectory): adds to
/// `report_data` (ReportData's JSON) a "viewer" object (which plots the task has, and "layout":
/// the observation indices the plots' titles name, {"finger_width": "obs[9] + obs[10]",
/// "object_height": "obs[5]" or null}, from src/observation_layout.h) and, per
/// recorded episode, "viewer" (whether its signals are on the page) and "thumbs" (its sheet's
/// first and last tile, or null); returns one block per episode with signals, id
/// "fetchscope-episode-K", for the page to parse when the episode's view opens. An episode whose
/// trajectory cannot be read has none (ReportData notes why).
std::vector<PageBlock> AddEpisodeViewers(const std::filesystem::path& dir, const Manifest& manifest,
                                         nlohmann::json* report_data);

/// The viewer's part of `compare`'s page (A and B on one step cursor, over the comparison video):
/// adds to `page_data` a "viewer" object (the threshold, which plots the task has, "layout" as
/// AddEpisodeViewers writes it) and, per
/// compared episode (its "episodes" rows, by "index"), "viewer_a" and "viewer_b" (whether the run's
/// signals are on the page); returns their blocks, ids "fetchscope-a-episode-K" and
/// "fetchscope-b-episode-K".
std::vector<PageBlock> AddCompareViewers(const RecordedRun& a, const RecordedRun& b,
                                         nlohmann::json* page_data);

}  // namespace fetchscope
