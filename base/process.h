// Child processes, one way for every caller (the scheduler's workers, the node probe, the exec:
// policy, bench's children), after ninja's subprocess-posix.cc: each child starts from an exact
// argv (or runs a function in a fork) in a process group of its own, so a terminal's Ctrl-C
// reaches fetchscope alone, which decides and forwards it; it dies with the thread that started
// it (PR_SET_PDEATHSIG), so none is ever orphaned. The parent waits on its children's pipes
// with ppoll while the stop signals are blocked, so a stop request ends the wait at once.
#pragma once

#include <poll.h>
#include <sys/resource.h>
#include <sys/types.h>

#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace fetchscope {

/// One file descriptor, closed when the object goes. Move-only.
class UniqueFd {
 public:
  UniqueFd() = default;
  explicit UniqueFd(int fd) : fd_(fd) {}
  ~UniqueFd() { Reset(); }
  UniqueFd(UniqueFd&& other) noexcept : fd_(other.Release()) {}
  UniqueFd& operator=(UniqueFd&& other) noexcept;
  UniqueFd(const UniqueFd&) = delete;
  UniqueFd& operator=(const UniqueFd&) = delete;

  int get() const { return fd_; }                      ///< the descriptor, or -1
  explicit operator bool() const { return fd_ >= 0; }  ///< true when open
  int Release();            ///< gives the descriptor up without closing it
  void Reset(int fd = -1);  ///< closes the one held and holds `fd`

 private:
  int fd_ = -1;
};

/// How a child ended: exited with a status, or killed by a signal.
struct ChildExit {
  int code = 0;    ///< the exit status when it exited
  int signal = 0;  ///< the signal that killed it, or 0 when it exited

  /// From a waitpid status.
  static ChildExit FromWait(int status);
  bool exited() const { return signal == 0; }           ///< it called exit
  bool ok() const { return signal == 0 && code == 0; }  ///< exit status 0
  /// Killed by SIGINT, SIGTERM or SIGHUP: somebody stopped it, which is no failure of its own.
  bool interrupted() const;
  /// What a shell says of it: the exit status, or 128 + the signal.
  int ShellCode() const { return signal ? 128 + signal : code; }
  /// "exited with status 3" or "died of signal 9 (SIGKILL: Killed)".
  std::string Describe() const;
};

/// "signal 9 (SIGKILL: Killed)": the number, the name users grep for, and the description.
std::string SignalName(int sig);

/// `arg` as a POSIX shell reads it back as one word: unchanged when it holds only letters,
/// digits and @%+=:,./_- (and is not empty), else in single quotes (a quote inside as '\''), so
/// that a command line we print can be pasted.
std::string ShellQuote(const std::string& arg);

/// The words of a command line as a POSIX shell splits them (blanks between words; single
/// quotes, double quotes and backslashes as the shell reads them; no expansions): the inverse of
/// joining ShellQuote'd words with spaces. nullopt for an unterminated quote.
std::optional<std::vector<std::string>> SplitShellWords(const std::string& line);

/// Lines both ways over descriptors (a pipe pair, or one socket): writes whole lines, reads
/// into a buffer and hands out complete lines. One JSON object per line for the JSON calls.
class LineChannel {
 public:
  LineChannel() = default;
  /// Reads from `in`, writes to `out` (either may be closed; a socket may be both: dup it).
  LineChannel(UniqueFd in, UniqueFd out) : in_(std::move(in)), out_(std::move(out)) {}

  /// Writes all of `line` and a newline; false when the peer has gone (no SIGPIPE on sockets;
  /// on a pipe the caller ignores SIGPIPE, as ChildProcess::Spawn does when it pipes stdin).
  bool WriteLine(const std::string& line);
  /// Writes `message` as one line of JSON.
  bool Send(const nlohmann::json& message);
  /// Reads once (what is there, or blocks for some) into the buffer; false at end of file or on
  /// an error.
  bool ReadSome();
  /// The next complete line in the buffer, without its newline (or a final carriage return).
  std::optional<std::string> TakeLine();
  /// The next complete line as JSON. Throws nlohmann's parse_error on a line that is not JSON.
  std::optional<nlohmann::json> TakeMessage();
  /// Blocks for the next whole JSON line; nullopt when the peer has gone first.
  std::optional<nlohmann::json> Receive();
  /// Closes the writing side (the peer reads end of file).
  void CloseOutput() { out_.Reset(); }
  /// Closes both sides.
  void Close();

  int in_fd() const { return in_.get(); }                 ///< for poll sets
  int out_fd() const { return out_.get(); }               ///< the writing descriptor
  size_t buffered() const { return buffer_.size(); }      ///< bytes read and not yet taken
  const std::string& pending() const { return buffer_; }  ///< those bytes (a line not ended yet)

 private:
  UniqueFd in_, out_;
  std::string buffer_;
};

/// What a spawned child's standard stream is.
enum class Stdio {
  kInherit,  ///< this process's
  kPipe,     ///< a pipe to this process (stdin and stdout: the channel; stderr: stderr_fd)
  kNull,     ///< /dev/null
};

/// How to spawn a program.
struct SpawnOptions {
  Stdio in = Stdio::kInherit;   ///< stdin
  Stdio out = Stdio::kInherit;  ///< stdout
  Stdio err = Stdio::kInherit;  ///< stderr
  /// The file to execute; empty: argv[0], looked up on PATH when it has no slash.
  std::string program;
  /// The child's environment ("NAME=value"); nullopt: this process's.
  std::optional<std::vector<std::string>> env;
};

/// A running child process: its own process group, dying with the thread that started it.
/// Move-only; the destructor kills the group (SIGKILL) and reaps the child if it still runs.
class ChildProcess {
 public:
  /// Starts `argv` (exact: no shell). Throws RunError when it cannot start; a program that is
  /// not there exits with status 127 (as a shell says).
  static ChildProcess Spawn(const std::vector<std::string>& argv, const SpawnOptions& options = {});
  /// Runs `body` in a forked child, which exits with what it returns (1 on an exception). The
  /// two talk over a socket: the child's end is the argument, this side is channel(). The
  /// child unblocks the stop signals; other threads of this process do not exist in it, so
  /// `body` uses only what it makes itself or what this thread owned.
  static ChildProcess Fork(const std::function<int(LineChannel& parent)>& body);

  ChildProcess() = default;
  ~ChildProcess();
  ChildProcess(ChildProcess&& other) noexcept;
  ChildProcess& operator=(ChildProcess&& other) noexcept;
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const { return pid_; }               ///< also its process group id
  bool running() const { return pid_ > 0; }        ///< started and not yet reaped
  LineChannel& channel() { return channel_; }      ///< stdin/stdout, or the socket
  int stderr_fd() const { return stderr_.get(); }  ///< with SpawnOptions::err kPipe
  /// Sends `sig` to the child's process group (the child and what it started).
  void SignalGroup(int sig) const;
  /// Sends `sig` to the child alone.
  void Signal(int sig) const;
  /// Waits for the child to end (retrying on EINTR); `usage` gets its resource use. Once it
  /// has been reaped, Wait, TryWait and WaitFor return how it ended at once.
  ChildExit Wait(rusage* usage = nullptr);
  /// How the child ended if it has, without blocking; nullopt while it runs.
  std::optional<ChildExit> TryWait(rusage* usage = nullptr);
  /// Waits at most `seconds` for the child to end.
  std::optional<ChildExit> WaitFor(double seconds);
  /// Kills the group (SIGKILL) and reaps the child, unless it has been reaped already.
  void Kill();

 private:
  pid_t pid_ = -1;
  std::optional<ChildExit> exit_;  // once reaped
  LineChannel channel_;
  UniqueFd stderr_;
};

/// What ended a WaitForInput.
enum class WaitEnd {
  kReady,  ///< a descriptor has input (see the revents)
  kNone,   ///< nothing is ready: the time passed, or another signal came
  kStop,   ///< a stop was requested (StopSignal() says which signal)
};

/// Waits until one of `fds` (events set by the caller) is ready, `timeout_ms` passes (-1:
/// never), or, with `watch_stop`, a stop is requested (InstallStopSignals). The stop signals
/// are blocked while it checks StopSignal() and are let in only inside ppoll, so a signal
/// cannot slip in between; the stop self-pipe wakes it when another thread took the signal.
/// Throws RunError when ppoll fails.
WaitEnd WaitForInput(std::vector<pollfd>* fds, int timeout_ms, bool watch_stop = true);

/// The path of `name` on PATH (or `name` itself when it has a slash and is executable); empty
/// when there is none.
std::string FindProgram(const std::string& name);

/// How a command fetchscope prints for the user to paste names fetchscope itself: "fetchscope"
/// when that is what PATH finds, else the absolute path of what runs (the bundle's launcher,
/// FETCHSCOPE_LAUNCHER, or this executable).
std::string SelfCommand();

}  // namespace fetchscope
