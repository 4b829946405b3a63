// --jobs and --worker-mode, the options of every subcommand that runs episodes on the episode
// scheduler (run/episode_scheduler.h).
#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace fetchscope::cli {

/// Adds --jobs and --worker-mode to `sub` (ResolveJobs and ParseWorkerMode read them).
void AddJobsOptions(CLI::App* sub, int* jobs, std::string* mode);

}  // namespace fetchscope::cli
