// Options and helpers shared by the subcommands.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "base/cores.h"
#include "base/json_util.h"
#include "base/stop_signal.h"
#include "src/versions.h"

namespace fetchscope::cli {

/// --env-id, --assets, --seed as every env-driven subcommand takes them.
struct EnvOptions {
  std::string env_id = "auto";     ///< a v4 id or auto (FetchReachDense-v4)
  std::string assets = "bundled";  ///< bundled | auto | DIR
  std::string seed = "0";          ///< non-negative integer, parsed by ParseSeed
  /// The options as added by AddEnvOptions (null where not added): whether the command line
  /// named them, once parsed (a replayed trajectory JSON brings its own env and seed).
  const CLI::Option* env_id_option = nullptr;
  const CLI::Option* seed_option = nullptr;
};

/// Adds --env-id/--assets (and --seed when with_seed) to `sub`.
void AddEnvOptions(CLI::App* sub, EnvOptions* options, bool with_seed = true);

/// Parses a Gymnasium seed: a non-negative integer below 2^64. Throws UsageError.
uint64_t ParseSeed(const std::string& text);

/// `--json-out P` naming: P itself if it ends in .json; P + suffix + ".json" if it ends in '/'
/// (P names a folder: results/ gives results/describe.json); else P + "_" + suffix + ".json".
std::string JsonOutPath(const std::string& prefix, const std::string& suffix);

/// What a result file is about, in the order it is told: ("env_id", id), ("seed", n), ("task",
/// name); the keys are those of the JSON the file holds.
using ResultIdentity = std::vector<std::pair<std::string, nlohmann::json>>;

/// Before --json-out writes `path`: throws UsageError, naming the file, its identity and this
/// run's, when the file holds fetchscope's results (a JSON object with "assets") for another
/// env, seed or task, unless `overwrite`. A missing file, one of the same identity or one that
/// is not fetchscope's passes (it is replaced, as before).
void CheckJsonOutReplaces(const std::string& path, const ResultIdentity& identity, bool overwrite);

/// The help text of --overwrite for the --json-out writers.
inline constexpr const char* kJsonOverwriteHelp =
    "Let --json-out replace a result file of another env, seed or task (one of the same is "
    "replaced without it)";

/// The most --steps rollout, record and render take: steps beyond the env's TimeLimit (50) are
/// allowed and marked (docs/guide/recording.md, "Steps past the TimeLimit").
inline constexpr int kMaxSteps = 10000;

/// The help text of rollout's and record's --steps.
inline constexpr const char* kStepsHelp =
    "Steps per episode, 1..10000. Gymnasium's TimeLimit truncates at 50; steps after it are "
    "allowed, said once on stderr and marked \"past_time_limit\" in the trajectory JSON and "
    "in the HUD";

/// The command line as typed (set by main), recorded in manifests.
std::string& CommandLine();

/// The datasets options shared by rollout, record and export: --minari-author,
/// --minari-author-email (metadata `author`, `author_email`).
struct DatasetAuthor {
  std::string name;   ///< --minari-author ("": "fetchscope")
  std::string email;  ///< --minari-author-email ("": none)
};
void AddDatasetAuthorOptions(CLI::App* sub, DatasetAuthor* author);

/// Adds --signals (record, rollout): "none" (the default) or "contacts".
void AddSignalsOption(CLI::App* sub, std::string* signals);

/// --signals parsed: whether the trajectory's steps carry their contacts. Throws UsageError naming
/// the value and the accepted ones.
bool ParseContactSignals(const std::string& signals);

/// The --help formatter of every command: a placeholder named after the option instead of
/// CLI11's type names ("--seed SEED", not "--seed TEXT=0"), defaults in the description, no
/// "{false}" after negated flags. Set on the app before the subcommands are added (they inherit
/// it).
std::shared_ptr<CLI::Formatter> MakeHelpFormatter();

}  // namespace fetchscope::cli
