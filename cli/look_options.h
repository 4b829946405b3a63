// --randomize and --randomize-config (render/look.h's randomized looks) as typed, and what a
// command makes of them: shared by render, record, rollout and serve.
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>

#include "render/look.h"

namespace fetchscope::cli {

/// The options as typed.
struct LookOptions {
  std::string randomize;          ///< --randomize LIST; empty: not given
  std::string config;             ///< --randomize-config FILE.json; empty: the default ranges
  std::string look_seed;          ///< --look-seed S; empty: the run's --seed
  CLI::Option* option = nullptr;  ///< --randomize's option (count() > 0 when given)
};

/// Adds --randomize and --randomize-config to `sub`. `from_note`: the sentence saying what a
/// re-render does without --randomize (record --from), or "" for a command that has none.
void AddLookOptions(CLI::App* sub, LookOptions* options, const std::string& from_note = "");

/// --randomize as given: its kinds (none: the plain look) and ranges (--randomize-config, read
/// and checked now); nullopt when --randomize was not given. --randomize-config without
/// --randomize is refused in one line. Throws UsageError as ParseRandomize and ReadLookConfig.
std::optional<LookConfig> ResolveLook(const LookOptions& options);

/// --look-seed: the seed the looks are drawn from (LookSeed(S, episode)) instead of --seed, so
/// that the same episodes are drawn under other looks; nullopt when not given. Refused in one
/// line without --randomize, or as a seed that is not one (ParseSeed).
std::optional<uint64_t> ResolveLookSeed(const LookOptions& options);

}  // namespace fetchscope::cli
