// Error types shared by every layer. main() maps them to exit codes.
#pragma once

#include <stdexcept>
#include <string>

namespace fetchscope {

/// Bad input on the command line (unknown id, malformed spec, bad size...).
/// The message names the bad value and what is accepted. Exit code 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A failure while running (bad assets, GL unavailable, a full disk, a malformed replay
/// file...). Exit code 1.
class RunError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A policy could not answer because the run is being stopped (SIGINT/SIGTERM), e.g. an exec:
/// child that died of the same signal. An interruption, not a failure: the episode in progress
/// ends there, incomplete (RunEpisode catches it).
class PolicyInterrupted : public RunError {
 public:
  using RunError::RunError;
};

/// The one rule for a path named on the command line (docs/reference/exit-codes.md): when the
/// system's error `error` (an errno) says the path cannot be used as given (it does not exist,
/// is of the wrong kind, lies below a file, or may not be read or written: ENOENT, ENOTDIR,
/// EISDIR, EEXIST, EACCES, EPERM, EROFS, ENAMETOOLONG, ELOOP) it is a usage error, exit 2;
/// any other (a full disk, an I/O error) is a run-time failure, exit 1. Throws the one chosen,
/// with `message`.
[[noreturn]] void ThrowPathError(const std::string& message, int error);

/// `s` in single quotes, as messages name a value or a path: 'episode_000.mp4'.
std::string Quoted(const std::string& s);

}  // namespace fetchscope
