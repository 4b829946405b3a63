// A whole record run, once cli/record.cc has parsed and resolved its options into a RecordJob:
// the node probe (GPUs, encoder), the run folder, the episodes on the scheduler
// (run/record_run.h), the manifest assembled from the workers' entries, the summary, and the
// Minari dataset written from the run folder. Nothing here parses a user's text.
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "run/episode_output.h"
#include "run/episode_scheduler.h"
#include "run/manifest.h"
#include "run/minari_output.h"
#include "run/node_probe.h"
#include "run/record_run.h"
#include "run/robomimic_output.h"
#include "run/shard.h"
#include "src/episode_source.h"

namespace fetchscope {

/// A record run, resolved: the workers' plan and what the parent does around it.
struct RecordJob {
  RecordPlan plan;                         ///< what the workers read
  Shard shard;                             ///< this run's shard (count 1: all)
  WorkerMode mode = WorkerMode::kProcess;  ///< --worker-mode
  std::string worker_mode;                 ///< --worker-mode as given (the manifest's)
  int jobs = 1;                            ///< workers
  std::vector<int> episodes;               ///< this run's episodes, ascending
  int episodes_requested = 1;              ///< --episodes (a replay: one past its last)
  std::string formats_text;                ///< --format as given
  std::string from_option;                 ///< --from as given ("" none)
  std::string replay_file;                 ///< a replay: policy's file ("" none)
  bool hud = false;                        ///< the HUD overlay is drawn
  bool quiet = false;                      ///< -q
  bool report = true;                      ///< write the run's index.html
  bool overwrite = false;                  ///< --overwrite
  bool resume = false;                     ///< --resume
  std::string command_line;                ///< as typed (the manifest's)
  std::string minari_root_given;  ///< --minari-root as given (empty: none), for the export advice
  std::optional<MinariRequest> minari;               ///< --minari: the dataset written after
  std::optional<RobomimicRequest> robomimic;         ///< --robomimic: the file written after
  bool keep_successful = false;                      ///< --keep successful
  std::string model_path;                            ///< the model file the env loaded
  std::chrono::steady_clock::time_point wall_start;  ///< when the command started
  /// Writes the run's report (inspect/, above this layer) for the manifest at this path.
  std::function<void(const std::string& manifest_path)> write_report;
  /// The view options as given: the manifest's words, and what SameRun compares.
  struct ViewText {
    std::string camera;   ///< --camera
    std::string overlay;  ///< --overlay
    std::string msaa;     ///< --msaa
    std::string gpu;      ///< --gpu ("" when not given)
  } view_text;
};

/// The run a record job's dataset describes (plan.spec, seed, seed_text, policy and steps,
/// episodes_requested).
OutputRun RecordOutputRun(const RecordJob& job);

/// Checks `job.minari` (set, with plan and overwrite) now, before the run, as CheckMinariOutput.
void CheckRecordMinari(const RecordJob& job);

/// Checks `job.robomimic` now, before the run, as CheckRobomimicOutput.
void CheckRecordRobomimic(const RecordJob& job);

/// Runs `job` after cli/record.cc resolved it: probes the node, opens the run folder, records,
/// writes the manifest, the summary, the report and the Minari dataset. Returns the exit status
/// (128 + signal when interrupted); throws UsageError/RunError as the run fails.
int RecordRun(RecordJob job);

/// What makes two record runs the same run (SameRun): what a resumed run must repeat for its
/// episodes to come out byte for byte as the run it continues (--jobs, --gpu and --backend are
/// free: outputs do not depend on them on one machine).
RunParameters RecordParameters(const RecordJob& job);

/// The workers' results summed for the manifest.
struct RecordTally {
  std::vector<ManifestEpisode> entries;       ///< the episodes, without what differs with --jobs
  ManifestTimings timings;                    ///< sim, render, encode, write: seconds summed
  std::map<int, std::vector<int>> by_worker;  ///< the episodes each worker recorded
  std::map<std::string, double> cpu_stages;   ///< thread CPU by stage (base/cpu_clock.h)
};
RecordTally TallyRecordResults(const std::map<int, EpisodeResult>& results);

/// The record run's manifest; `tally.entries` already with the kept episodes of a resumed run.
Manifest BuildRecordManifest(const RecordJob& job, const NodeProbe& node,
                             const ScheduleResult& result, RecordTally tally, double wall,
                             long frames, const RunParameters& parameters, bool resumed);

/// A dataset episode's divergence as the manifest's entry and the viewer hold it: first_step,
/// where, difference, max_difference, tolerance, position_error_mm {gripper, object}, and the
/// largest difference's place (non-finite numbers as null).
nlohmann::json DivergenceJson(const EpisodeDivergence& d);

/// A dataset source: each manifest entry gets "reset" and "divergence", the manifest a
/// "dataset" member (what was found, the tolerance). Nothing for a recording.
void AddDivergence(const TrajectorySource& source, std::vector<ManifestEpisode>* episodes,
                   nlohmann::json* manifest_extra);

}  // namespace fetchscope
