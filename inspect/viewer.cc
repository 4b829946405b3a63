#include "inspect/viewer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "base/errors.h"
#include "encode/contact_sheet.h"
#include "render/overlay.h"
#include "src/fetch_env.h"
#include "src/hindsight.h"
#include "src/observation_layout.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// A plotted value: rounded to 1e-6 (a micrometre is far below what a plot shows, and keeps the
// page small); null where there is none.
json Plotted(double value) {
  if (!std::isfinite(value)) return nullptr;
  return std::round(value * 1e6) / 1e6;
}

json Lists(size_t count) {
  json lists = json::array();
  for (size_t i = 0; i < count; ++i) lists.push_back(json::array());
  return lists;
}

double Clip(double a) { return std::isnan(a) ? a : std::clamp(a, -1.0, 1.0); }

double Distance3(const double* a, const std::array<double, 3>& b) {
  return GoalDistance({a[0], a[1], a[2]}, b);
}

// Where the plotted observation values are (src/observation_layout.h), as the plots' titles name
// them: {"finger_width": "obs[9] + obs[10]", "object_height": "obs[5]" (null without an object)};
// null for an env this build does not know.
json ViewerLayout(const EnvSpec* spec) {
  if (!spec) return nullptr;
  const bool object = spec->has_object;
  return {{"finger_width", FingerWidthText(object)},
          {"object_height",
           object ? json("obs[" + std::to_string(ObservationIndex(true, "object_pos.z")) + "]")
                  : json()}};
}

}  // namespace

json EpisodeSignals(const EnvSpec& spec, const std::vector<TrajectoryStep>& steps,
                    std::optional<uint64_t> hindsight_seed) {
  // the observation's layout (src/observation_layout.h)
  const FingerIndices fingers = FingerPositionIndices(spec.has_object);
  const size_t needed = static_cast<size_t>(ObservationSize(spec.has_object));
  const size_t grip = static_cast<size_t>(FindObservationSlice(spec.has_object, "grip_pos")->first);
  // with an object: its position (and its height, object_pos.z)
  const int object = spec.has_object ? FindObservationSlice(true, "object_pos")->first : -1;
  json distance = json::array(), reward = json::array(), width = json::array();
  json gripper = json::array(), height = json::array(), object_goal = json::array();
  json action = Lists(4), commanded = Lists(3), achieved = Lists(3);
  for (size_t t = 0; t < steps.size(); ++t) {
    const Observation& s = steps[t].obs;
    const std::optional<Action>& a = steps[t].action;
    const bool full = s.observation.size() >= needed;
    distance.push_back(Plotted(GoalDistance(s.achieved_goal, s.desired_goal)));
    reward.push_back(steps[t].reward ? Plotted(*steps[t].reward) : json(nullptr));
    for (size_t i = 0; i < 4; ++i) action[i].push_back(a ? Plotted(a->value[i]) : json());
    const std::vector<double>& before = t > 0 ? steps[t - 1].obs.observation : s.observation;
    const bool moved = t > 0 && full && before.size() >= needed;
    for (size_t i = 0; i < 3; ++i) {
      commanded[i].push_back(a ? Plotted(kActionScale * Clip(a->value[i])) : json());
      achieved[i].push_back(moved ? Plotted(s.observation[grip + i] - before[grip + i]) : json());
    }
    width.push_back(full ? Plotted(s.observation[fingers.right] + s.observation[fingers.left])
                         : json());
    gripper.push_back(a ? Plotted(Clip(a->value[3])) : json());
    height.push_back(full && object >= 0 ? Plotted(s.observation[object + 2]) : json());
    object_goal.push_back(
        full && object >= 0 ? Plotted(Distance3(&s.observation[object], s.desired_goal)) : json());
  }
  json signals = {{"frames", steps.size()},
                  {"distance", std::move(distance)},
                  {"reward", std::move(reward)},
                  {"action", std::move(action)},
                  {"commanded", std::move(commanded)},
                  {"achieved", std::move(achieved)},
                  {"finger_width", std::move(width)}};
  if (!spec.block_gripper) signals["gripper_command"] = std::move(gripper);
  if (spec.has_object) {
    signals["object_height"] = std::move(height);
    signals["object_goal_distance"] = std::move(object_goal);
  }
  // record/rollout --signals contacts: the fingers' forces on the object, N, and the grasp
  if (std::any_of(steps.begin(), steps.end(), [](const TrajectoryStep& s) { return s.contacts; })) {
    json left = json::array(), right = json::array(), grasped = json::array(),
         on_table = json::array();
    for (const TrajectoryStep& s : steps) {
      left.push_back(s.contacts ? Plotted(s.contacts->left_finger_force) : json());
      right.push_back(s.contacts ? Plotted(s.contacts->right_finger_force) : json());
      grasped.push_back(s.contacts ? json(s.contacts->grasped()) : json());
      on_table.push_back(s.contacts ? json(s.contacts->object_on_table) : json());
    }
    signals["contacts"] = {{"left_finger_force", std::move(left)},
                           {"right_finger_force", std::move(right)},
                           {"grasped", std::move(grasped)},
                           {"object_on_table", std::move(on_table)},
                           {"colors",
                            {{"finger-object", ContactPairColor(ContactPair::kFingerObject)},
                             {"object-table", ContactPairColor(ContactPair::kObjectTable)}}}};
  }
  if (hindsight_seed && !steps.empty()) {
    std::vector<std::array<double, 3>> goals;
    for (const TrajectoryStep& s : steps) goals.push_back(s.obs.achieved_goal);
    // FetchEnv::ComputeReward and IsSuccess, from the spec alone
    const auto reward_of = [&spec](const std::array<double, 3>& a, const std::array<double, 3>& g) {
      const double d = GoalDistance(a, g);
      return spec.dense ? -d : d > spec.distance_threshold ? -1.0 : -0.0;
    };
    const auto success_of = [&spec](const std::array<double, 3>& a,
                                    const std::array<double, 3>& g) {
      return GoalDistance(a, g) < spec.distance_threshold;
    };
    const HindsightEpisode h = SampleHindsight(goals, steps.front().obs.desired_goal,
                                               *hindsight_seed, kHindsightK, reward_of, success_of);
    json rewards = Lists(kHindsightK), successes = json::array({nullptr});
    for (json& list : rewards) list.push_back(nullptr);  // the reset: no transition
    for (const std::vector<HindsightGoal>& transition : h.transitions) {
      int n = 0;
      for (size_t i = 0; i < transition.size() && i < rewards.size(); ++i) {
        rewards[i].push_back(Plotted(transition[i].reward));
        n += transition[i].success;
      }
      successes.push_back(n);
    }
    signals["her"] = {{"k", kHindsightK},
                      {"rewards", std::move(rewards)},
                      {"successes", std::move(successes)},
                      {"relabelled_successes", h.relabelled_successes},
                      {"original_successes", h.original_successes}};
  }
  return signals;
}

std::optional<SheetThumbs> LocateSheetThumbs(int sheet_width, int sheet_height, int tiles) {
  if (tiles <= 0 || sheet_width <= 0 || sheet_height <= 0) return std::nullopt;
  // MakeContactSheet: columns = ceil(sqrt(n)), at most n; width = M + columns * (W + M)
  int columns = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(tiles))));
  columns = std::max(1, std::min(columns, tiles));
  const int rows = (tiles + columns - 1) / columns;
  if ((sheet_width - kSheetMargin) % columns != 0) return std::nullopt;
  const int tile_width = (sheet_width - kSheetMargin) / columns - kSheetMargin;
  if (tile_width < 16 || tile_width > 4096) return std::nullopt;
  // height = T + rows * (M + H + L) + M
  const SheetLayout layout = ContactSheetLayout(tile_width);
  const int cells = sheet_height - layout.title_bar_height - kSheetMargin;
  if (cells <= 0 || cells % rows != 0) return std::nullopt;
  const int tile_height = cells / rows - kSheetMargin - layout.label_bar_height;
  if (tile_height <= 0) return std::nullopt;
  const auto corner = [&](int i) {
    return std::array<int, 2>{
        kSheetMargin + (i % columns) * (tile_width + kSheetMargin),
        layout.title_bar_height + kSheetMargin +
            (i / columns) * (kSheetMargin + tile_height + layout.label_bar_height)};
  };
  return SheetThumbs{sheet_width, sheet_height, tile_width,
                     tile_height, corner(0),    corner(tiles - 1)};
}

int SheetTileCount(int frames, int steps_requested, int every) {
  if (frames <= 0) return 0;
  int n = 0;
  for (int i : SheetFrameIndices(std::max(frames, steps_requested + 1), std::max(0, every))) {
    n += i < frames - 1;
  }
  return n + 1;  // the last frame, always
}

std::optional<std::pair<int, int>> PngSize(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char header[24] = {};
  if (!in.read(reinterpret_cast<char*>(header), sizeof(header))) return std::nullopt;
  static const unsigned char kSignature[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (!std::equal(std::begin(kSignature), std::end(kSignature), header) ||
      std::string(reinterpret_cast<char*>(header) + 12, 4) != "IHDR") {
    return std::nullopt;
  }
  const auto big_endian = [&](int at) {
    return static_cast<int>((header[at] << 24) | (header[at + 1] << 16) | (header[at + 2] << 8) |
                            header[at + 3]);
  };
  return std::make_pair(big_endian(16), big_endian(20));
}

std::vector<PageBlock> AddEpisodeViewers(const fs::path& dir, const Manifest& manifest,
                                         json* report_data) {
  std::vector<PageBlock> blocks;
  const EnvSpec* spec = nullptr;
  try {
    spec = &FindEnvSpec(manifest.env_id);
  } catch (const std::exception&) {
    // an env this build does not know: no per-step signals, thumbnails still
  }
  const bool hindsight = manifest.overlay.find("hindsight") != std::string::npos;
  const uint64_t seed = manifest.seed;
  const int steps_requested = manifest.steps_per_episode;
  const int every = manifest.sheet_every;
  json& data = *report_data;
  data["viewer"] = {{"signals", spec != nullptr},
                    {"has_object", spec && spec->has_object},
                    {"gripper_command", spec && !spec->block_gripper},
                    {"hindsight", spec && hindsight},
                    {"reach", spec && spec->task == Task::kReach},
                    {"layout", ViewerLayout(spec)}};
  for (json& e : data["episodes"]) {
    if (e["status"] == "missing") continue;
    e["viewer"] = false;
    e["thumbs"] = nullptr;
    const int k = e["index"].get<int>();
    if (e["sheet"].is_string() && !e["sheet"].get<std::string>().empty()) {
      try {
        const auto size = PngSize(dir / e["sheet"].get<std::string>());
        const int tiles = SheetTileCount(e.value("frames", 0), steps_requested, every);
        const auto thumbs = size ? LocateSheetThumbs(size->first, size->second, tiles)
                                 : std::optional<SheetThumbs>();
        if (thumbs) {
          e["thumbs"] = {{"sheet", {thumbs->sheet_width, thumbs->sheet_height}},
                         {"tile", {thumbs->tile_width, thumbs->tile_height}},
                         {"first", thumbs->first},
                         {"last", thumbs->last}};
        }
      } catch (const std::exception&) {
        // no font for the layout: no thumbnails
      }
    }
    if (!spec || !e["trajectory"].is_string()) continue;
    try {
      const Trajectory trajectory =
          ReadTrajectory((dir / e["trajectory"].get<std::string>()).string());
      if (trajectory.episodes.empty()) continue;
      const std::vector<TrajectoryStep>& steps = trajectory.episodes.front().steps;
      json signals = EpisodeSignals(
          *spec, steps, hindsight ? std::optional<uint64_t>(HindsightSeed(seed, k)) : std::nullopt);
      signals["index"] = k;
      blocks.emplace_back("fetchscope-episode-" + std::to_string(k), signals.dump());
      e["viewer"] = true;
    } catch (const RunError&) {
      // ReportData has noted the unreadable trajectory already
    }
  }
  return blocks;
}

std::vector<PageBlock> AddCompareViewers(const RecordedRun& a, const RecordedRun& b,
                                         json* page_data) {
  std::vector<PageBlock> blocks;
  json& page = *page_data;
  const EnvSpec* spec = nullptr;
  try {
    spec = &FindEnvSpec(a.manifest.env_id);
  } catch (const std::exception&) {
    // an env this build does not know: the videos alone
  }
  page["viewer"] = {{"signals", spec != nullptr},
                    {"threshold", spec ? spec->distance_threshold : 0.05},
                    {"has_object", spec && spec->has_object},
                    {"gripper_command", spec && !spec->block_gripper},
                    {"reach", spec && spec->task == Task::kReach},
                    {"layout", ViewerLayout(spec)}};
  for (json& row : page["episodes"]) {
    const int k = row.value("index", -1);
    for (const auto& [run, side] : {std::pair{&a, "a"}, std::pair{&b, "b"}}) {
      const std::string key = std::string("viewer_") + side;
      row[key] = false;
      const auto entry = run->recorded.find(k);
      if (!spec || entry == run->recorded.end() || entry->second.trajectory.empty()) continue;
      try {
        const Trajectory trajectory =
            ReadTrajectory((run->dir / entry->second.trajectory).string());
        if (trajectory.episodes.empty()) continue;
        json signals = EpisodeSignals(*spec, trajectory.episodes.front().steps);
        signals["index"] = k;
        blocks.emplace_back(std::string("fetchscope-") + side + "-episode-" + std::to_string(k),
                            signals.dump());
        row[key] = true;
      } catch (const RunError&) {
        // compare has read both trajectories already: it would have stopped
      }
    }
  }
  return blocks;
}

}  // namespace fetchscope
