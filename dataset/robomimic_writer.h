// Writes robomimic's HDF5 layout (docs/guide/datasets.md, "robomimic"), the one robomimic,
// MimicGen, LIBERO and diffusion_policy's robomimic loader read: `data` (attrs total, env_args),
// `data/demo_N` (attr num_samples; actions, rewards, dones, states, obs/KEY, next_obs/KEY) and
// `mask/train|valid`. The file is written under a temporary name beside it and renamed into place
// when complete.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "base/atomic_file.h"
#include "dataset/hdf5_handles.h"
#include "dataset/minari_format.h"
#include "dataset/pixel_obs.h"
#include "src/env_spec.h"

namespace fetchscope {

/// What the file is and holds.
struct RobomimicWriteOptions {
  std::filesystem::path file;           ///< --robomimic FILE.hdf5
  bool overwrite = false;               ///< replace an existing file
  const EnvSpec* spec = nullptr;        ///< the env (required)
  int max_episode_steps = 0;            ///< env_kwargs' max_episode_steps (0: the spec's)
  const PixelLayout* pixels = nullptr;  ///< images and states (layout.states must be set)
  bool next_obs = true;                 ///< write next_obs (robomimic's --exclude-next-obs: off)
  double valid_fraction = 0;            ///< mask/valid's share of the demos (0: no mask)
  std::string env_args;                 ///< merge-datasets: a shard's env_args, kept as it is
};

/// Refuses an existing file without `overwrite` (UsageError naming it), a name not ending in
/// .hdf5 or .h5, and a folder that cannot be written (RunError), leaving nothing behind.
void CheckRobomimicDestination(const RobomimicWriteOptions& options);

/// One robomimic file being written.
class RobomimicWriter {
 public:
  /// Checks the destination and creates the temporary file (RunError if it cannot).
  explicit RobomimicWriter(const RobomimicWriteOptions& options);
  ~RobomimicWriter();
  RobomimicWriter(const RobomimicWriter&) = delete;
  RobomimicWriter& operator=(const RobomimicWriter&) = delete;

  /// Appends demo_<n> from `episode` (T steps) and its staged images and states (T+1 rows):
  /// obs row t is the state before action t, next_obs row t the state after it.
  void Add(const MinariEpisode& episode, const StagedEpisode& staged);

  /// Appends demo_<n> as a copy of `demo` (e.g. "data/demo_3") of the open HDF5 file `source`
  /// (a shard), whose num_samples is `samples`. Throws RunError naming `label`.
  void AddCopy(hid_t source, const std::string& demo, int64_t samples, const std::string& label);

  /// Stores `selection` (which of the run's episodes these are) as data's attr "selection".
  void SetSelection(const nlohmann::json& selection) { selection_ = selection; }

  /// Writes the masks and data's attrs, closes the file and renames it into place. Returns the
  /// final path.
  std::filesystem::path Commit();

 private:
  RobomimicWriteOptions options_;
  PixelLayout pixels_;  // the geometry from the first demo
  ParentFolders parents_;
  std::string temp_;
  H5File file_;
  H5Group data_;
  nlohmann::json selection_;
  int demos_ = 0;
  int64_t total_ = 0;
};

/// env_args: {"env_name", "type": 2 (robomimic's gym type), "env_kwargs": {"reward_type",
/// "max_episode_steps"}} as json.dumps(..., indent=4) writes it.
std::string RobomimicEnvArgs(const EnvSpec& spec, int max_episode_steps);

/// The demos of mask/valid for `demos` demos: demo i where floor((i + 1) f) > floor(i f), spread
/// evenly over the file (none for f = 0).
std::vector<int> ValidDemos(int demos, double fraction);

}  // namespace fetchscope
