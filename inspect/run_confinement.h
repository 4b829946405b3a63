// Where a run folder's files may lie (inspect/run_confinement.cc): its own folder, and a merged
// run's shard folders where their shard manifests are; a manifest naming a file elsewhere, or one
// that is not a regular file, is refused with one line naming the entry.
#pragma once

#include <filesystem>
#include <vector>

#include "inspect/report.h"
#include "run/manifest.h"

namespace fetchscope {

/// The folders the files of the run in `dir` (manifest `m`) may lie in: `dir`, and for a merged
/// run the folders of the shard manifests its "shards" names, resolved, where such a file is.
std::vector<std::filesystem::path> RunFolders(const std::filesystem::path& dir, const Manifest& m);

/// Throws UsageError naming the entry when a file an episode of `run`'s manifest names lies
/// outside run.folders or is there but is not a regular file.
void CheckNamedFiles(const RecordedRun& run);

}  // namespace fetchscope
