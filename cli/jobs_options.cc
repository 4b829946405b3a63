#include "cli/jobs_options.h"

#include "base/errors.h"

namespace fetchscope::cli {

void AddJobsOptions(CLI::App* sub, int* jobs, std::string* mode) {
  sub->add_option("-j,--jobs", *jobs,
                  "Worker processes, each with its own environment, policy, GL context and "
                  "encoders (0: one per usable core, affinity mask and cgroup quota counted); "
                  "outputs are byte-identical to --jobs 1")
      ->capture_default_str()
      ->check(CLI::Range(0, 1024));
  sub->add_option("--worker-mode", *mode,
                  "process (default) or thread: threads share one process and so one GL driver, "
                  "which serialises them on NVIDIA; kept for comparison (bench --what node)")
      ->capture_default_str()
      ->check(CLI::IsMember({"process", "thread"}));
}

WorkerMode ParseWorkerMode(const std::string& text) {
  if (text == "process") return WorkerMode::kProcess;
  if (text == "thread") return WorkerMode::kThread;
  throw UsageError("--worker-mode '" + text + "' is not known; accepted: process, thread");
}

}  // namespace fetchscope::cli
