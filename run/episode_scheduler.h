// One scheduler of episodes over workers, for every subcommand that runs episodes (record,
// rollout, random-episodes). Workers are processes by default: each makes its own GL context,
// environment, policy and encoders, because threads that share a process serialise in NVIDIA's
// GL driver (BENCHMARKS.md, "GPU node"). The parent owns progress, signals and the
// results; it hands out episodes in ascending order, one at a time, to whichever worker asks.
//
// Results never depend on which worker ran an episode: a runner brings its generators forward
// over the episodes other workers play (EpisodeSequence), so episode k is the episode k of a
// sequential run, and the parent orders results by episode index.
#pragma once

#include <sys/types.h>

#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "src/episode.h"
#include "src/episode_source.h"
#include "src/fetch_env.h"
#include "src/policy_spec.h"

namespace fetchscope {

/// What a runner tells the scheduler while it works. Thread-safe.
class WorkerChannel {
 public:
  virtual ~WorkerChannel() = default;
  /// `n` more frames (or steps) done, for the progress line.
  virtual void Progress(int n) = 0;
  /// Episode `episode` is finished; `result` goes to the parent. A runner may report an
  /// episode after Run() has returned (its encoding finishing in the background), and must
  /// have reported every episode it was given by the time Finish() returns.
  virtual void Done(int episode, nlohmann::json result) = 0;
  /// True once SIGINT/SIGTERM asked the run to stop: end the episode in progress early.
  virtual bool StopRequested() const = 0;
};

/// The per-subcommand work of one worker, made in the worker (its process or thread).
class EpisodeRunner {
 public:
  virtual ~EpisodeRunner() = default;
  /// Makes what the worker needs (GL context, renderer...). Returns what the manifest says
  /// of this worker (device, renderer), or null.
  virtual nlohmann::json Start() { return nullptr; }
  /// Plays episode `episode`; episodes come in ascending order. Reports it with
  /// channel.Done, now or later (see WorkerChannel::Done).
  virtual void Run(int episode, WorkerChannel& channel) = 0;
  /// Waits for work still in flight and reports it. Called once, after the last Run.
  virtual void Finish(WorkerChannel& channel) { (void)channel; }
};

/// Makes worker `worker`'s runner (0-based), inside that worker.
using RunnerFactory = std::function<std::unique_ptr<EpisodeRunner>(int worker)>;

/// How workers run.
enum class WorkerMode {
  kProcess,  ///< one process per worker (the default; --jobs 1 runs in this process)
  kThread,   ///< one thread per worker in this process (bench compares the two)
};

/// What to run and how.
struct ScheduleOptions {
  std::vector<int> episodes;               ///< ascending, no repeats
  int jobs = 1;                            ///< workers; capped at the number of episodes
  WorkerMode mode = WorkerMode::kProcess;  ///< for jobs > 1
  /// Called in the parent, on one thread at a time, as progress arrives (may be empty).
  std::function<void(int n)> on_progress;
  /// Called in the parent, on one thread at a time, as each episode's result arrives.
  std::function<void(int episode, const nlohmann::json& result)> on_done;
  /// What the result keeps of each episode's result once on_done has seen it (all of it when
  /// empty): a long run whose episodes went to an output keeps a summary, not every trajectory.
  std::function<nlohmann::json(const nlohmann::json& result)> keep;
};

/// A worker that failed: an exception in its runner, or a process that died.
struct WorkerFailure {
  int worker = 0;             ///< 0-based
  std::vector<int> episodes;  ///< the episodes it had in hand (lost)
  std::string message;        ///< one line, e.g. "worker 2 died of signal 9 (Killed)"
  bool usage = false;         ///< a UsageError (exit 2) rather than a run-time failure
};

/// The outcome of a run.
struct ScheduleResult {
  std::map<int, nlohmann::json> results;  ///< by episode index
  std::vector<nlohmann::json> workers;    ///< what each worker's Start() returned (null if none)
  std::vector<pid_t> pids;                ///< each worker's process (this process for threads)
  std::vector<WorkerFailure> failures;    ///< in the order they happened
  std::vector<int> missing;               ///< episodes asked for that have no result, ascending
  int signal = 0;                         ///< SIGINT or SIGTERM that stopped the run, or 0
  int jobs = 1;                           ///< workers actually used
};

/// Runs `options.episodes` over `options.jobs` workers made by `factory`. Installs the stop
/// signals (InstallStopSignals) for the duration: SIGINT/SIGTERM end every worker's episode in
/// progress (reported, shorter), then no new episode starts; the parent forwards the signal the
/// moment it arrives (base/process.h's WaitForInput). A worker process killed by SIGINT, SIGTERM
/// or SIGHUP stops the run the same way (result.signal), rather than failing it. After the first
/// failure no new episode starts either; episodes in progress elsewhere still finish. Worker
/// processes run in their own process group (a terminal's Ctrl-C reaches the parent, which forwards
/// it) and die with the parent (PR_SET_PDEATHSIG), so none is left behind.
ScheduleResult RunEpisodes(const ScheduleOptions& options, const RunnerFactory& factory);

/// The number of workers for --jobs `jobs` (0: one per usable core, UsableCores) and
/// `episodes` episodes.
int ResolveJobs(int jobs, int episodes);

/// A one-line account of the failures for an error message, e.g. "worker 1 (episode 3): ...".
std::string DescribeFailures(const ScheduleResult& result);

}  // namespace fetchscope
