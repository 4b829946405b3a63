// Where episodes come from: played live by a policy (EpisodeSequence), or replayed from a
// recording (EpisodeReplayer over a TrajectorySource, record --from; the hindsight overlay
// replays an episode it has just played). Every source starts episode k from the reset a
// sequential run reaches there, so an episode is the same whichever worker plays it.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "base/errors.h"
#include "src/episode.h"
#include "src/fetch_env.h"
#include "src/policy_spec.h"
#include "src/trajectory.h"

namespace fetchscope {

/// An environment and a policy that can start any episode of a run exactly as a sequential
/// run would reach it: before episode k it replays the resets and the policy's draws of the
/// episodes between the last one played and k (a reset draws only from the env's generator).
class EpisodeSequence {
 public:
  /// `seed` seeds episode 0's reset; later episodes continue the generator.
  EpisodeSequence(std::unique_ptr<FetchEnv> env, std::unique_ptr<Policy> policy, uint64_t seed,
                  int steps);
  // out of line: Policy is only declared here (src/policy.h stays out of this header)
  ~EpisodeSequence();
  EpisodeSequence(EpisodeSequence&&) noexcept;
  EpisodeSequence& operator=(EpisodeSequence&&) noexcept;
  /// Plays episode k (k greater than any played before), calling `on_step` as RunEpisode does.
  EpisodeRecord Play(int k, const StepCallback& on_step = nullptr);

  /// --stop-after-success K: end each episode K steps after its first success after a step
  /// (t >= 1), complete (a shorter episode, truncated as Minari marks every episode's end); the
  /// policy's generator then moves on as if the episode had run all its steps, so that every
  /// episode is the start of the same episode of a run without the option, whatever --jobs. -1:
  /// off.
  void SetStopAfterSuccess(int k) { stop_after_success_ = k; }

  FetchEnv& env() { return *env_; }      ///< the environment
  Policy& policy() { return *policy_; }  ///< the policy
  int steps() const { return steps_; }   ///< steps per episode

 private:
  std::unique_ptr<FetchEnv> env_;
  std::unique_ptr<Policy> policy_;
  uint64_t seed_;
  int steps_;
  int next_ = 0;  // the episode the generators stand at
  int stop_after_success_ = -1;
};

/// How a dataset episode starts (record --from DATASET): reset with its own seed, or, where it
/// has none, rebuilt from its first observation (FetchEnv::ResetTo).
struct EpisodeStart {
  std::optional<uint64_t> seed;      ///< the episode's `seed`; nullopt: rebuilt
  std::array<double, 3> goal{};      ///< desired_goal[0]
  std::optional<ObjectPose> object;  ///< observation[0]'s object pose (object tasks)
  /// An episode without a seed that follows a seeded one: the reset generator as the previous
  /// reset left it, where continuing it gives the dataset's first row bit for bit (the
  /// "one seeded reset, then reset()" collection; MeasureDivergence finds it). Preferred to the
  /// rebuild: it is the env's own reset, hidden state (the object's quaternion) included.
  std::optional<NumpyGenerator> generator;
  int continued_from = -1;  ///< the seeded episode whose generator it continues
  /// a recording's episode whose reset was placed by hand (TrajectoryEpisode::placed): reset
  /// there by FetchEnv::ResetTo, and checked step by step as any recording
  bool placed = false;
  /// "seed", "continued generator", "placed" or "first observation": said per episode in the
  /// console, manifest and report.
  const char* Rule() const {
    return seed        ? "seed"
           : generator ? "continued generator"
           : placed    ? "placed"
                       : "first observation";
  }
};

/// How far a replayed dataset episode drifts from the dataset, row by row.
struct EpisodeDivergence {
  std::string reset;          ///< EpisodeStart::Rule()
  int continued_from = -1;    ///< "continued generator": the seeded episode it continues
  double tolerance = 0;       ///< --tolerance
  int first_step = -1;        ///< first row t (0 = the reset) off by more than it; -1: none
  std::string where;          ///< its first value off, e.g. "observation[3]"
  std::string component;      ///< its name in src/observation_layout.h, e.g. "object_pos.x"
  std::string unit;           ///< its unit: "m", "m/step", "rad", "rad/step"
  double difference = 0;      ///< replayed - recorded there
  double max_difference = 0;  ///< largest |replayed - recorded| over every row
  int max_step = -1;          ///< the row of the largest difference; -1: none differs
  std::string max_where;      ///< its value, e.g. "observation[11]"
  std::string max_component;  ///< e.g. "object_rot.z"
  std::string max_unit;       ///< e.g. "rad"
  double max_signed = 0;      ///< replayed - recorded there
  /// per row t: how far the replayed gripper (grip_pos) and object (object_pos; empty for
  /// Reach) are from the recorded ones, in metres (the viewer's "replayed vs recorded" plot)
  std::vector<double> gripper_error, object_error;
};

/// Recorded episodes to replay (record --from): one trajectory file, or every episode_NNN.json
/// of a run folder, which must all be one run (one env id and seed); or a Minari dataset
/// (dataset/minari_source.h), whose episodes each start as `starts` says.
struct TrajectorySource {
  std::string path;                           ///< as given
  std::string env_id;                         ///< trajectory env_id
  uint64_t seed = 0;                          ///< trajectory seed (episode 0's reset)
  std::string policy;                         ///< the policy that made it (for the manifest)
  AssetSource assets;                         ///< trajectory assets (kind, root, sha256, origin)
  std::map<int, TrajectoryEpisode> episodes;  ///< by index; each names the file it came from
  int max_steps = 0;                          ///< the longest episode's steps
  /// A dataset: how each episode starts (by index). A fetchscope recording: its episodes placed
  /// by hand (EpisodeStart::placed); the others' episode 0 resets with `seed` and the others
  /// continue the generator.
  std::map<int, EpisodeStart> starts;
  /// A dataset: replayed steps are compared within `tolerance` and any divergence is reported
  /// (MeasureDivergence), never fatal; the dataset's achieved goal shows as a ghost marker.
  bool dataset = false;
  double tolerance = 0;                         ///< --tolerance (a dataset)
  std::string found;                            ///< a dataset: what was found, one line
  std::map<int, EpisodeDivergence> divergence;  ///< by index, once measured
};

/// Reads a trajectory JSON file, or every episode_NNN.json of a run folder. Throws UsageError
/// for a path that is neither, RunError naming the file and key (ReadTrajectory) for content
/// that is not a fetchscope trajectory, and for files that mix env ids or seeds or repeat an
/// episode. Messages start with "--from".
TrajectorySource LoadTrajectorySource(const std::string& path);

/// The --assets value that reproduces `source`: "bundled" for bundled assets, else the
/// recorded folder.
std::string SourceAssets(const TrajectorySource& source);

/// Replays recorded episodes on one environment: episode k starts from the reset the run made
/// (episode 0's reset seeded with `seed`, the others continuing the generator: the resets in
/// between are replayed, as EpisodeSequence does), then steps the recorded actions.
class EpisodeReplayer {
 public:
  EpisodeReplayer(FetchEnv& env, uint64_t seed) : env_(env), seed_(seed) {}
  /// Replays episode `k` with the actions of `recorded` (steps 1..), calling `on_step` as
  /// RunEpisode does. With `check` set, each replayed observation, reward and success flag must
  /// equal the recorded ones exactly; the first that does not throws ReplayMismatch naming
  /// `check` (the file), the episode, the step, the value and the difference. The result is
  /// complete only when `recorded_complete` and every recorded step was replayed (`on_step`
  /// may stop it early).
  EpisodeRecord Replay(int k, const std::vector<StepRecord>& recorded, bool recorded_complete,
                       const std::string& check, const StepCallback& on_step);
  /// Replays `recorded` as episode `k`: from its reset placed by hand where it has one
  /// (TrajectoryEpisode::placed, FetchEnv::ResetTo), else as Replay; checked against `check`.
  EpisodeRecord ReplayEpisode(int k, const TrajectoryEpisode& recorded, const std::string& check,
                              const StepCallback& on_step);
  /// Replays episode `k` of `source`: as Replay with the exact check for a recording; for a
  /// dataset, from its EpisodeStart and unchecked (MeasureDivergence measured it).
  EpisodeRecord ReplaySource(const TrajectorySource& source, int k, const StepCallback& on_step);

 private:
  EpisodeRecord ReplayFrom(int k, const Observation& reset, const std::vector<StepRecord>& recorded,
                           bool recorded_complete, const std::string& check,
                           const StepCallback& on_step);

  FetchEnv& env_;
  uint64_t seed_;
  int next_ = 0;  // the episode whose reset the generator stands before
};

/// The message of a replayed step that differs from the recording (see EpisodeReplayer); one
/// line, which record prints alone.
struct ReplayMismatch : RunError {
  using RunError::RunError;
};

/// Where replay and recording differ first in one step, or "" when they agree: e.g.
/// "observation[3] recorded 1.3, replayed 1.2 (difference replayed - recorded -0.1)".
std::string FirstDifference(const StepRecord& replayed, const StepRecord& recorded);

/// Replays every episode of `source` on `env` (no rendering) and checks each step as
/// EpisodeReplayer does: an edited recording stops the run before anything is written. Throws
/// ReplayMismatch.
void VerifyRecording(FetchEnv& env, const TrajectorySource& source);

/// Resets `env` as `start` says (its seed, else its generator continued, else
/// FetchEnv::ResetTo).
Observation ResetForStart(FetchEnv& env, const EpisodeStart& start);

/// Resolves how each episode of the dataset `source` starts, by resets alone: an episode without
/// a seed whose id follows a seeded (or continued) one keeps that generator continued
/// (EpisodeStart::generator, "continued generator") where its reset gives the dataset's first row
/// bit for bit; the others keep their seed or their first observation.
void ResolveStarts(FetchEnv& env, TrajectorySource* source);

/// The divergence of episode `k` of the dataset `source` (its start resolved) from `replayed`,
/// its observations as replayed from that start (row t = the observation after step t).
EpisodeDivergence CompareReplay(const TrajectorySource& source, int k,
                                const std::vector<Observation>& replayed);

/// Replays every episode of the dataset `source` on `env` (no rendering) and fills
/// `source->divergence` (ResolveStarts, then each episode replayed and CompareReplay): every
/// observation, achieved_goal and desired_goal row against the dataset's, within
/// `source->tolerance`. An episode without a seed whose id follows a seeded (or continued) one is
/// first reset by continuing that generator; where that gives the dataset's first row bit for bit,
/// its start keeps the generator (Rule() "continued generator"), else it is rebuilt from the first
/// row.
void MeasureDivergence(FetchEnv& env, TrajectorySource* source);

/// The dataset's own achieved goal at row `t` of episode `k` (the ghost marker); nullopt for a
/// recording (it replays exactly) or a row the dataset does not have.
std::optional<std::array<double, 3>> RecordedAchieved(const TrajectorySource& source, int k, int t);

/// For `--policy replay:FILE.json` holding a trajectory (the spec holds it, read once): the
/// file's episode indices, ascending, which a run replaying it plays (each under its own index,
/// so with its own reset); nullopt for any other policy. `episodes` is --episodes when the
/// user gave it (0: not given): a different count is a UsageError, and so is a file recorded on
/// another env or seed than `env_id` / `seed` (it would not reproduce the recording).
std::optional<std::vector<int>> ReplayedEpisodes(const PolicySpec& policy, int episodes,
                                                 const std::string& env_id, uint64_t seed);

}  // namespace fetchscope
