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

}  // namespace fetchscope
