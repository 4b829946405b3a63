#include "base/kill_point.h"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>

#include "base/stop_signal.h"

namespace fetchscope {
namespace {

struct Hook {
  long target = -1;  // -1: no hook, 0: list the points, N: act at the Nth
  bool pause = false;
  std::string resume;  // pause: go on also once this file exists
};

const Hook& TheHook() {
  static const Hook hook = [] {
    Hook h;
    const char* at = std::getenv("FETCHSCOPE_TEST_KILL_AT");
    if (!at || !*at) return h;
    if (const char* cond = std::getenv("FETCHSCOPE_TEST_KILL_IF"); cond && *cond) {
      // NAME=VALUE[,NAME=VALUE...]: all must hold; NAME= holds where NAME is unset or empty
      const std::string all = cond;
      for (size_t at = 0; at <= all.size();) {
        size_t comma = all.find(',', at);
        if (comma == std::string::npos) comma = all.size();
        const std::string c = all.substr(at, comma - at);
        at = comma + 1;
        const size_t eq = c.find('=');
        if (eq == std::string::npos) return h;
        const char* value = std::getenv(c.substr(0, eq).c_str());
        if (c.substr(eq + 1) != (value ? value : "")) return h;
      }
    }
    const char* how = std::getenv("FETCHSCOPE_TEST_KILL_HOW");
    h.pause = how && std::strcmp(how, "pause") == 0;
    if (const char* resume = std::getenv("FETCHSCOPE_TEST_KILL_RESUME")) h.resume = resume;
    if (std::strcmp(at, "list") == 0) {
      h.target = 0;
      return h;
    }
    char* end = nullptr;
    const long n = std::strtol(at, &end, 10);
    if (*end == '\0' && n > 0) h.target = n;
    return h;
  }();
  return hook;
}

std::atomic<long> reached{0};

}  // namespace

void KillPoint(const char* what) {
  const Hook& hook = TheHook();
  if (hook.target < 0) return;
  const long n = reached.fetch_add(1) + 1;
  if (hook.target == 0) {
    std::fprintf(stderr, "fetchscope: kill point %ld: %s\n", n, what);
  } else if (n == hook.target && hook.pause) {
    std::fprintf(stderr, "fetchscope: paused at kill point %ld: %s\n", n, what);
    std::fflush(stderr);
    for (int i = 0; i < 2400 && StopSignal() == 0; ++i) {
      if (!hook.resume.empty() && ::access(hook.resume.c_str(), F_OK) == 0) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  } else if (n == hook.target) {
    ::kill(::getpid(), SIGKILL);
    ::pause();
  }
}

}  // namespace fetchscope
