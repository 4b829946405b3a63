#include "cli/common.h"

#include <mujoco/mujoco.h>
#include <sched.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "src/atomic_file.h"
#include "src/errors.h"
#include "src/json_util.h"
#include "src/policy.h"

namespace fetchscope::cli {

void AddEnvOptions(CLI::App* sub, EnvOptions* options, bool with_seed) {
  sub->add_option("--env-id", options->env_id,
                  "FetchReach-v4, FetchReachDense-v4, FetchPush[Dense]-v4, "
                  "FetchPickAndPlace[Dense]-v4, FetchSlide[Dense]-v4, or auto (FetchReachDense-v4)")
      ->capture_default_str();
  sub->add_option("--assets", options->assets,
                  "bundled (our models/), auto ($FETCHSCOPE_ASSETS, else an installed "
                  "gymnasium_robotics, else bundled), or a Gymnasium-Robotics envs/assets folder")
      ->capture_default_str();
  if (with_seed) {
    sub->add_option("--seed", options->seed,
                    "env.reset(seed=S) for the first episode (later episodes continue the "
                    "generator) and action_space.seed(S) for the random policy")
        ->capture_default_str();
  }
}

uint64_t ParseSeed(const std::string& text) {
  const std::string accepted =
      ": a seed is a non-negative integer below 2^64, as Gymnasium accepts";
  if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos) {
    throw UsageError("--seed '" + text + "' is not valid" + accepted);
  }
  errno = 0;
  char* end = nullptr;
  unsigned long long v = std::strtoull(text.c_str(), &end, 10);
  if (errno == ERANGE || *end != '\0')
    throw UsageError("--seed '" + text + "' is too large" + accepted);
  return v;
}

std::string JsonOutPath(const std::string& prefix, const std::string& suffix) {
  if (prefix.empty()) return "";
  if (prefix.size() >= 5 && prefix.compare(prefix.size() - 5, 5, ".json") == 0) return prefix;
  return prefix + "_" + suffix + ".json";
}

void WriteJson(const std::string& path, const nlohmann::json& json) {
  WriteFileAtomically(path, DumpJson(json) + "\n");
}

double CgroupCpuQuota(const std::string& proc_self_cgroup, const std::string& cgroup_root) {
  double best = 0;
  auto consider = [&](double quota, double period) {
    if (quota > 0 && period > 0 && (best == 0 || quota / period < best)) best = quota / period;
  };
  std::string v2_path;
  std::ifstream cgroups(proc_self_cgroup);
  for (std::string line; std::getline(cgroups, line);) {
    if (line.rfind("0::", 0) == 0) v2_path = line.substr(3);
  }
  if (!v2_path.empty()) {
    // this cgroup and each ancestor: a limit anywhere above applies too
    for (std::string dir = v2_path;; dir = dir.substr(0, dir.rfind('/'))) {
      if (dir == "/") dir.clear();
      std::ifstream max(cgroup_root + dir + "/cpu.max");
      std::string quota;
      double period = 0;
      if (max >> quota >> period && quota != "max") consider(std::atof(quota.c_str()), period);
      if (dir.empty()) break;
    }
  }
  std::ifstream v1_quota(cgroup_root + "/cpu/cpu.cfs_quota_us");
  std::ifstream v1_period(cgroup_root + "/cpu/cpu.cfs_period_us");
  double quota = 0, period = 0;
  if (v1_quota >> quota >> std::ws && v1_period >> period) consider(quota, period);
  return best;
}

Cores UsableCores() {
  Cores cores;
  cores.online = static_cast<int>(std::max(1L, sysconf(_SC_NPROCESSORS_ONLN)));
  cores.usable = cores.online;
  cores.source = "online";
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0 && CPU_COUNT(&set) > 0 &&
      CPU_COUNT(&set) < cores.usable) {
    cores.usable = CPU_COUNT(&set);
    cores.source = "affinity";
  }
  const double quota = CgroupCpuQuota("/proc/self/cgroup", "/sys/fs/cgroup");
  if (quota > 0 && static_cast<int>(std::ceil(quota)) < cores.usable) {
    cores.usable = std::max(1, static_cast<int>(std::ceil(quota)));
    cores.source = "cgroup quota";
  }
  return cores;
}

std::optional<std::vector<int>> ReplayedEpisodes(const std::string& policy, int episodes,
                                                 const std::string& env_id, uint64_t seed,
                                                 bool quiet) {
  std::string file_env, file_seed;
  std::optional<std::vector<int>> indices = ReplayTrajectoryEpisodes(policy, &file_env, &file_seed);
  if (!indices) return std::nullopt;
  if (episodes > 0 && episodes != static_cast<int>(indices->size())) {
    throw UsageError("--episodes " + std::to_string(episodes) + " disagrees with " + policy +
                     ", which holds " + std::to_string(indices->size()) +
                     " episode(s): a trajectory JSON replays all its episodes; drop --episodes");
  }
  if (!quiet && (file_env != env_id || file_seed != std::to_string(seed))) {
    std::fprintf(stderr,
                 "fetchscope: warning: %s was recorded on %s with --seed %s, this run is %s with "
                 "--seed %llu: the resets differ, so the recorded trajectory is not reproduced\n",
                 policy.c_str() + 7, file_env.c_str(), file_seed.c_str(), env_id.c_str(),
                 static_cast<unsigned long long>(seed));
  }
  return indices;
}

nlohmann::json VersionsJson() {
  return {{"fetchscope", FETCHSCOPE_VERSION}, {"mujoco", mj_versionString()}};
}

std::string& CommandLine() {
  static std::string line;
  return line;
}

namespace {
std::atomic<int> g_stop_signal{0};
void OnStopSignal(int sig) { g_stop_signal.store(sig); }
}  // namespace

void InstallStopSignals() {
  g_stop_signal.store(0);
  struct sigaction sa {};
  sa.sa_handler = OnStopSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

int StopSignal() { return g_stop_signal.load(); }

int& ExitStatus() {
  static int status = 0;
  return status;
}

}  // namespace fetchscope::cli
