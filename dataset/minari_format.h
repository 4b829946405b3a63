// What Minari 0.5 datasets look like, shared by the writer and the reader: the per-episode
// arrays, where a dataset id lives on disk, and the metadata strings (spaces, env_spec) exactly
// as Minari and Gymnasium serialise them. The layout itself is described in docs/guide/datasets.md.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "src/env_spec.h"

namespace fetchscope {

/// One episode as Minari stores it: T steps, T+1 observation rows (row 0 is the reset).
struct MinariEpisode {
  int64_t id = 0;                     ///< the episode group's `id` attribute (episode_<id>)
  std::optional<uint64_t> seed;       ///< the reset seed, where the episode was seeded
  int obs_dim = 0;                    ///< width of `observation`: 10 (Reach) or 25
  std::vector<double> observation;    ///< (T+1) x obs_dim, row-major
  std::vector<double> achieved_goal;  ///< (T+1) x 3
  std::vector<double> desired_goal;   ///< (T+1) x 3
  std::vector<float> actions;         ///< T x 4, as applied (after clipping)
  std::vector<double> rewards;        ///< T (read from float32 or float64)
  std::vector<uint8_t> terminations;  ///< T, 0 or 1
  std::vector<uint8_t> truncations;   ///< T, 0 or 1
  std::vector<float> is_success;      ///< T+1 (0 or 1), or empty where the dataset has none
  std::string look;                   ///< a randomized look's draw as JSON text ("" plain)

  /// T, the number of steps (the length of `rewards`).
  int steps() const { return static_cast<int>(rewards.size()); }
};

/// The `minari_version` the writer stores: accepted by every Minari 0.5.x loader.
inline constexpr const char* kMinariVersionWritten = "0.5.0";

/// True for the versions Minari 0.5.3's loader accepts (its `supported_dataset_versions`:
/// 0.4.0-0.4.3 and 0.5.0-0.5.3, exact strings, not specifiers).
bool IsSupportedMinariVersion(const std::string& version);

/// Checks a dataset id against Minari's `(namespace/)name-vN` form (the version is required,
/// as `parse_dataset_id` needs it). Throws UsageError naming the id and the form otherwise.
void ValidateMinariDatasetId(const std::string& id);

/// True when `id` has that form. The one rule for ids, read or written: an id names a folder
/// under the datasets root and never leaves it (no "..", no leading "/"); a dataset elsewhere is
/// given by its path.
bool IsMinariDatasetId(const std::string& id);

/// The datasets root: `flag` if not empty, else $MINARI_DATASETS_PATH, else
/// ~/.minari/datasets (Minari's get_dataset_path).
std::filesystem::path MinariRoot(const std::string& flag);

/// The namespace part of an id ("fetchscope/FetchPush" of "fetchscope/FetchPush/scripted-v0"),
/// empty when it has none.
std::string MinariNamespace(const std::string& id);

/// `observation_space` as Minari's serialize_space writes it for a Fetch env: a Dict of three
/// float64 Boxes (keys sorted, as gymnasium's Dict sorts them) with infinite bounds written as
/// the JSON literals -Infinity / Infinity, in Python's json.dumps spacing.
std::string FetchObservationSpaceJson(int obs_dim);

/// The image keys of a pixel dataset's observation space (dataset/pixel_obs.h).
struct PixelSpaces {
  std::vector<std::string> cameras;  ///< camera names
  int width = 0, height = 0;         ///< pixels
  bool rgb = false;                  ///< "images": uint8 (H, W, 3) Boxes, 0..255
  bool depth = false;                ///< "depth": float32 (H, W) Boxes, 0..inf
  bool segmentation = false;         ///< "segmentation": int32 (H, W) Boxes, -1..max_segment
  int max_segment = 0;               ///< the largest object index
};

/// `observation_space` of a pixel dataset: FetchObservationSpaceJson's three Boxes plus, per
/// layer, a Dict of one Box per camera (keys sorted, as gymnasium's Dict sorts them), each with
/// its full `low` and `high` as nested lists, as serialize_space writes any Box.
std::string FetchPixelObservationSpaceJson(int obs_dim, const PixelSpaces& pixels);

/// `action_space`: Box(-1, 1, (4,), float32) in serialize_space's form.
std::string FetchActionSpaceJson();

/// gymnasium's EnvSpec.to_json() for a registered Fetch v4 id after gymnasium.make (id,
/// entry_point, max_episode_steps, order_enforce true, kwargs.reward_type, ...):
/// `max_episode_steps` is the TimeLimit of gym.make(id, max_episode_steps=N); 0: the spec's 50.
std::string FetchEnvSpecJson(const EnvSpec& spec, int max_episode_steps = 0);

/// metadata `requirements`: the pip requirements recover_environment() checks (the
/// Gymnasium-Robotics release whose v4 envs fetchscope matches, and MuJoCo's version).
std::vector<std::string> FetchRequirements();

/// A string as Python's json.dumps writes it (quoted, ASCII-only, \uXXXX escapes).
std::string PythonJsonString(const std::string& s);

/// Parses JSON as Python's json module does: the bare literals Infinity, -Infinity and NaN
/// (which Python writes and nlohmann does not read) are accepted and become the strings
/// "Infinity", "-Infinity" and "NaN". Throws nlohmann::json::parse_error on anything else.
nlohmann::json ParsePythonJson(const std::string& text);

/// A number of a parsed Python JSON value, with "Infinity"/"-Infinity"/"NaN" turned back into
/// doubles; nullopt for anything else.
std::optional<double> PythonJsonNumber(const nlohmann::json& value);

/// Makes libhdf5 print nothing on its own (its default handler prints a stack of errors on
/// stderr for every failed call): our callers turn failures into one line. Also keeps libhdf5
/// from closing files at exit: a file whose close failed (a full disk) stays in libhdf5's list,
/// and its clean-up at exit() then crashed (SIGSEGV in H5F__close_cb); every file is closed by
/// its owner (dataset/hdf5_handles.h), and the kernel closes what a failed close left. Idempotent.
void SilenceHdf5Errors();

/// The operating system's reason behind the last failed libhdf5 call, read from libhdf5's error
/// stack ("No space left on device" where its file driver recorded errno 28), or "" when the
/// stack names none. Call it right after the failure: the next libhdf5 call clears the stack.
std::string Hdf5SystemReason();

}  // namespace fetchscope
