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

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

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

// Whose file it is, by its content (a run folder keeps only what fetchscope wrote, and refuses to
// replace anything else):

/// True for a fetchscope trajectory file (an object with env_id, seed and episodes).
bool IsFetchscopeTrajectory(const std::filesystem::path& path);
/// True for a video record wrote for episode k: its metadata (MP4 tags, Matroska tags, whose
/// names are upper case, the GIF comment) holds fetchscope_version and the title
/// "... episode K (POLICY)" (or `title`). Read in pieces, so a large video costs no more memory
/// than a small one.
bool IsFetchscopeVideo(const std::filesystem::path& path, int k, const std::string& title = "");
/// True when one of `names` (files in `out`) is a video of episode k with fetchscope's tags;
/// the answer is remembered in `videos`.
bool EpisodeHasFetchscopeVideo(const std::filesystem::path& out, int k,
                               const std::vector<std::string>& names, std::map<int, bool>* videos);
/// True when `path` is a report page fetchscope wrote (it carries the generator tag
/// `<meta name="generator" content="fetchscope ...">`).
bool IsFetchscopeReport(const std::filesystem::path& path);

}  // namespace fetchscope
