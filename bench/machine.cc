// The machine description that goes with every benchmark figure.
#include <sys/utsname.h>
#include <unistd.h>

#include <fstream>
#include <string>

#include "base/cores.h"
#include "bench/bench.h"

namespace fetchscope::bench {

nlohmann::json MachineJson() {
  std::string cpu = "unknown";
  std::ifstream cpuinfo("/proc/cpuinfo");
  for (std::string line; std::getline(cpuinfo, line);) {
    if (line.rfind("model name", 0) == 0) {
      cpu = line.substr(line.find(':') + 2);
      break;
    }
  }
  utsname u{};
  uname(&u);
  const double mem_gib =
      sysconf(_SC_PHYS_PAGES) * static_cast<double>(sysconf(_SC_PAGE_SIZE)) / (1 << 30);
  std::string os = "unknown";
  std::ifstream release("/etc/os-release");
  for (std::string line; std::getline(release, line);) {
    if (line.rfind("PRETTY_NAME=", 0) == 0) os = line.substr(13, line.size() - 14);
  }
  return {{"cpu", cpu},
          {"cores", sysconf(_SC_NPROCESSORS_ONLN)},
          {"usable_cores", UsableCores().usable},
          {"memory_gib", mem_gib},
          {"os", os},
          {"kernel", u.release}};
}

}  // namespace fetchscope::bench
