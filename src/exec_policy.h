// exec:CMD — a child process is the policy. Protocol, one JSON line each way per step:
//   fetchscope → child stdin:
//   {"t":0,"observation":[...],"achieved_goal":[...],"desired_goal":[...]} child stdout →
//   fetchscope: 4 numbers separated by spaces or commas, or a JSON array of 4.
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <string>

namespace fetchscope {

class Policy;

/// Starts `command` under /bin/sh, in its own process group, dying with the calling thread
/// (PR_SET_PDEATHSIG); each answer must come within `timeout_s` seconds. When the child dies
/// while `stop_requested` says the run is being stopped, Act throws PolicyInterrupted (an
/// interruption) rather than RunError.
std::unique_ptr<Policy> MakeExecPolicy(const std::string& command, double timeout_s,
                                       std::function<bool()> stop_requested = nullptr);

/// Parses one answer line into 4 finite numbers. Throws RunError describing what was wrong.
std::array<double, 4> ParseActionLine(const std::string& line);

}  // namespace fetchscope
