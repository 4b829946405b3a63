// The file layout of a record run folder, in one place: every name record writes, and the parser
// that tells the run folder, merge-manifests and report which files are a run's.
//
//   manifest.json                         the run (or a merged run): see run/manifest.h
//   manifest_shard_IIII_of_NNNN.json      one shard's manifest (--shard I/N)
//   index.html                            the run's report
//   episode_NNN.{mp4,webm,gif}            episode NNN's video, one per --format
//   episode_NNN_sheet.png                 its contact sheet
//   episode_NNN.json                      its trajectory
//   episode_NNN_LAYER.{mp4,webm,gif}      its --layers videos (LAYER: depth, segmentation)
//   episode_NNN_segmentation_legend.json  the colours of its segmentation video
//
// and their hidden temporaries: .episode_NNN.partial.EXT (VideoWriter) and .NAME.tmp-XXXX
// (WriteFileAtomically).
#pragma once

#include <optional>
#include <string>

namespace fetchscope {

/// The manifest of an unsplit or merged run.
inline constexpr const char kManifestFileName[] = "manifest.json";
/// The run's report page, beside its manifest.
inline constexpr const char kReportFileName[] = "index.html";

/// "episode_007": the stem every file of episode k starts with.
std::string EpisodeStem(int k);
/// "episode_007.mp4": episode k's video with file extension `extension` ("mp4", "webm", "gif").
std::string EpisodeVideoFileName(int k, const std::string& extension);
/// "episode_007_depth.mp4": episode k's `layer` video.
std::string EpisodeLayerVideoFileName(int k, const std::string& layer,
                                      const std::string& extension);
/// "episode_007_segmentation_legend.json": the colours of episode k's segmentation video.
std::string EpisodeLegendFileName(int k);
/// "episode_007_sheet.png": episode k's contact sheet.
std::string EpisodeSheetFileName(int k);
/// "episode_007.json": episode k's trajectory.
std::string EpisodeTrajectoryFileName(int k);

/// "manifest.json" for an unsplit run (count 1), else "manifest_shard_IIII_of_NNNN.json" (so shards
/// writing into one folder never collide).
std::string ManifestFileName(int shard_index, int shard_count);
/// True for manifest.json and a shard's manifest name.
bool IsManifestFileName(const std::string& name);
/// True for a shard's manifest name (manifest_shard_*.json).
bool IsShardManifestFileName(const std::string& name);

/// A record run file name, parsed. `episode` is -1 for a manifest and the report; `hidden` for a
/// temporary.
struct RunFileName {
  int episode = -1;
  bool manifest = false;  ///< manifest.json or a shard's manifest
  bool report = false;    ///< index.html, the run's report
  bool hidden = false;
};

/// Parses `name` as one of the run's file names (see the top of this file); nullopt otherwise.
std::optional<RunFileName> ParseRunFileName(const std::string& name);

}  // namespace fetchscope
