// What `--policy` names, parsed once at the command line's edge (ParsePolicySpec, called from
// cli/) into a typed PolicySpec that every layer below passes on. This header is light on
// purpose (no MuJoCo, no env): the run, serve and inspect headers that carry a PolicySpec include
// it alone; src/policy.h holds the Policy interface and MakePolicy, which build one.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "src/action.h"

namespace fetchscope {

struct Trajectory;
struct WireStep;

/// The cases of a PolicySpec, one per policy.
namespace policy_spec {
struct Random {};    ///< action_space.seed(seed) + sample()
struct Zero {};      ///< all-zero actions
struct Scripted {};  ///< src/scripted_policy.h
/// replay:FILE, read once by ParsePolicySpec: exactly one of `rows` and `trajectory` is set.
struct Replay {
  std::string path;  ///< the file, as read (a relative one joined to PolicyOptions::base_dir)
  /// .csv, .npy, .jsonl or a .json of bare rows: the actions, in order, --replay-dtype applied
  std::shared_ptr<const std::vector<Action>> rows;
  /// fetchscope's trajectory .json: its episodes, each replayed under its own index
  std::shared_ptr<const Trajectory> trajectory;
  std::string dtype;  ///< --replay-dtype: "" (the file's own), "float32" or "float64"
};
/// exec:CMD, a child process speaking JSON lines (src/exec_policy.h).
struct Exec {
  std::string command;    ///< run under /bin/sh
  double timeout_s = 10;  ///< --exec-timeout: seconds to wait for each answer
  /// --exec-fields, checked against the env (ParseExecFields, src/exec_wire.h): the state
  /// fields each line carries, in order; empty: all of them, as before the option existed
  std::vector<std::string> fields;
};
}  // namespace policy_spec

/// A parsed `--policy`: which policy, with everything it needs from outside the process (a
/// replay file's contents), and its text as the user gave it (manifests, titles, trajectories).
struct PolicySpec {
  std::variant<policy_spec::Random, policy_spec::Zero, policy_spec::Scripted, policy_spec::Replay,
               policy_spec::Exec>
      value;
  std::string text;  ///< as given, e.g. "replay:run.csv"; what every output names

  static PolicySpec Random() { return {policy_spec::Random{}, "random"}; }
  /// Zero actions; `text` names it (record --from labels its replay with the recording's
  /// policy, which it does not run).
  static PolicySpec Zero(std::string text = "zero") {
    return {policy_spec::Zero{}, std::move(text)};
  }
  static PolicySpec Scripted() { return {policy_spec::Scripted{}, "scripted"}; }

  /// The replay case, or null.
  const policy_spec::Replay* replay() const { return std::get_if<policy_spec::Replay>(&value); }
  /// A replay of fetchscope's trajectory JSON: the trajectory, else null.
  const Trajectory* replay_trajectory() const {
    const policy_spec::Replay* r = replay();
    return r ? r->trajectory.get() : nullptr;
  }
  /// --replay-dtype as given ("" for every other policy).
  std::string replay_dtype() const { return replay() ? replay()->dtype : std::string(); }
  bool is_exec() const { return std::holds_alternative<policy_spec::Exec>(value); }
};

/// The options that go with `--policy` on the command line.
struct PolicyOptions {
  double exec_timeout_s = 10.0;  ///< --exec-timeout
  /// --replay-dtype: "" (the file's own), "float32" or "float64". CSV and JSON lines are read
  /// in double precision and then, with float32, rounded to float32 and played on Gymnasium's
  /// float32 path; .npy and trajectory JSON carry their dtype (a different one is refused).
  std::string replay_dtype;
  std::string base_dir;  ///< a relative replay:FILE is read from this folder ("": as given)
};

/// Parses `--policy` text: random | zero | scripted | replay:FILE | exec:CMD. A replay file is
/// read here, once, whatever its format. Throws UsageError (one line naming the bad value and
/// the accepted ones) for an unknown name, an empty file or command, or a --replay-dtype that
/// does not fit; RunError naming the file for one that cannot be read or parsed. Called at
/// the command line's edge (cli/) and by the golden manifest's reader; nothing else parses it.
PolicySpec ParsePolicySpec(const std::string& text, const PolicyOptions& options = {});

/// What building a policy needs from the run (never from the command line's text).
struct PolicyContext {
  uint64_t seed = 0;           ///< action_space.seed(seed) for random
  int steps_per_episode = 50;  ///< replay checks it has enough rows
  int episodes = 1;            ///< replay checks it has enough rows
  /// True while the run is being stopped (SIGINT/SIGTERM): an exec: child that dies then is
  /// an interruption (PolicyInterrupted), not a failure. May be empty.
  std::function<bool()> stop_requested;
  /// The episodes the run plays (replay checks the file has them); empty: 0 .. episodes-1.
  std::vector<int> episode_indices;
  /// --obs-camera with an exec: policy: the images of the state the policy is asked about at
  /// step t (src/exec_wire.h), drawn by the worker just before; empty or null: no images.
  std::function<const WireStep*(int t)> images;
};

/// --replay-dtype's help.
inline constexpr const char* kReplayDtypeHelp =
    "float32 or float64: the precision of a replay:FILE .csv or .jsonl's actions (default "
    "float64; float32 rounds each value to float32 and plays it on Gymnasium's float32 path, "
    "as a recorded random policy's actions). A .npy or trajectory .json carries its own";

/// Every policy name --policy accepts (with the ':' of those that take an argument), once: the
/// parser's "did you mean", the completion and the help's test read it.
inline constexpr const char* kPolicyNames[] = {"random", "zero", "scripted", "replay:", "exec:"};

/// The accepted policy names, for --help.
inline constexpr const char* kPolicyHelp =
    "random (seeded like action_space.seed + sample), zero, scripted, replay:FILE "
    "(.csv with 4 columns, .npy T x 4 float32/float64, .jsonl, or fetchscope's trajectory "
    ".json: all its episodes, in their recorded precision), exec:CMD (child process speaking "
    "JSON lines)";

}  // namespace fetchscope
