#include "src/exec_policy.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <nlohmann/json.hpp>
#include <vector>

#include "base/errors.h"
#include "base/json_util.h"
#include "src/policy.h"

namespace fetchscope {
namespace {

std::string Shorten(const std::string& s) {
  std::string out = s.substr(0, 80);
  for (char& c : out) {
    if (static_cast<unsigned char>(c) < 32) c = '?';
  }
  return s.size() > 80 ? out + "..." : out;
}

extern "C" char** environ;

// The child's environment: ours, except that the bundle's launcher (tools/bundle.sh) put the
// bundle's libraries first on LD_LIBRARY_PATH and kept the caller's value in
// FETCHSCOPE_CALLER_LD_LIBRARY_PATH ("__unset__" when there was none): the child gets the
// caller's back, so that e.g. a Python policy loads its own libraries, not ours.
std::vector<std::string> ChildEnvironment() {
  const char* caller = std::getenv("FETCHSCOPE_CALLER_LD_LIBRARY_PATH");
  std::vector<std::string> env;
  for (char** e = environ; e && *e; ++e) {
    const std::string entry = *e;
    if (caller && (entry.rfind("LD_LIBRARY_PATH=", 0) == 0 ||
                   entry.rfind("FETCHSCOPE_CALLER_LD_LIBRARY_PATH=", 0) == 0)) {
      continue;
    }
    env.push_back(entry);
  }
  if (caller && std::string(caller) != "__unset__")
    env.push_back("LD_LIBRARY_PATH=" + std::string(caller));
  return env;
}

class ExecPolicy : public Policy {
 public:
  // The child runs in its own process group, so a terminal's Ctrl-C (sent to fetchscope's
  // foreground group) reaches fetchscope, which stops the run, and not the child; and it dies
  // with the thread that made it (PR_SET_PDEATHSIG: the creating thread, which owns this policy
  // and lives as long as it), so no child outlives its worker.
  ExecPolicy(std::string command, double timeout_s, std::function<bool()> stop_requested)
      : command_(std::move(command)),
        timeout_s_(timeout_s),
        stop_requested_(std::move(stop_requested)) {
    int to_child[2], from_child[2];
    if (pipe2(to_child, O_CLOEXEC) != 0 || pipe2(from_child, O_CLOEXEC) != 0) {
      throw RunError("exec policy: cannot create pipes: " + std::string(std::strerror(errno)));
    }
    signal(SIGPIPE, SIG_IGN);  // a child that exits early must not kill us: we see EPIPE
    // everything the child needs is made before fork: only async-signal-safe calls after it
    const std::vector<std::string> env = ChildEnvironment();
    std::vector<char*> envp;
    for (const std::string& e : env) envp.push_back(const_cast<char*>(e.c_str()));
    envp.push_back(nullptr);
    const char* argv[] = {"sh", "-c", command_.c_str(), nullptr};
    const pid_t parent = getpid();
    pid_ = fork();
    if (pid_ < 0) throw RunError("exec policy: fork failed: " + std::string(std::strerror(errno)));
    if (pid_ == 0) {
      setpgid(0, 0);
      prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (getppid() != parent) _exit(127);  // the parent went before prctl
      // a stop signal fetchscope ignores or handles must not be inherited as ignored
      signal(SIGINT, SIG_DFL);
      signal(SIGTERM, SIG_DFL);
      signal(SIGPIPE, SIG_DFL);
      dup2(to_child[0], STDIN_FILENO);
      dup2(from_child[1], STDOUT_FILENO);
      execve("/bin/sh", const_cast<char* const*>(argv), envp.data());
      _exit(127);
    }
    setpgid(pid_, pid_);  // also from this side, so that the group exists when we return
    close(to_child[0]);
    close(from_child[1]);
    in_ = to_child[1];
    out_ = from_child[0];
  }

  ~ExecPolicy() override {
    if (in_ >= 0) close(in_);
    if (out_ >= 0) close(out_);
    if (pid_ > 0) {
      // give the child a moment to exit on EOF, then make sure it is gone
      for (int i = 0; i < 20; ++i) {
        if (waitpid(pid_, nullptr, WNOHANG) == pid_) return;
        usleep(10000);
      }
      kill(-pid_, SIGKILL);  // the child's group: a shell's own children go too
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }

  Action Act(const Observation& obs, int t) override {
    nlohmann::json msg;
    msg["t"] = t;
    msg["observation"] = JsonVector(obs.observation.data(), obs.observation.size());
    msg["achieved_goal"] = JsonVector(obs.achieved_goal.data(), 3);
    msg["desired_goal"] = JsonVector(obs.desired_goal.data(), 3);
    const std::string line = msg.dump() + "\n";
    size_t done = 0;
    while (done < line.size()) {
      ssize_t n = write(in_, line.data() + done, line.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) throw RunError(Died(t));
      done += static_cast<size_t>(n);
    }
    const std::string answer = ReadLine(t);
    try {
      Action a;
      a.value = ParseActionLine(answer);
      return a;
    } catch (const RunError& e) {
      // the usual cause: a print() or a library's log line on stdout, which is the protocol's
      throw RunError("exec policy '" + command_ + "' at step " + std::to_string(t) + ": " +
                     e.what() +
                     "; its stdout must carry only the action lines: send logs and "
                     "prints to stderr (Python: print(..., file=sys.stderr))");
    }
  }
  std::string name() const override { return "exec:" + command_; }

 private:
  // The child closed its output: it exited or died. While the run is being stopped that is an
  // interruption (PolicyInterrupted), whatever the child died of; otherwise a failure.
  std::string Died(int t) {
    int status = 0;
    std::string how = "closed its output";
    for (int i = 0; i < 50; ++i) {
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        how = WIFEXITED(status) ? "exited with status " + std::to_string(WEXITSTATUS(status))
                                : "was killed by signal " + std::to_string(WTERMSIG(status));
        break;
      }
      usleep(10000);
    }
    if (stop_requested_ && stop_requested_()) {
      throw PolicyInterrupted("exec policy '" + command_ + "' " + how + " at step " +
                              std::to_string(t) + " while the run was being stopped");
    }
    return "exec policy '" + command_ + "' " + how + " before answering step " + std::to_string(t) +
           ": it must read one JSON line per step on stdin and print one action line (4 numbers)";
  }

  std::string ReadLine(int t) {
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s_);
    while (true) {
      size_t nl = buffer_.find('\n');
      if (nl != std::string::npos) {
        std::string line = buffer_.substr(0, nl);
        buffer_.erase(0, nl + 1);
        if (!line.empty() && line.back() == '\r') line.pop_back();
        return line;
      }
      if (buffer_.size() > (1 << 16)) {
        throw RunError("exec policy '" + command_ + "' at step " + std::to_string(t) +
                       ": answer longer than 64 KiB without a newline");
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                            deadline - std::chrono::steady_clock::now())
                            .count();
      if (left <= 0) {
        throw RunError("exec policy '" + command_ + "' gave no answer for step " +
                       std::to_string(t) + " within " + JsonDouble(timeout_s_).dump() +
                       " s (raise --exec-timeout)");
      }
      pollfd p{out_, POLLIN, 0};
      int r = poll(&p, 1, static_cast<int>(std::min<long long>(left, 1000)));
      if (r < 0 && errno == EINTR) continue;
      if (r <= 0) continue;
      char buf[4096];
      ssize_t n = read(out_, buf, sizeof(buf));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) throw RunError(Died(t));
      buffer_.append(buf, static_cast<size_t>(n));
    }
  }

  std::string command_;
  double timeout_s_;
  std::function<bool()> stop_requested_;
  pid_t pid_ = -1;
  int in_ = -1, out_ = -1;
  std::string buffer_;
};

}  // namespace

std::array<double, 4> ParseActionLine(const std::string& line) {
  std::string s = line;
  size_t first = s.find_first_not_of(" \t");
  if (first != std::string::npos && s[first] == '[') {
    nlohmann::json j = nlohmann::json::parse(s, nullptr, false);
    if (j.is_discarded() || !j.is_array()) {
      throw RunError("answer '" + Shorten(line) +
                     "' is not a valid JSON array: expected 4 numbers");
    }
    if (j.size() != 4) {
      throw RunError("answer '" + Shorten(line) + "' has " + std::to_string(j.size()) +
                     " values: expected 4 numbers");
    }
    std::array<double, 4> a;
    for (int i = 0; i < 4; ++i) {
      if (!j[i].is_number())
        throw RunError("answer '" + Shorten(line) + "': value " + std::to_string(i) +
                       " is not a number");
      a[i] = j[i].get<double>();
    }
    for (double v : a) {
      if (!std::isfinite(v))
        throw RunError("answer '" + Shorten(line) + "' holds a non-finite value");
    }
    return a;
  }
  for (char& c : s) {
    if (c == ',' || c == '\t') c = ' ';
  }
  std::array<double, 4> a{};
  const char* p = s.c_str();
  int count = 0;
  while (true) {
    while (*p == ' ') ++p;
    if (*p == '\0') break;
    char* end = nullptr;
    errno = 0;
    double v = std::strtod(p, &end);
    if (end == p || (*end != ' ' && *end != '\0')) {
      throw RunError("answer '" + Shorten(line) +
                     "' is not 4 numbers separated by spaces or commas (or a JSON array)");
    }
    if (!std::isfinite(v))
      throw RunError("answer '" + Shorten(line) + "' holds a non-finite value");
    if (count < 4) a[count] = v;
    ++count;
    p = end;
  }
  if (count != 4) {
    throw RunError("answer '" + Shorten(line) + "' has " + std::to_string(count) +
                   " numbers: expected 4 (dx dy dz gripper)");
  }
  return a;
}

std::unique_ptr<Policy> MakeExecPolicy(const std::string& command, double timeout_s,
                                       std::function<bool()> stop_requested) {
  return std::make_unique<ExecPolicy>(command, timeout_s, std::move(stop_requested));
}

}  // namespace fetchscope
