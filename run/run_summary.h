// What record says about a run when it ends, by one rule that the report (inspect/report.h)
// follows too: the success rate counts the complete episodes only; episodes cut short (by a
// signal, or already so in a recording that --from replays) are counted apart and left out of
// it. The counts are of the whole run in the folder: after --resume, the episodes kept too.
#pragma once

#include <string>
#include <vector>

#include "run/manifest.h"

namespace fetchscope {

/// A run's episodes, counted by the one rule.
struct EpisodeCounts {
  int complete = 0;    ///< episodes with all their steps (older manifests: no flag, complete)
  int successes = 0;   ///< complete episodes that succeeded at their last step
  int incomplete = 0;  ///< episodes cut short: never in the rate
};

/// Counts `episodes` by the one rule.
EpisodeCounts CountEpisodes(const std::vector<ManifestEpisode>& episodes);

/// The command that continues an interrupted run: `command_line` without --overwrite, with
/// --resume (once).
std::string ResumeCommand(const std::string& command_line);

/// record's summary of the run `m` it has just written to `out`, of which this process recorded
/// `recorded` episodes and kept `kept` (--resume): "record: 3 episode(s), ... success 2/3 complete,
/// 1 incomplete (not in the rate), ... -> out", and when interrupted a second line naming the
/// --resume command.
std::string RecordSummaryText(const Manifest& m, size_t recorded, size_t kept,
                              const std::string& out);

/// --resume of a run already whole: "record: --out 'X' already holds the whole run (N
/// episode(s)): nothing to record; success S/C complete".
std::string AlreadyCompleteText(const std::string& out, const std::vector<ManifestEpisode>& kept);

}  // namespace fetchscope
