// fetchscope merge-manifests DIR...: the shard manifests of one sharded record run -> one
// manifest.json listing every episode in order (run/merge.h does the merging and the checks),
// and the run's report beside it.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cli/command.h"
#include "cli/common.h"
#include "inspect/report.h"
#include "run/merge.h"

namespace fetchscope::cli {
namespace {

struct MergeManifestsOptions {
  std::vector<std::string> dirs;
  std::string out;  // "": DIR/manifest.json of the first DIR
  bool quiet = false;
  bool no_report = false;
};

int RunMergeManifests(const MergeManifestsOptions& o) {
  MergeRequest request;
  request.dirs = o.dirs;
  request.out = o.out;
  request.command_line = CommandLine();
  request.versions = VersionsJson();
  const MergeResult merged = MergeShardManifests(request);
  if (!o.quiet) {
    std::printf("merge-manifests: %d shard(s) of %d, %d episode(s), success %d/%d -> %s\n",
                merged.shards, merged.shard_count, merged.episodes, merged.successes,
                merged.episodes, merged.manifest.string().c_str());
  }
  if (!o.no_report) WriteRunReportOrWarn(merged.manifest, o.quiet);
  return 0;
}

}  // namespace

Command AddMergeManifests(CLI::App& app) {
  auto o = std::make_shared<MergeManifestsOptions>();
  CLI::App* sub = app.add_subcommand(
      "merge-manifests",
      "Merge the shard manifests of a sharded record run into one manifest.json; exit 1 naming "
      "any missing, interrupted or duplicated shard or episode, or a shard of another run (the "
      "first record option in which it differs)");
  sub->add_option("DIR", o->dirs, "Folders holding manifest_shard_*.json (and the episodes' files)")
      ->required();
  sub->add_option("--out", o->out,
                  "Merged manifest path (default: DIR/manifest.json of the first DIR)");
  sub->add_flag("-q,--quiet", o->quiet, "No summary on stdout");
  sub->add_flag("--no-report", o->no_report,
                "Do not write the run's HTML report (index.html beside the merged manifest)");
  return {sub, [o] { return RunMergeManifests(*o); }};
}

}  // namespace fetchscope::cli
