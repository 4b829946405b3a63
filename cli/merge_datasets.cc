// fetchscope merge-datasets SHARD...: the datasets the shards of one run wrote (--shard I/N with
// --minari or --robomimic) joined into one (dataset/dataset_merge.h does the merging and checks).
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "base/errors.h"
#include "cli/command.h"
#include "cli/common.h"
#include "cli/obs_options.h"
#include "dataset/dataset_merge.h"
#include "dataset/minari_format.h"

namespace fetchscope::cli {
namespace {

struct MergeDatasetsOptions {
  std::vector<std::string> shards;
  std::string minari;       // --minari: the merged dataset's id
  std::string minari_root;  // --minari-root
  std::string robomimic;    // --robomimic: the merged file
  bool overwrite = false;
  double valid_fraction = 0;
  bool quiet = false;
};

int RunMergeDatasets(const MergeDatasetsOptions& o) {
  if (o.minari.empty() == o.robomimic.empty()) {
    throw UsageError(
        "merge-datasets: give --minari ID (the shards are Minari datasets) or "
        "--robomimic FILE.hdf5 (the shards are robomimic files), one of them");
  }
  CheckValidFraction(o.valid_fraction);
  if (!o.minari.empty() && o.valid_fraction > 0) {
    throw UsageError("--valid-fraction applies to the file of --robomimic");
  }
  DatasetMergeRequest request;
  request.shards = o.shards;
  request.root = MinariRoot(o.minari_root);
  request.minari_id = o.minari;
  request.robomimic = o.robomimic;
  request.overwrite = o.overwrite;
  request.valid_fraction = o.valid_fraction;
  if (!o.minari.empty()) ValidateMinariDatasetId(o.minari);
  const DatasetMergeResult r =
      o.minari.empty() ? MergeRobomimicShards(request) : MergeMinariShards(request);
  if (!o.quiet) {
    std::printf("merge-datasets: %d shard(s), %d episode(s) -> %s\n", r.shards, r.episodes,
                r.path.c_str());
  }
  return 0;
}

}  // namespace

Command AddMergeDatasets(CLI::App& app) {
  auto o = std::make_shared<MergeDatasetsOptions>();
  CLI::App* sub = app.add_subcommand(
      "merge-datasets",
      "Join the datasets the shards of one run wrote (rollout/record --shard I/N with --minari or "
      "--robomimic) into one, episodes in the run's order, each copied bit for bit; a shard of "
      "another run, one given twice or one missing is refused");
  sub->add_option("SHARD", o->shards,
                  "The shards' datasets: Minari ids (under --minari-root), folders or "
                  "main_data.hdf5 files; or robomimic .hdf5 files")
      ->required();
  sub->add_option("--minari", o->minari, "Write the merged Minari dataset under this id");
  sub->add_option("--minari-root", o->minari_root,
                  "Datasets root (default $MINARI_DATASETS_PATH, else ~/.minari/datasets)");
  sub->add_option("--robomimic", o->robomimic, "Write the merged robomimic file here (.hdf5)");
  sub->add_option("--valid-fraction", o->valid_fraction,
                  "--robomimic: mask/train and mask/valid of the merged file, this share in valid");
  sub->add_flag("--overwrite", o->overwrite, "Replace an existing dataset or file");
  sub->add_flag("-q,--quiet", o->quiet, "No summary on stdout");
  return {sub, [o] { return RunMergeDatasets(*o); }};
}

}  // namespace fetchscope::cli
