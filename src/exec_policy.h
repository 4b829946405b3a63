// exec:CMD — a child process is the policy. Protocol, one JSON line each way per step:
//   fetchscope → child stdin:
//   {"t":0,"observation":[...],"achieved_goal":[...],"desired_goal":[...]} (src/exec_wire.h:
//   the fields --exec-fields chose, and with --obs-camera the images' bytes after the line);
//   child stdout → fetchscope: 4 numbers separated by spaces or commas, or a JSON array of 4.
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <string>

#include "src/policy_spec.h"

namespace fetchscope {

class Policy;

/// Starts `exec.command` under /bin/sh, in its own process group, dying with the calling thread
/// (PR_SET_PDEATHSIG); each answer must come within `exec.timeout_s` seconds; each line carries
/// `exec.fields` (src/exec_wire.h). When the child dies while `stop_requested` says the run is
/// being stopped, Act throws PolicyInterrupted (an interruption) rather than RunError. With
/// `images`, each line is followed by the images it returns for the step asked about, and a
/// child that answers before reading them all is an error.
std::unique_ptr<Policy> MakeExecPolicy(const policy_spec::Exec& exec,
                                       std::function<bool()> stop_requested = nullptr,
                                       std::function<const WireStep*(int t)> images = nullptr);

/// Parses one answer line into 4 finite numbers. Throws RunError describing what was wrong.
std::array<double, 4> ParseActionLine(const std::string& line);

}  // namespace fetchscope
