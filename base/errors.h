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

/// A failure while running (bad assets, GL unavailable, unwritable output,
/// malformed replay file...). Exit code 1.
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

}  // namespace fetchscope
