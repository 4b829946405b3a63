// The course chapter's deliverables as functions: D1 (describe), D2 (reward-check), D3
// (random-episodes), shared by those subcommands and by `anatomy`, which makes them all at once.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli/common.h"
#include "inspect/describe.h"
#include "src/fetch_env.h"

namespace fetchscope::cli {

/// The chapter's expected D3 mean return of the random policy on FetchReachDense-v4 (D1's
/// differences from the chapter: inspect/describe.h).
inline constexpr double kChapterDenseReturnLow = -25, kChapterDenseReturnHigh = -15;

/// What describe runs.
struct DescribeOptions {
  EnvOptions env;
  std::string json_out;    ///< empty: the JSON goes to stdout
  bool overwrite = false;  ///< replace a --json-out file of another env (CheckJsonOutReplaces)
};

/// D1, `describe`: to stdout, or to JsonOutPath(json_out, "describe"), then (with --json-out)
/// the lines of "chapter_differences" on stdout. Returns the exit status.
int RunDescribe(const DescribeOptions& options);

/// What reward-check runs.
struct RewardCheckOptions {
  EnvOptions env;
  int n_steps = 500;       ///< random-policy steps per variant
  std::string json_out;    ///< empty: no JSON file
  bool overwrite = false;  ///< replace a --json-out file of another task or seed
};

/// D2, `reward-check`: prints a table and writes JSON when asked. Returns true on pass.
bool RunRewardCheck(const RewardCheckOptions& options);

/// What random-episodes runs.
struct RandomEpisodesOptions {
  EnvOptions env;
  int n_episodes = 10;
  std::string json_out;  ///< empty: the JSON goes to stdout
  int jobs = 1;
  std::string worker_mode = "process";
  bool overwrite = false;  ///< replace a --json-out file of another env or seed
};

/// D3, `random-episodes`: the random-policy baseline, to stdout or JsonOutPath(json_out,
/// "random_metrics") (then a one-line summary, and a line where the mean return lies outside
/// the chapter's range, go to stdout; the JSON has that line under "chapter_differences").
/// Returns the exit status (128 + signal when interrupted).
int RunRandomEpisodes(const RandomEpisodesOptions& options);

}  // namespace fetchscope::cli
