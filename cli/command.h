// The one shape of every subcommand (ninja's kTools[] table, for CLI11): a function adds the
// subcommand to the parent app with its options bound into an options struct, and returns the
// subcommand with what runs it once the command line is parsed. After parsing nothing reads argv.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace fetchscope::cli {

/// One subcommand: its CLI11 app (options bound) and what runs it.
struct Command {
  CLI::App* app = nullptr;   ///< the subcommand, owned by the parent app
  std::function<int()> run;  ///< runs it: the exit status (0, 1 failure, 2 usage, 128+signal)
};

/// Adds one subcommand to `parent`. Each cli/<command>.cc defines one (two for golden's pair).
using AddCommandFn = Command (*)(CLI::App& parent);

Command AddListEnvs(CLI::App& parent);
Command AddDescribe(CLI::App& parent);
Command AddRewardCheck(CLI::App& parent);
Command AddRandomEpisodes(CLI::App& parent);
Command AddAnatomy(CLI::App& parent);
Command AddRollout(CLI::App& parent);
Command AddExport(CLI::App& parent);
Command AddDatasets(CLI::App& parent);
Command AddRender(CLI::App& parent);
Command AddListCameras(CLI::App& parent);
Command AddRecord(CLI::App& parent);
Command AddBench(CLI::App& parent);
Command AddProbeActions(CLI::App& parent);
Command AddMergeManifests(CLI::App& parent);
Command AddMergeDatasets(CLI::App& parent);
Command AddGolden(CLI::App& parent);
Command AddListGpus(CLI::App& parent);
Command AddReport(CLI::App& parent);
Command AddCompare(CLI::App& parent);
Command AddServe(CLI::App& parent);
Command AddHelp(CLI::App& parent);

/// Every subcommand, in the order `fetchscope --help` lists them.
inline constexpr AddCommandFn kCommands[] = {
    AddListEnvs, AddDescribe, AddRewardCheck,  AddRandomEpisodes, AddAnatomy,
    AddRollout,  AddExport,   AddDatasets,     AddRender,         AddListCameras,
    AddRecord,   AddBench,    AddProbeActions, AddMergeManifests, AddMergeDatasets,
    AddGolden,   AddListGpus, AddReport,       AddCompare,        AddServe,
    AddHelp};

}  // namespace fetchscope::cli
