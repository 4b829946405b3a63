#include "base/process.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <thread>

#include "base/errors.h"
#include "base/json_util.h"
#include "base/stop_signal.h"

extern "C" char** environ;

namespace fetchscope {
namespace {

std::string Errno(const std::string& what) { return what + ": " + std::strerror(errno); }

// In a new child, before anything else: its own process group, so that a terminal's Ctrl-C
// (sent to fetchscope's foreground group) reaches the parent only; death with the parent's
// thread, checking the parent is still there (it may have gone before prctl).
bool DetachAndTie(pid_t parent) {
  setpgid(0, 0);
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  return getppid() == parent;
}

// A child must not inherit the parent's blocked stop signals (a thread inside WaitForInput).
void UnblockSignals() {
  sigset_t none;
  sigemptyset(&none);
  sigprocmask(SIG_SETMASK, &none, nullptr);
}

// Makes `fd` the child's descriptor `target` (async-signal-safe).
void MoveTo(int fd, int target) {
  if (fd < 0) return;
  if (fd == target) {
    fcntl(fd, F_SETFD, 0);  // keep it across exec
  } else {
    dup2(fd, target);
  }
}

UniqueFd DupCloexec(int fd) { return UniqueFd(fcntl(fd, F_DUPFD_CLOEXEC, 0)); }

}  // namespace

UniqueFd& UniqueFd::operator=(UniqueFd&& other) noexcept {
  if (this != &other) Reset(other.Release());
  return *this;
}

int UniqueFd::Release() {
  const int fd = fd_;
  fd_ = -1;
  return fd;
}

void UniqueFd::Reset(int fd) {
  if (fd_ >= 0) close(fd_);
  fd_ = fd;
}

// ---- exit statuses ----

ChildExit ChildExit::FromWait(int status) {
  ChildExit s;
  if (WIFSIGNALED(status)) {
    s.signal = WTERMSIG(status);
  } else {
    s.code = WEXITSTATUS(status);
  }
  return s;
}

bool ChildExit::interrupted() const {
  return signal == SIGINT || signal == SIGTERM || signal == SIGHUP;
}

std::string ChildExit::Describe() const {
  return signal ? "died of " + SignalName(signal) : "exited with status " + std::to_string(code);
}

std::string SignalName(int sig) {
  const char* abbrev = sigabbrev_np(sig);
  const char* description = sigdescr_np(sig);
  std::string text = "signal " + std::to_string(sig);
  if (abbrev) {
    text +=
        std::string(" (SIG") + abbrev + (description ? std::string(": ") + description : "") + ")";
  }
  return text;
}

std::string ShellQuote(const std::string& arg) {
  bool plain = !arg.empty();
  for (char c : arg) {
    plain = plain && (std::isalnum(static_cast<unsigned char>(c)) ||
                      (c != '\0' && std::strchr("@%+=:,./_-", c)));
  }
  if (plain) return arg;
  std::string quoted = "'";
  for (char c : arg) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

std::optional<std::vector<std::string>> SplitShellWords(const std::string& line) {
  std::vector<std::string> words;
  std::string word;
  bool in_word = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (c == ' ' || c == '\t' || c == '\n') {
      if (in_word) words.push_back(std::move(word));
      word.clear();
      in_word = false;
    } else if (c == '\'') {
      const size_t end = line.find('\'', i + 1);
      if (end == std::string::npos) return std::nullopt;
      word += line.substr(i + 1, end - i - 1);
      i = end;
      in_word = true;
    } else if (c == '"') {
      size_t j = i + 1;
      for (; j < line.size() && line[j] != '"'; ++j) {
        // inside double quotes a backslash escapes only $ ` " \ and a newline
        if (line[j] == '\\' && j + 1 < line.size() && std::strchr("$`\"\\\n", line[j + 1])) ++j;
        word += line[j];
      }
      if (j >= line.size()) return std::nullopt;
      i = j;
      in_word = true;
    } else if (c == '\\') {
      if (i + 1 < line.size()) word += line[++i];
      in_word = true;
    } else {
      word += c;
      in_word = true;
    }
  }
  if (in_word) words.push_back(std::move(word));
  return words;
}

// ---- line channels ----

bool LineChannel::WriteLine(const std::string& line) {
  const std::string text = line + "\n";
  size_t done = 0;
  bool socket = true;
  while (done < text.size()) {
    // MSG_NOSIGNAL: a peer that has gone is an EPIPE, not a SIGPIPE
    ssize_t n = socket ? send(out_.get(), text.data() + done, text.size() - done, MSG_NOSIGNAL)
                       : write(out_.get(), text.data() + done, text.size() - done);
    if (n < 0 && errno == ENOTSOCK && socket) {
      socket = false;
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<size_t>(n);
  }
  return true;
}

bool LineChannel::Send(const nlohmann::json& message) { return WriteLine(DumpJson(message, -1)); }

bool LineChannel::ReadSome() {
  char buffer[65536];
  while (true) {
    const ssize_t n = read(in_.get(), buffer, sizeof(buffer));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    buffer_.append(buffer, static_cast<size_t>(n));
    return true;
  }
}

std::optional<std::string> LineChannel::TakeLine() {
  const size_t end = buffer_.find('\n');
  if (end == std::string::npos) return std::nullopt;
  std::string line = buffer_.substr(0, end);
  buffer_.erase(0, end + 1);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return line;
}

std::optional<nlohmann::json> LineChannel::TakeMessage() {
  const std::optional<std::string> line = TakeLine();
  if (!line) return std::nullopt;
  return nlohmann::json::parse(*line);
}

std::optional<nlohmann::json> LineChannel::Receive() {
  while (true) {
    if (std::optional<nlohmann::json> message = TakeMessage()) return message;
    if (!ReadSome()) return std::nullopt;
  }
}

void LineChannel::Close() {
  in_.Reset();
  out_.Reset();
}

// ---- child processes ----

ChildProcess ChildProcess::Spawn(const std::vector<std::string>& argv,
                                 const SpawnOptions& options) {
  if (argv.empty()) throw RunError("cannot start a process: no program named");
  // everything the child needs is made before fork: only async-signal-safe calls after it
  std::string program = options.program.empty() ? argv[0] : options.program;
  if (program.find('/') == std::string::npos) {
    const std::string found = FindProgram(program);
    if (!found.empty()) program = found;
  }
  const std::string cannot_run = argv[0] + ": cannot run (not found, or not executable)\n";
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  std::vector<char*> envp;
  if (options.env) {
    for (const std::string& e : *options.env) envp.push_back(const_cast<char*>(e.c_str()));
    envp.push_back(nullptr);
  }
  int to_child[2] = {-1, -1}, from_child[2] = {-1, -1}, errors[2] = {-1, -1};
  if ((options.in == Stdio::kPipe && pipe2(to_child, O_CLOEXEC) != 0) ||
      (options.out == Stdio::kPipe && pipe2(from_child, O_CLOEXEC) != 0) ||
      (options.err == Stdio::kPipe && pipe2(errors, O_CLOEXEC) != 0)) {
    throw RunError(Errno("cannot create pipes for " + argv[0]));
  }
  UniqueFd ends[] = {UniqueFd(to_child[0]),   UniqueFd(to_child[1]), UniqueFd(from_child[0]),
                     UniqueFd(from_child[1]), UniqueFd(errors[0]),   UniqueFd(errors[1])};
  const bool any_null =
      options.in == Stdio::kNull || options.out == Stdio::kNull || options.err == Stdio::kNull;
  UniqueFd null(any_null ? open("/dev/null", O_RDWR | O_CLOEXEC) : -1);
  // a child that exits early must not kill us as we write to it: we see EPIPE
  if (options.in == Stdio::kPipe) signal(SIGPIPE, SIG_IGN);
  auto stream = [&](Stdio how, int pipe_end) {
    return how == Stdio::kNull ? null.get() : pipe_end;
  };
  const int child_in = stream(options.in, to_child[0]);
  const int child_out = stream(options.out, from_child[1]);
  const int child_err = stream(options.err, errors[1]);

  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) throw RunError(Errno("cannot start " + argv[0]));
  if (pid == 0) {
    if (!DetachAndTie(parent)) _exit(127);
    // a stop signal fetchscope ignores must not be inherited as ignored
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    signal(SIGHUP, SIG_DFL);
    signal(SIGPIPE, SIG_DFL);
    UnblockSignals();
    MoveTo(child_in, STDIN_FILENO);
    MoveTo(child_out, STDOUT_FILENO);
    MoveTo(child_err, STDERR_FILENO);
    if (options.env) {
      execve(program.c_str(), args.data(), envp.data());
    } else {
      execv(program.c_str(), args.data());
    }
    (void)!write(STDERR_FILENO, cannot_run.data(), cannot_run.size());
    _exit(127);  // as a shell says of a program it cannot run
  }
  setpgid(pid, pid);  // also from this side, so the group exists when Spawn returns
  ChildProcess child;
  child.pid_ = pid;
  child.channel_ = LineChannel(std::move(ends[2]), std::move(ends[1]));
  child.stderr_ = std::move(ends[4]);
  return child;  // the child's ends close here
}

ChildProcess ChildProcess::Fork(const std::function<int(LineChannel& parent)>& body) {
  int sockets[2];
  if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sockets) != 0) {
    throw RunError(Errno("cannot create a socket for a child process"));
  }
  UniqueFd mine(sockets[0]), theirs(sockets[1]);
  std::fflush(stdout);  // or the child flushes our buffered output a second time
  std::fflush(stderr);
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) throw RunError(Errno("cannot start a child process"));
  if (pid == 0) {
    if (!DetachAndTie(parent)) _exit(1);
    UnblockSignals();
    mine.Reset();
    int status = 1;
    {
      UniqueFd in = DupCloexec(theirs.get());  // before `theirs` is moved from
      LineChannel channel(std::move(in), std::move(theirs));
      try {
        status = body(channel);
      } catch (...) {
        status = 1;
      }
    }
    std::fflush(stdout);
    std::fflush(stderr);
    _exit(status);  // no destructors of the parent's objects here
  }
  setpgid(pid, pid);
  ChildProcess child;
  child.pid_ = pid;
  UniqueFd in = DupCloexec(mine.get());
  child.channel_ = LineChannel(std::move(in), std::move(mine));
  return child;
}

ChildProcess::~ChildProcess() { Kill(); }

ChildProcess::ChildProcess(ChildProcess&& other) noexcept
    : pid_(other.pid_),
      exit_(other.exit_),
      channel_(std::move(other.channel_)),
      stderr_(std::move(other.stderr_)) {
  other.pid_ = -1;
}

ChildProcess& ChildProcess::operator=(ChildProcess&& other) noexcept {
  if (this != &other) {
    Kill();
    pid_ = other.pid_;
    exit_ = other.exit_;
    other.pid_ = -1;
    channel_ = std::move(other.channel_);
    stderr_ = std::move(other.stderr_);
  }
  return *this;
}

void ChildProcess::SignalGroup(int sig) const {
  if (pid_ > 0) kill(-pid_, sig);
}

void ChildProcess::Signal(int sig) const {
  if (pid_ > 0) kill(pid_, sig);
}

ChildExit ChildProcess::Wait(rusage* usage) {
  if (pid_ <= 0) return exit_.value_or(ChildExit{});
  int status = 0;
  rusage ignored{};
  while (wait4(pid_, &status, 0, usage ? usage : &ignored) < 0 && errno == EINTR) {
  }
  pid_ = -1;
  exit_ = ChildExit::FromWait(status);
  return *exit_;
}

std::optional<ChildExit> ChildProcess::TryWait(rusage* usage) {
  if (pid_ <= 0) return exit_;
  int status = 0;
  rusage ignored{};
  const pid_t r = wait4(pid_, &status, WNOHANG, usage ? usage : &ignored);
  if (r != pid_) return std::nullopt;
  pid_ = -1;
  exit_ = ChildExit::FromWait(status);
  return exit_;
}

std::optional<ChildExit> ChildProcess::WaitFor(double seconds) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (true) {
    if (std::optional<ChildExit> status = TryWait()) return status;
    if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

void ChildProcess::Kill() {
  if (pid_ <= 0) return;
  SignalGroup(SIGKILL);  // the group: a shell's own children go too
  Signal(SIGKILL);       // and the child, had it left its group
  Wait();
}

// ---- waiting ----

WaitEnd WaitForInput(std::vector<pollfd>* fds, int timeout_ms, bool watch_stop) {
  StopSignalBlock block;
  if (watch_stop && StopSignal() != 0) return WaitEnd::kStop;
  for (pollfd& p : *fds) p.revents = 0;
  const int stop_fd = watch_stop ? StopSignalFd() : -1;
  if (stop_fd >= 0) fds->push_back({stop_fd, POLLIN, 0});
  timespec timeout{timeout_ms / 1000, (timeout_ms % 1000) * 1000000L};
  const int r =
      ppoll(fds->data(), fds->size(), timeout_ms < 0 ? nullptr : &timeout, block.wait_mask());
  const int error = errno;
  if (stop_fd >= 0) fds->pop_back();
  if (r < 0 && error != EINTR) {
    errno = error;
    throw RunError(Errno("ppoll"));
  }
  if (watch_stop && StopSignal() != 0) return WaitEnd::kStop;
  for (const pollfd& p : *fds) {
    if (p.revents != 0) return WaitEnd::kReady;
  }
  return WaitEnd::kNone;
}

std::string SelfCommand() {
  std::error_code ec;
  const char* launcher = std::getenv("FETCHSCOPE_LAUNCHER");
  const std::filesystem::path self = launcher && *launcher
                                         ? std::filesystem::path(launcher)
                                         : std::filesystem::read_symlink("/proc/self/exe", ec);
  if (self.empty()) return "fetchscope";
  const std::string found = FindProgram("fetchscope");
  if (!found.empty() && std::filesystem::equivalent(found, self, ec)) return "fetchscope";
  return std::filesystem::absolute(self, ec).string();
}

std::string FindProgram(const std::string& name) {
  if (name.empty()) return "";
  if (name.find('/') != std::string::npos) return access(name.c_str(), X_OK) == 0 ? name : "";
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  size_t start = 0;
  while (start <= dirs.size()) {
    size_t end = dirs.find(':', start);
    if (end == std::string::npos) end = dirs.size();
    const std::string dir = end > start ? dirs.substr(start, end - start) : ".";
    const std::string candidate = dir + "/" + name;
    if (access(candidate.c_str(), X_OK) == 0) return candidate;
    start = end + 1;
  }
  return "";
}

}  // namespace fetchscope
