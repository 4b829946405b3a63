// The trajectory: episodes as fetchscope records them (rollout --json-out, record's
// episode_NNN.json), in memory and on disk. One type, one writer, one reader: replay:FILE.json,
// record --from and the report read it here, and every file is written here, with doubles
// formatted as Python's json.dumps writes them (base/json_util.h), so that bytes are stable.
//
// The file (docs/reference/file-formats.md, "Trajectory JSON"):
//   {"schema_version", "env_id", "seed", "policy", "assets": {kind, path, sha256, origin},
//    "episodes": [{"index", "length", "complete", "return", "is_success", "action_dtype",
//                  "steps": [{"t", "observation", "achieved_goal", "desired_goal", "action",
//                             "reward", "is_success"}, ...]}, ...]}
// With --signals contacts each step also carries "contacts": {"left_finger_force",
// "right_finger_force", "grasped", "object_on_table", "list": [{"pair", "geom1", "geom2", "body1",
// "body2", "position", "normal", "normal_force", "penetration"}]} (an addition: older readers,
// which skip members they do not know, read such files as before, so the version is unchanged).
// Step 0 is the reset (action and reward null). Steps past the env's TimeLimit (--steps above
// max_episode_steps) carry "past_time_limit": true, their episode "past_time_limit":
// {"max_episode_steps", "first_step", "steps"} and the file a "note"; files without such steps
// have none of these keys. An episode whose reset was placed by hand (serve) carries "reset":
// {"rule": "placed", "goal", "object_position", "object_euler"} (PlacedReset; an addition like
// "contacts"), and one rendered with a randomized look its draw, "look" (render/look.h). Non-finite
// values are written as the strings "inf", "-inf" and "nan" (JSON has no literal for them) and read
// back as such.
//
// Versions, as the manifest's (run/manifest.h): the file carries "schema_version"
// (kTrajectorySchemaVersion). A file without one was written before versions existed and is read
// as version 0, the same layout; a newer version is refused in one line naming the file and both
// versions.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "src/action.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/fetch_env.h"

namespace fetchscope {

/// The trajectory schema version this build writes, and the newest it reads.
inline constexpr int kTrajectorySchemaVersion = 1;

/// One row of a trajectory: t = 0 is the reset observation.
struct TrajectoryStep {
  int t = 0;                     ///< steps since reset
  Observation obs;               ///< observation after this step (after the reset at t = 0)
  std::optional<Action> action;  ///< what the policy gave, in its dtype (none at t = 0)
  std::optional<double> reward;  ///< none at t = 0
  bool is_success = false;       ///< distance < threshold
  /// t > the env's max_episode_steps: a step Gymnasium's TimeLimit would not give before a
  /// reset (--steps beyond it); written as "past_time_limit": true, and only then
  bool past_time_limit = false;
  /// The contacts of the state after this step (record/rollout --signals contacts); written as
  /// "contacts" and only then (docs/reference/file-formats.md: an addition older readers skip,
  /// so the schema version stays)
  std::optional<ContactSignals> contacts;
};

/// An episode's reset placed by hand (serve's "place" form) rather than drawn by the reset
/// generator: FetchEnv::ResetTo(goal, object) after the episode's own reset. Written as the
/// episode's "reset": {"rule": "placed", "goal", "object_position", "object_euler"} (the object's
/// members on object tasks only); record --from resets there.
struct PlacedReset {
  std::array<double, 3> goal{};      ///< desired goal, m
  std::optional<ObjectPose> object;  ///< the object's pose (object tasks)
};

/// One episode: its reset and its steps.
struct TrajectoryEpisode {
  int index = 0;                      ///< episode number within the run
  std::vector<TrajectoryStep> steps;  ///< steps[0] is the reset
  double episode_return = 0;          ///< sum of rewards
  /// false when the episode was ended early (SIGINT/SIGTERM, an interrupted policy) before
  /// all its steps: it is kept as far as it got and said so ("complete": false)
  bool complete = true;
  /// the seed its reset was given, where known (a trajectory file's episode 0: the file's
  /// seed; later episodes continue the generator and have none). Not written to the file.
  std::optional<uint64_t> seed;
  std::string file;  ///< the file it was read from, for messages ("" when played here)
  std::optional<PlacedReset> placed;  ///< a reset placed by hand; nullopt: the generator's
  /// the randomized look its frames were drawn with (--randomize: render/look.h's LookJson, read
  /// back there); null: the plain look. Written as the episode's "look", only when set
  nlohmann::json look;
};

/// A trajectory file: the run's environment and policy, and its episodes in file order.
struct Trajectory {
  /// as read: 0 for a file from before versions; what this build writes otherwise (the writer
  /// always writes kTrajectorySchemaVersion)
  int schema_version = kTrajectorySchemaVersion;
  std::string env_id;                       ///< e.g. "FetchPush-v4"
  uint64_t seed = 0;                        ///< the run's seed (episode 0's reset)
  std::string policy;                       ///< the policy that made it ("" when unknown)
  AssetSource assets;                       ///< kind, root, sha256, origin (no fetch_dir)
  std::vector<TrajectoryEpisode> episodes;  ///< in file order, indices distinct
};

/// "float32" or "float64": the dtype of the episode's actions (its first), "none" without
/// a step. The file's "action_dtype".
std::string ActionDtype(const TrajectoryEpisode& episode);

// ---- writer

/// {"kind", "origin", "path", "sha256"} of `assets`, as every output records them.
nlohmann::json AssetsJson(const AssetSource& assets);

/// A step's "contacts" member (ContactSignals as the trajectory writes it).
nlohmann::json ContactsJson(const ContactSignals& contacts);

/// The step rows of one episode (t, observation, achieved_goal, desired_goal, action, reward,
/// is_success), as in the trajectory JSON; golden state files hold the same rows.
nlohmann::json StepsJson(const TrajectoryEpisode& episode);

/// One episode as JSON: {"index", "length", "complete", "return", "is_success",
/// "action_dtype", "steps": [...]}.
nlohmann::json EpisodeJson(const TrajectoryEpisode& episode);

/// The trajectory file from episodes already made into JSON (EpisodeJson), in order: how
/// workers hand their episodes to the parent.
nlohmann::json TrajectoryJson(const EnvSpec& spec, const AssetSource& assets, uint64_t seed,
                              const std::string& policy, nlohmann::json episodes);

/// The trajectory file.
nlohmann::json TrajectoryJson(const Trajectory& trajectory);

/// The bytes of the trajectory file: TrajectoryJson as DumpJson writes it, and a newline.
std::string TrajectoryText(const Trajectory& trajectory);

// ---- reader

/// Parses the text of a trajectory file. `file` names it in errors. Throws RunError naming the
/// file and the key, e.g. "run.json: episodes[2].steps[5].action: expected 4 numbers": for text
/// that is not JSON, a schema_version that is not an integer of at least 0 or is newer than
/// kTrajectorySchemaVersion ("run.json: has trajectory schema version 2; this fetchscope reads
/// versions 0 to 1: use a newer fetchscope"), a missing or mistyped member, an action_dtype other
/// than float32, float64 or none, a float32 episode with a value that is not a float32, a
/// non-finite action, an index given twice. Numbers keep every bit (-0.0 included); "inf", "-inf"
/// and "nan" read as those values, except in actions.
Trajectory ParseTrajectory(const std::string& text, const std::string& file);

/// ParseTrajectory of a document already parsed (or built in memory): the same checks, with no
/// text in between.
Trajectory ParseTrajectoryJson(const nlohmann::json& root, const std::string& file);

/// Reads and parses the trajectory file `path` (ParseTrajectory). Throws RunError when it
/// cannot be read, UsageError when it is not a regular file or holds more than kMaxJsonFileBytes
/// (base/confined_file.h).
Trajectory ReadTrajectory(const std::string& path);

/// For `--policy replay:FILE`: the trajectory in `path` when it is a .json file holding one
/// (an object with an "episodes" list), read once; nullopt for any other file (bare action rows,
/// or a file that cannot be read: ReadReplayFile says why). Throws RunError "replay file
/// PATH: KEY: ..." for a malformed trajectory, UsageError for a file that is not a regular file
/// or holds more than kMaxJsonFileBytes.
std::optional<Trajectory> ReadReplayTrajectory(const std::string& path);

/// As ReadReplayTrajectory, on the bytes `text` of the .json file `path` already read.
std::optional<Trajectory> ParseReplayTrajectory(const std::string& text, const std::string& path);

}  // namespace fetchscope
