// fetchscope report DIR: a record run folder -> DIR/index.html (see cli/html_page.h), and the
// reading of run folders that `report` and `compare` share.
#pragma once

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "run/manifest.h"
#include "src/trajectory.h"

namespace fetchscope {

/// A record run as its manifest describes it.
struct RecordedRun {
  std::filesystem::path dir;            ///< the folder holding the manifest
  std::filesystem::path manifest_path;  ///< dir/manifest.json (or a shard manifest)
  Manifest manifest;
  std::vector<int> expected;                ///< the episodes the run was asked to record
  std::map<int, ManifestEpisode> recorded;  ///< manifest entries by episode index
  std::map<int, std::string> failed;        ///< a worker's failure message by episode index
  /// Where its files may lie, resolved: `dir`, and for a merged run the folders of the shard
  /// manifests its `shards` names (merge-manifests DIR... names files in each shard's folder).
  std::vector<std::filesystem::path> folders;
};

/// Reads `manifest_path` (a record or merge-manifests manifest). Throws UsageError when the file
/// is missing or is not a record manifest, or names a file that lies outside its folder (symbolic
/// links and '..' followed) or is there but is not a regular file; RunError when it cannot be
/// read.
RecordedRun ReadRunManifest(const std::filesystem::path& manifest_path);

/// `run.dir / entry` for a file name `entry` of the run's manifest, once checked: it lies inside
/// one of `run.folders` (symbolic links and '..' followed) and, where it exists, is a regular
/// file. Throws UsageError "`named_by` 'ENTRY', which lies outside the run folder 'DIR': ..."
/// (or "..., which is a FIFO, not a regular file ...") otherwise.
std::filesystem::path RunFile(const RecordedRun& run, const std::string& entry,
                              const std::string& named_by);

/// Reads the run in folder `dir`: dir/manifest.json. Throws UsageError naming `dir` when it is
/// not a folder or holds no manifest.json (saying so when it holds shard manifests instead).
RecordedRun ReadRunFolder(const std::string& dir);

/// The steps of the single episode in an episode_NNN.json trajectory file (ReadTrajectory).
/// Throws RunError naming the file (and the key) when it is missing or malformed.
std::vector<TrajectoryStep> ReadEpisodeTrajectory(const std::filesystem::path& path);

/// Every other video file the entry names anywhere (such as per-layer videos of record
/// --layers), by file name, in name order, without those of EpisodeVideos().
std::vector<std::string> OtherEpisodeVideos(const ManifestEpisode& entry);

/// The video a page or a comparison shows of an episode: the first of EpisodeVideos() whose
/// file exists in `dir`, or nullptr when none does.
const EpisodeVideo* PlayableVideo(const std::vector<EpisodeVideo>& videos,
                                  const std::filesystem::path& dir);

/// Euclidean distance from achieved to desired goal of a step.
double GoalDistance(const TrajectoryStep& step);

/// The run's provenance as {label, value} rows: env, seed, policy, assets and their hash, encoder,
/// GL device(s), fetchscope version, command line...
nlohmann::json RunProvenance(const RecordedRun& run);

/// The report page's data for `run` (see web/src/report.js): provenance, episodes with their
/// distance curves, histogram and success rate.
nlohmann::json ReportData(const RecordedRun& run);

/// Writes index.html beside the manifest, atomically. Returns its path. Throws on failure.
std::filesystem::path WriteRunReport(const RecordedRun& run);

/// For record and merge-manifests: writes the report of `manifest_path`; a failure is a warning
/// on stderr ("fetchscope: warning: ..."), never a failed run. Prints the path unless quiet.
void WriteRunReportOrWarn(const std::filesystem::path& manifest_path, bool quiet);

}  // namespace fetchscope
