#include "src/exec_policy.h"

#include <fcntl.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "base/errors.h"
#include "base/json_util.h"
#include "base/process.h"
#include "src/exec_wire.h"
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
  // and lives as long as it), so no child outlives its worker. The command is the user's shell
  // text, so it runs under /bin/sh.
  ExecPolicy(const policy_spec::Exec& exec, std::function<bool()> stop_requested,
             std::function<const WireStep*(int)> images)
      : command_(exec.command),
        timeout_s_(exec.timeout_s),
        fields_(exec.fields),
        stop_requested_(std::move(stop_requested)),
        images_(std::move(images)) {
    SpawnOptions options;
    options.in = Stdio::kPipe;  // Spawn ignores SIGPIPE: a child that exits early is an EPIPE
    options.out = Stdio::kPipe;
    options.program = "/bin/sh";
    options.env = ChildEnvironment();
    try {
      child_ = ChildProcess::Spawn({"sh", "-c", command_}, options);
    } catch (const RunError& e) {
      throw RunError(std::string("exec policy: ") + e.what());
    }
    if (images_) {
      // images are written in pieces as the child reads them, never blocking past the timeout
      // or a stop; a larger pipe (1 MiB, the unprivileged limit) takes a step's images in
      // fewer turns between the two processes
      const int fd = child_.channel().out_fd();
      fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
      fcntl(fd, F_SETPIPE_SZ, 1 << 20);
    }
  }

  ~ExecPolicy() override { End(); }

  void BeginEpisode(int, const Observation&) override { legend_sent_ = false; }

  Action Act(const Observation& obs, int t) override {
    const WireStep* step = images_ ? images_(t) : nullptr;
    if (step && step->t != t) {
      throw RunError("exec policy: the images are of step " + std::to_string(step->t) +
                     ", not of step " + std::to_string(t) + " (a bug in fetchscope)");
    }
    const std::string line = ExecMessage(obs, t, fields_, step, !legend_sent_).dump();
    if (images_) {
      legend_sent_ = true;
      SendWithImages(line + "\n", step, t);
    } else if (!child_.channel().WriteLine(line)) {
      throw RunError(Died(t, /*writing=*/true));
    }
    const std::string answer = ReadLine(t);
    if (step) CheckAllRead(*step, t);
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
  // The one message for a child that closed its stdin and kept running, whichever way fetchscope
  // saw it: the write of step t's line failed (EPIPE), or the pipe reported that its reader had
  // gone (POLLERR) while fetchscope waited for the answer.
  std::string InputClosed(int t) const {
    return "exec policy '" + command_ + "' closed its input (stdin) and kept running without " +
           "answering step " + std::to_string(t) +
           ": it must keep reading one JSON line per step until fetchscope closes it";
  }

  // The child closed its output: it exited or died. While the run is being stopped that is an
  // interruption (PolicyInterrupted), whatever the child died of; otherwise a failure.
  // `writing`: its stdin is closed (the observation could not be written, or the pipe reported
  // that its reader had gone); a child still running half a second later closed its input.
  std::string Died(int t, bool writing = false) {
    std::string how = "closed its output";
    bool crashed = false;  // a failure of its own: its error (a traceback) is on stderr above
    if (const std::optional<ChildExit> status = child_.WaitFor(0.5)) {
      how = status->exited() ? "exited with status " + std::to_string(status->code)
                             : "was killed by signal " + std::to_string(status->signal);
      crashed = !status->exited() || status->code != 0;
    } else if (writing && !(stop_requested_ && stop_requested_())) {
      return InputClosed(t);
    }
    if (stop_requested_ && stop_requested_()) {
      throw PolicyInterrupted("exec policy '" + command_ + "' " + how + " at step " +
                              std::to_string(t) + " while the run was being stopped");
    }
    if (crashed) {
      return "exec policy '" + command_ + "' " + how + " before answering step " +
             std::to_string(t) + " (its own error, if it printed one, is on stderr above)";
    }
    return "exec policy '" + command_ + "' " + how + " before answering step " + std::to_string(t) +
           ": it must read one JSON line per step on stdin and print one action line (4 numbers)";
  }

  // Closes its input, gives it a moment to exit on that (and its shell to reap it), then makes
  // sure it is gone (the group: a shell's own children go too).
  void End() {
    child_.channel().Close();
    if (!child_.WaitFor(0.2)) child_.Kill();
  }

  // Why step t got no answer in time, as far as can be seen from here: an answer without its
  // newline, the child's input closed, or silence.
  std::string NoAnswer(int t) {
    LineChannel& channel = child_.channel();
    const std::string within = " within " + JsonDouble(timeout_s_).dump() + " s";
    const std::string who = "exec policy '" + command_ + "'";
    if (channel.buffered() > 0) {
      return who + " answered '" + Shorten(channel.pending()) + "' for step " + std::to_string(t) +
             " but no newline followed" + within +
             ": end each answer with a newline and flush it (Python: print(..., flush=True))";
    }
    return who + " gave no answer for step " + std::to_string(t) + within +
           " (raise --exec-timeout)";
  }

  std::string ReadLine(int t) {
    LineChannel& channel = child_.channel();
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s_);
    while (true) {
      if (std::optional<std::string> line = channel.TakeLine()) return *line;
      if (channel.buffered() > (1 << 16)) {
        throw RunError("exec policy '" + command_ + "' at step " + std::to_string(t) +
                       ": answer longer than 64 KiB without a newline");
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                            deadline - std::chrono::steady_clock::now())
                            .count();
      if (left <= 0) throw RunError(NoAnswer(t));
      // the answer's wait ends at once on SIGINT/SIGTERM: the child is ended (its group) and the
      // episode ends at the step it reached, an interruption
      // the child's stdin is watched too: the write end of a pipe whose reader has gone reports
      // POLLERR at once, so a child that closed its input is named as such when it does so, not
      // when the timeout passes (whichever came first, the write or the close, the same message)
      std::vector<pollfd> fds = {{channel.in_fd(), POLLIN, 0}, {channel.out_fd(), 0, 0}};
      const int wait_ms = static_cast<int>(std::min<long long>(left, 1000));
      const WaitEnd end = WaitForInput(&fds, wait_ms, /*watch_stop=*/true);
      if (end == WaitEnd::kStop || (stop_requested_ && stop_requested_())) {
        End();
        throw PolicyInterrupted("exec policy '" + command_ + "' was ended while it answered step " +
                                std::to_string(t) + ": the run was being stopped");
      }
      if (end != WaitEnd::kReady) continue;
      if (fds[0].revents == 0) throw RunError(Died(t, /*writing=*/true));  // only its stdin closed
      if (!channel.ReadSome()) throw RunError(Died(t));
    }
  }

  // The bytes of step t's images in all.
  static size_t ImageBytes(const WireStep* step) {
    size_t total = 0;
    if (step) {
      for (const WireImage& im : step->images) total += im.bytes;
    }
    return total;
  }

  std::string EarlyAnswer(const WireStep* step, int t, size_t unread) const {
    return "exec policy '" + command_ + "' answered step " + std::to_string(t) +
           " before reading its images (" + std::to_string(unread) + " of their " +
           std::to_string(ImageBytes(step)) +
           " bytes unread): read the line, then each image's `bytes` "
           "(Python: sys.stdin.buffer.read(n)), then answer";
  }

  // Writes the line and then each image of `step`, as the child reads them: an answer (or the
  // child's end) before the last byte is written is an error, as is a child that reads nothing
  // for --exec-timeout; a stop ends the child and the episode.
  void SendWithImages(const std::string& line, const WireStep* step, int t) {
    std::vector<std::pair<const char*, size_t>> pieces = {{line.data(), line.size()}};
    if (step) {
      for (const WireImage& im : step->images)
        pieces.emplace_back(static_cast<const char*>(im.data), im.bytes);
    }
    size_t left = ImageBytes(step) + line.size();
    LineChannel& channel = child_.channel();
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s_);
    for (auto [p, n] : pieces) {
      while (n > 0) {
        const ssize_t w = write(channel.out_fd(), p, n);
        if (w > 0) {
          p += w;
          n -= static_cast<size_t>(w);
          left -= static_cast<size_t>(w);
          continue;
        }
        if (w < 0 && errno == EINTR) continue;
        if (w < 0 && errno != EAGAIN) throw RunError(Died(t, /*writing=*/true));
        const auto wait = std::chrono::duration_cast<std::chrono::milliseconds>(
                              deadline - std::chrono::steady_clock::now())
                              .count();
        if (wait <= 0) {
          throw RunError("exec policy '" + command_ + "' left " + std::to_string(left) +
                         " bytes of step " + std::to_string(t) + "'s input unread for " +
                         JsonDouble(timeout_s_).dump() +
                         " s: it must read the line and each image's `bytes` every step "
                         "(raise --exec-timeout for a slow reader)");
        }
        std::vector<pollfd> fds = {{channel.in_fd(), POLLIN, 0}, {channel.out_fd(), POLLOUT, 0}};
        const WaitEnd end =
            WaitForInput(&fds, static_cast<int>(std::min<long long>(wait, 1000)), true);
        if (end == WaitEnd::kStop || (stop_requested_ && stop_requested_())) {
          End();
          throw PolicyInterrupted("exec policy '" + command_ + "' was ended while it read step " +
                                  std::to_string(t) + ": the run was being stopped");
        }
        if (end != WaitEnd::kReady) continue;
        if (fds[0].revents != 0) {
          if (!channel.ReadSome()) throw RunError(Died(t));
          throw RunError(EarlyAnswer(step, t, left));
        }
        if (fds[1].revents & (POLLERR | POLLHUP)) throw RunError(Died(t, /*writing=*/true));
      }
    }
  }

  // After step t's answer: the child must have read every byte it was sent (a pipe's FIONREAD
  // counts what is still unread, whichever end asks).
  void CheckAllRead(const WireStep& step, int t) {
    int unread = 0;
    if (ioctl(child_.channel().out_fd(), FIONREAD, &unread) == 0 && unread > 0) {
      throw RunError(EarlyAnswer(&step, t, static_cast<size_t>(unread)));
    }
  }

  std::string command_;
  double timeout_s_;
  std::vector<std::string> fields_;
  std::function<bool()> stop_requested_;
  std::function<const WireStep*(int)> images_;
  bool legend_sent_ = false;  // the segmentation legend went with this episode's first line
  ChildProcess child_;
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

std::unique_ptr<Policy> MakeExecPolicy(const policy_spec::Exec& exec,
                                       std::function<bool()> stop_requested,
                                       std::function<const WireStep*(int)> images) {
  return std::make_unique<ExecPolicy>(exec, std::move(stop_requested), std::move(images));
}

}  // namespace fetchscope
