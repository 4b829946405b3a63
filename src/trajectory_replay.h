// `--policy replay:FILE.json` where FILE is fetchscope's own trajectory JSON (record's
// episode_NNN.json, rollout's --json-out): every episode of it, by its index, each action in
// the precision the episode was recorded in (`action_dtype`), so that replaying a recorded
// run reproduces it bit for bit.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "src/action.h"

namespace fetchscope {

/// One episode of a trajectory file.
struct TrajectoryEpisode {
  std::vector<Action> actions;  ///< the actions of steps 1..length
  bool complete = true;         ///< false: SIGINT/SIGTERM ended it early
  std::string dtype;            ///< "float32" or "float64" ("none" when it has no step)
};

/// A trajectory file's episodes and what it was recorded with.
struct TrajectoryReplay {
  std::map<int, TrajectoryEpisode> episodes;  ///< by episode index
  std::string env_id;                         ///< as recorded
  std::string seed;                           ///< as recorded (decimal)
};

/// True when `text` is a trajectory JSON document (an object with an "episodes" array).
bool IsTrajectoryJson(const std::string& text);

/// Parses a trajectory JSON. Throws RunError naming the file, the episode and step, for
/// anything malformed: a missing or non-numeric action, an action_dtype other than float32 or
/// float64, a float32 episode with a value that is not a float32, a repeated index.
TrajectoryReplay ParseTrajectoryReplay(const std::string& text, const std::string& name);

/// Reads `path` if it is a .json trajectory file; nullopt for any other replay file.
std::optional<TrajectoryReplay> ReadTrajectoryReplay(const std::string& path);

}  // namespace fetchscope
