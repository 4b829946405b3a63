#include "base/stop_signal.h"

#include <fcntl.h>
#include <pthread.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>

namespace fetchscope {

namespace {
std::atomic<int> g_stop_signal{0};
// The self-pipe: the handler writes a byte, so a poll in any thread wakes. It belongs to the
// process that made it: a forked child that inherits it must not write into its parent's.
std::atomic<int> g_pipe_read{-1};
std::atomic<int> g_pipe_write{-1};
std::atomic<pid_t> g_pipe_owner{-1};

void OnStopSignal(int sig) {
  const int saved = errno;  // a handler must leave errno as it found it
  g_stop_signal.store(sig);
  const int fd = g_pipe_write.load();
  if (fd >= 0 && g_pipe_owner.load() == getpid()) {
    const char byte = 1;
    (void)!write(fd, &byte, 1);  // full (EAGAIN): it is readable already
  }
  errno = saved;
}

// Makes this process's self-pipe, or empties it when this process already has one.
void PrepareSelfPipe() {
  if (g_pipe_owner.load() == getpid()) {
    char buffer[64];
    while (read(g_pipe_read.load(), buffer, sizeof(buffer)) > 0) {
    }
    return;
  }
  // the parent's pipe, inherited through fork, stays open here (closing it would not free the
  // parent's, and another thread of the parent's copy may not run here anyway)
  int fds[2];
  if (pipe2(fds, O_CLOEXEC | O_NONBLOCK) != 0) return;  // no self-pipe: the flag still works
  g_pipe_owner.store(-1);
  g_pipe_read.store(fds[0]);
  g_pipe_write.store(fds[1]);
  g_pipe_owner.store(getpid());
}
}  // namespace

void InstallStopSignals() {
  g_stop_signal.store(0);
  PrepareSelfPipe();
  struct sigaction sa {};
  sa.sa_handler = OnStopSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

int StopSignal() { return g_stop_signal.load(); }

int StopSignalFd() { return g_pipe_owner.load() == getpid() ? g_pipe_read.load() : -1; }

sigset_t StopSignalSet() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  return set;
}

StopSignalBlock::StopSignalBlock() {
  const sigset_t stop = StopSignalSet();
  pthread_sigmask(SIG_BLOCK, &stop, &old_);
  wait_ = old_;
  sigdelset(&wait_, SIGINT);
  sigdelset(&wait_, SIGTERM);
}

StopSignalBlock::~StopSignalBlock() { pthread_sigmask(SIG_SETMASK, &old_, nullptr); }

}  // namespace fetchscope
