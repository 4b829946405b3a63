// The cores this process may use: what --jobs 0, the encoder budget and bench --what node count.
#pragma once

#include <string>

namespace fetchscope {

/// The cores this process may use, and why that many.
struct Cores {
  int usable = 1;      ///< what --jobs 0 and the encoder budget count
  int online = 1;      ///< the machine's online CPUs
  std::string source;  ///< "online", "affinity" (taskset, Slurm, cpusets) or "cgroup quota"
};

/// The cores this process may use: the CPUs in its affinity mask (Slurm's and Kubernetes'
/// cpusets, taskset), capped by a cgroup CPU quota (cgroup v2 cpu.max, v1 cfs_quota_us) rounded
/// up, as containers with CPU limits have. Never below 1.
Cores UsableCores();

/// The cgroup CPU quota in cores (quota / period; the smallest along the cgroup's ancestors), or
/// 0 when there is none: `proc_self_cgroup` is /proc/self/cgroup, `cgroup_root` /sys/fs/cgroup.
double CgroupCpuQuota(const std::string& proc_self_cgroup, const std::string& cgroup_root);

}  // namespace fetchscope
