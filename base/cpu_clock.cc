#include "base/cpu_clock.h"

#include <sys/resource.h>
#include <time.h>

namespace fetchscope {
namespace {

double Seconds(const timeval& t) { return static_cast<double>(t.tv_sec) + t.tv_usec * 1e-6; }

}  // namespace

double ThreadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + t.tv_nsec * 1e-9;
}

double ProcessCpuSeconds() {
  double total = 0;
  for (int who : {RUSAGE_SELF, RUSAGE_CHILDREN}) {
    rusage u{};
    if (getrusage(who, &u) == 0) total += Seconds(u.ru_utime) + Seconds(u.ru_stime);
  }
  return total;
}

CpuStages& CpuStages::operator+=(const CpuStages& o) {
  sim += o.sim;
  scene += o.scene;
  gl += o.gl;
  hud += o.hud;
  copy += o.copy;
  render_other += o.render_other;
  look += o.look;
  convert += o.convert;
  encode += o.encode;
  sheet += o.sheet;
  trajectory += o.trajectory;
  encode_other += o.encode_other;
  return *this;
}

double CpuStages::OutsideGl() const {
  return sim + scene + hud + copy + render_other + look + convert + encode + sheet + trajectory +
         encode_other;
}

std::map<std::string, double> CpuStages::Items() const {
  return {{"sim", sim},
          {"scene", scene},
          {"gl", gl},
          {"hud", hud},
          {"copy", copy},
          {"render_other", render_other},
          {"look", look},
          {"convert", convert},
          {"encode", encode},
          {"sheet", sheet},
          {"trajectory", trajectory},
          {"encode_other", encode_other}};
}

}  // namespace fetchscope
