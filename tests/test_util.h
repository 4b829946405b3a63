// Helpers shared by the test binaries: temp folders, running the CLI.
#pragma once

#include <sys/types.h>

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "render/overlay.h"

namespace fetchscope::testing {

/// Result of running a shell command.
struct CommandResult {
  int exit_code;       ///< exit status (128+signal if killed)
  std::string output;  ///< stdout and stderr together
};

/// Runs `fetchscope ARGS` (the built binary) through /bin/sh and captures its output.
/// The fetchscope the black-box tests run: this build's, or $FETCHSCOPE_TEST_BIN when set (to
/// run the tests against another build, e.g. to see a new test fail on the code before a fix).
std::string FetchscopeBinary();
CommandResult RunFetchscope(const std::string& args);

/// Runs an arbitrary shell command and captures its output.
CommandResult RunCommand(const std::string& command);

/// Runs `fetchscope ARGS` and captures its stdout alone (for JSON on stdout); its stderr goes to
/// `stderr_text` when given, else is dropped.
CommandResult RunFetchscopeStdout(const std::string& args, std::string* stderr_text = nullptr);

/// A fresh empty folder under the system temp dir, removed on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  /// The folder.
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// The genuine Gymnasium-Robotics assets folder (../shared/gymnasium-robotics-assets),
/// or empty if absent (tests then GTEST_SKIP).
std::filesystem::path GenuineAssetsDir();

/// The project's source folder.
std::filesystem::path SourceDir();

/// Reads a whole file into a string (empty if missing).
std::string ReadFile(const std::filesystem::path& path);

/// The per-episode output files of a record run folder (episode_*, not manifests): name -> bytes.
std::map<std::string, std::string> EpisodeFiles(const std::filesystem::path& dir);

/// Every file in `dir` (not below it), by name, with its bytes.
std::map<std::string, std::string> AllFiles(const std::filesystem::path& dir);

/// The names of the entries of `dir` (not below it).
std::set<std::string> FilesIn(const std::filesystem::path& dir);

/// How often `needle` occurs in `text` (overlapping occurrences counted).
int Count(const std::string& text, const std::string& needle);

/// Lines of `text` that hold `needle`.
std::vector<std::string> LinesWith(const std::string& text, const std::string& needle);

/// The lines of `text`, without their newlines.
std::vector<std::string> SplitLines(const std::string& text);

/// How many lines `text` has (a last line without a newline counts).
int LineCount(const std::string& text);

/// Starts `fetchscope ARGS` in the background, its output in `log`; returns its pid.
pid_t SpawnFetchscope(const std::string& args, const std::filesystem::path& log);

/// Waits for `pid`: its exit status, or 128 + the signal that ended it.
int WaitExit(pid_t pid);

/// Waits up to `seconds` until process `pid` has a handler of its own for `signal` (SigCgt in
/// /proc/PID/status): from then on a signal is the command's to handle, not the default's death.
/// False when it never did (or the process ended).
bool WaitForSignalHandler(pid_t pid, int signal, double seconds = 60);

/// ffprobe's JSON for `path` (-count_frames -show_entries SHOW_ENTRIES -of json); a failed probe
/// fails the test and gives a discarded value.
nlohmann::json FfprobeJson(const std::filesystem::path& path, const std::string& show_entries);

/// ffprobe's format tags of `path`, names lowercased (Matroska stores tag names in capitals).
std::map<std::string, std::string> FfprobeFormatTags(const std::filesystem::path& path);

/// The JSON of a page's `<script id="ID" type="application/json">` block ("fetchscope-data": the
/// page's data), or null when the page has none.
nlohmann::json PageBlock(const std::string& html, const std::string& id);

/// Frames ffprobe decodes from the first video stream of `video`, or -1 if it does not play.
int DecodedFrames(const std::filesystem::path& video);

/// A python3 that imports h5py and numpy: the one on PATH, else Debian's; "" when none.
std::string PythonWithH5py();

/// PythonWithH5py's python when it also imports PIL (python3-pil); "" when it does not.
std::string PythonWithPil();

/// Writes `text` to `file` with its first `from` replaced by `to` (a test's damaged metadata);
/// fails the test, writing nothing, where `text` lacks `from`.
void WriteEdited(const std::filesystem::path& file, const std::string& text,
                 const std::string& from, const std::string& to);

/// Replaces `episode`'s actions in the Minari HDF5 file `hdf5` ("episode_1") by `rows` rows of
/// four float32 zeros; with 0 rows they are only removed. Fails the test where it cannot.
void ReplaceMinariActions(const std::filesystem::path& hdf5, const std::string& episode,
                          size_t rows);

/// A running `fetchscope serve ARGS --port 0 --token-file DIR/token` (output in DIR/serve.log),
/// once it has printed its URL; stopped with SIGINT and waited for on destruction.
/// A raw TCP connection to 127.0.0.1:`port`, for what no HTTP client library sends; its reads
/// give up after `patience_s`. -1 where it cannot connect.
int ConnectLoopback(int port, int patience_s = 60);
/// Sends all of `bytes` at once (false when the connection took fewer).
bool SendAll(int fd, const std::string& bytes);
/// Everything the peer sends until it closes the connection (or the read times out).
std::string ReadUntilClosed(int fd);

class ServeProcess {
 public:
  ServeProcess(const std::string& args, const std::filesystem::path& dir);
  ~ServeProcess();
  ServeProcess(const ServeProcess&) = delete;
  ServeProcess& operator=(const ServeProcess&) = delete;
  /// Whether it printed its URL (else it exited: log() says why).
  bool started() const { return port > 0; }
  /// Sends `sig` and waits: its exit status, or 128 + the signal that ended it.
  int Stop(int sig);
  /// What it printed so far.
  std::string log() const;

  pid_t pid = -1;
  int port = 0;
  std::string token;  ///< read from DIR/token
  std::string url;    ///< the URL it printed, with ?token=
  std::filesystem::path log_path;
};

/// A Reach step on success, for the HUD and caption tests: the sparse reward is -0.0
/// (Gymnasium's -(d > threshold)), and an action component is -0.001.
FrameInfo ReachSuccessStep();

}  // namespace fetchscope::testing
