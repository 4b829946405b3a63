// Shared by the libFuzzer targets: what counts as an expected failure.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "base/errors.h"

namespace fetchscope::fuzz {

/// The fuzz input as a string.
inline std::string AsString(const uint8_t* data, size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

/// Runs `body`; UsageError and RunError are the parsers' documented answers to bad input and
/// are swallowed. Anything else (another exception, a crash, a sanitizer report) escapes to
/// libFuzzer, which reports it as a finding.
template <typename Body>
void ExpectOnlyOurErrors(Body&& body) {
  try {
    body();
  } catch (const UsageError&) {
  } catch (const RunError&) {
  }
}

}  // namespace fetchscope::fuzz
