// probe-actions' parts shared by the probes' run (inspect/probe.cc) and their report
// (inspect/probe_report.cc: the JSON, the summary, the table). Internal to inspect/probe*.
#pragma once

#include <array>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "encode/contact_sheet.h"
#include "inspect/probe_steps.h"
#include "render/vec.h"
#include "src/env_spec.h"

namespace fetchscope::probe_detail {

// Steps of action[3] = +1 that open the fingers before grip- is measured.
inline constexpr int kOpenPrepSteps = 5;
// Thresholds behind the flags (m, per step unless said otherwise).
inline constexpr double kCosineFloor = 0.9;
inline constexpr double kStillPerStep = 1e-3;  // slower than this counts as not moving
inline constexpr double kFingerStill = 1e-4;   // |finger change| below this over a probe: no motion
inline constexpr double kFingerUncommanded = 2e-3;    // finger change without a gripper command
inline constexpr double kSaturationTolerance = 0.05;  // relative: "same displacement as |a| = 1"
inline constexpr int kMaxMagnitudes = 16;
inline constexpr const char* kAxisNames[6] = {"+x", "-x", "+y", "-y", "+z", "-z"};

// One probe: a constant command held for the measured steps, after optional preparation.
struct Probe {
  std::string name;
  std::array<double, 4> command{};
  std::vector<std::array<double, 4>> prep;  // steps before the measurement starts
  int axis = -1;                            // commanded axis 0..2; -1 for gripper probes
  double magnitude = 1;                     // |command| on `axis` (or on action[3])
  bool sweep = false;                       // part of the magnitude sweep
};

// What one probe measured.
struct Measurement {
  Vec3 mean_step{};              // (p_end - p_start) / steps, m
  double norm = 0;               // |mean_step|
  double along = 0;              // mean_step . axis (signed), m per step
  double cosine = NAN;           // with the commanded axis; NaN for gripper probes or no motion
  double drift = 0;              // |component perpendicular to the axis| per step (all of it if
                                 // no axis was commanded)
  double finger_delta = 0;       // change of the finger width (r + l) over the probe, m
  double finger_baseline = 0;    // the same change with action[3] = 0 (same preparation and xyz)
  double commanded = 0;          // 0.05 * min(|a|, 1) m per step along the axis
  double ratio = NAN;            // along / commanded
  std::vector<ProbeStep> steps;  // per step (probe_steps.h)
  SteadyState steady;            // median before the first limit (probe_steps.h)
  std::vector<std::string> flags;
  SheetTile first, last;  // frames, when rendering
};

/// The report of one probe: what it commanded, its totals, its per-step series and flags.
nlohmann::json ProbeJson(const Probe& p, const Measurement& m);

/// The answers over all probes; `sweep_axis` names the sweep's signed axis ("+y") and `sweep_why`
/// how it was chosen.
nlohmann::json SummaryJson(const EnvSpec& spec, const std::vector<Probe>& probes,
                           const std::vector<Measurement>& ms, const std::string& sweep_axis,
                           const std::string& sweep_why);

/// The table on stdout: a row per probe, the per-step series, the summary lines.
void PrintTable(const EnvSpec& spec, uint64_t seed, int steps, const std::vector<Probe>& probes,
                const std::vector<Measurement>& ms, const nlohmann::json& summary);

}  // namespace fetchscope::probe_detail
