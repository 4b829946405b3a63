// Comparing two record runs of the same episodes (two policies, bundled against genuine assets,
// two versions of fetchscope): per episode the first step at which the states differ beyond a
// tolerance, the state difference over steps and, unless states only, a video A | B | per-pixel
// difference heat map; compare.json and an HTML page in the report's style.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace fetchscope {

/// What to compare, and how closely.
struct CompareOptions {
  std::string run_a;         ///< folder of the first record run
  std::string run_b;         ///< folder of the second
  std::string out;           ///< folder for the page, the videos and compare.json
  double tolerance = 1e-9;   ///< states: largest |a - b| of a step's vector still equal
  int pixel_tolerance = 0;   ///< frames: largest channel difference (0..255) still equal
  bool states_only = false;  ///< no videos decoded or written
  bool quiet = false;        ///< no table on stdout (read by the command)
  std::string command_line;  ///< recorded in compare.json
  nlohmann::json versions;   ///< recorded in compare.json
};

/// What the comparison found and wrote.
struct CompareResult {
  nlohmann::json rows;         ///< one per episode, as compare.json lists them
  bool same = true;            ///< every episode the same within the tolerances
  int differing = 0;           ///< episodes that differ
  std::filesystem::path page;  ///< the HTML page written
};

/// Compares the runs in `o.run_a` and `o.run_b` and writes `o.out`. Throws UsageError, before
/// anything is written, for runs of other episodes (SameRun's kEpisodes scope: env, seed, steps;
/// or other episode indices), unreadable trajectories and videos that cannot be compared.
CompareResult CompareRuns(const CompareOptions& o);

}  // namespace fetchscope
