#include "base/cores.h"

#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>

namespace fetchscope {

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

}  // namespace fetchscope
