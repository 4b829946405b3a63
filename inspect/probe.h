// The analysis behind `probe-actions`: what each action component really does. Every probe
// restarts from the same seeded reset, applies one constant command for `steps` steps and
// records the grip site's displacement and the fingers' opening change; the report flags what
// is surprising (off-axis motion, a blocked gripper, saturation above |a| = 1), keeps every
// step's displacement with the steps limited by reach, table, object or clip, and the steady
// state before them (inspect/probe_steps.h). With a renderer
// it also keeps the first and last frame of every probe, for a contact sheet.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "encode/contact_sheet.h"
#include "render/renderer.h"
#include "src/fetch_env.h"

namespace fetchscope {

/// The env moves the mocap target by this much per unit action per step (after clipping), m.
inline constexpr double kProbeMetresPerUnit = 0.05;

/// Parses --magnitudes: a comma list of 1 to 16 finite numbers > 0. Throws UsageError.
std::vector<double> ParseProbeMagnitudes(const std::string& text);

/// What ProbeActions measured.
struct ProbeResult {
  nlohmann::json report;         ///< env_id, seed, steps, probes, summary, ... (no versions)
  std::vector<SheetTile> tiles;  ///< with a renderer: each probe's first and last frame, in order
};

/// Parses --sweep-axis: "auto" (nullopt) or one of +x, -x, +y, -y, +z, -z (0..5 in that order).
/// Throws UsageError.
std::optional<int> ParseSweepAxis(const std::string& text);

/// Runs every probe (+x, -x, +y, -y, +z, -z, grip+, grip-, then the sweep "<axis>@M" for each of
/// `magnitudes`) on `env` from reset(seed) for `steps` steps, prints the table to stdout and
/// returns the report. The sweep runs along `sweep_axis` (0..5 as ParseSweepAxis), or, when
/// nullopt, along the axis whose unit probe went the most steps before a limit
/// (inspect/probe_steps.h). `renderer` (may be null) renders each probe's first and last frame.
ProbeResult ProbeActions(FetchEnv& env, uint64_t seed, int steps,
                         const std::vector<double>& magnitudes, std::optional<int> sweep_axis,
                         Renderer* renderer);

/// The probe sheet's columns for `tiles` tiles that come in pairs (each probe's first and last
/// frame side by side): an even number, so that a pair is never split, and about as many pairs
/// per row as make the sheet near square (11 pairs: 2 per row, 4 columns; 17: 3, 6 columns).
int ProbeSheetColumns(std::size_t tiles);

}  // namespace fetchscope
