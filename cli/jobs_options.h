// --jobs and --worker-mode, the options of every subcommand that runs episodes on the episode
// scheduler (run/episode_scheduler.h).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "run/episode_scheduler.h"

namespace fetchscope::cli {

/// Adds --jobs and --worker-mode to `sub` (ResolveJobs and ParseWorkerMode read them).
void AddJobsOptions(CLI::App* sub, int* jobs, std::string* mode);

/// Parses --worker-mode: process or thread. Throws UsageError.
WorkerMode ParseWorkerMode(const std::string& text);

}  // namespace fetchscope::cli
