// The manifest of a record run (manifest.json, a shard's manifest_shard_IIII_of_NNNN.json, or the
// one merge-manifests writes): one type, one reader and one writer, and the one definition of "the
// same run" (SameRun).
//
// Versions: the file carries "schema_version" (kManifestSchemaVersion). A manifest without one was
// written before versions existed and is read as version 0, the same layout; a newer version is
// refused, naming the file and both versions. Members this build does not know are kept
// (Manifest::extra, ManifestEpisode::extra, each typed section's extra) and written back unchanged.
//
// The sections "video", "backend", "gpu", "workers" and "timings_s" are typed too
// (run/manifest_sections.h); an episode entry is encode/episode_result.h's ManifestEpisode, which
// the episode sink fills.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "base/errors.h"
#include "encode/episode_result.h"
#include "run/manifest_sections.h"

namespace fetchscope {

/// The schema version this build writes, and the newest it reads.
inline constexpr int kManifestSchemaVersion = 1;

/// A file that is not a manifest this build can read (malformed, not a record manifest, or a newer
/// schema version). A RunError (exit 1); report turns it into a UsageError.
class ManifestError : public RunError {
 public:
  using RunError::RunError;
};

/// What makes two record runs the same run: the record options their outputs depend on, as the
/// manifest's "parameters" stores them (option name -> value). --jobs, --gpu and --backend are not
/// among them: outputs do not depend on them on one machine.
struct RunParameters {
  std::string env_id;         ///< --env-id
  uint64_t seed = 0;          ///< --seed
  std::string policy;         ///< --policy
  std::string replay_dtype;   ///< --replay-dtype ("" = as the replay file holds it)
  int episodes = 0;           ///< --episodes
  int steps = 0;              ///< --steps
  int sheet_every = 0;        ///< --sheet-every
  std::string assets_sha256;  ///< --assets, by the hash of their content
  std::string camera;         ///< --camera
  std::string overlay;        ///< --overlay
  int width = 0;              ///< --width, one camera's tile, pixels
  int height = 0;             ///< --height, pixels
  std::string msaa;           ///< --msaa as given ("auto", "0", "4"...)
  std::string codec;          ///< --codec as decided (libx264, h264_nvenc...)
  int crf = 0;                ///< --crf
  std::string preset;         ///< --preset (its default filled in)
  int fps = 0;                ///< --fps
  int shard_index = 0;        ///< --shard I/N: I
  int shard_count = 1;        ///< --shard I/N: N
  std::vector<std::string> formats = {"mp4"};  ///< --format, in the order given
  int gif_fps = 10;                            ///< --gif-fps (stored with gif among the formats)
  int gif_width = 320;                         ///< --gif-width (likewise)
  std::string layers = "rgb";                  ///< --layers ("rgb" and the extra layers in order)
  std::string signals = "none";                ///< --signals ("none" is not stored)
  /// False for a manifest written before "parameters" existed: then only env_id, seed and steps are
  /// known (from the manifest's own members).
  bool recorded = true;

  bool operator==(const RunParameters& other) const;
  bool operator!=(const RunParameters& other) const { return !(*this == other); }
};

/// Which parameters SameRun compares.
enum class SameRunScope {
  kRun,       ///< all of them: a --resume continues only the very same run
  kShards,    ///< all but the shard's index (N included): shards of one run (merge, a folder)
  kEpisodes,  ///< --env-id, --seed, --steps: the same episodes, of any run (compare)
};

/// The first parameter in which two runs differ.
struct RunDifference {
  std::string parameter;  ///< the option: "--msaa"
  std::string a;          ///< its value in the first run, as text: "auto"
  std::string b;          ///< in the second: "4"
};

/// The one definition of "the same run": the first parameter in `scope` (in the order of the record
/// options' table) whose value differs between `a` and `b`, or nullopt when none does. With kRun
/// and kShards both must be recorded (RunParameters::recorded).
std::optional<RunDifference> SameRun(const RunParameters& a, const RunParameters& b,
                                     SameRunScope scope = SameRunScope::kRun);

/// The record options, by name, that RunParameters holds ("--env-id" ... "--layers").
std::vector<std::string> RunParameterNames();

/// One video file of an episode in one output format (record --format).
struct EpisodeVideo {
  std::string format;  ///< "mp4", "webm", "gif", or the file's extension for others
  std::string file;    ///< relative to the run folder
  int frames = -1;     ///< frames in the file, -1 when the manifest does not say
  bool operator==(const EpisodeVideo& o) const {
    return format == o.format && file == o.file && frames == o.frames;
  }
};

/// The episode's videos in the formats record wrote ("videos"; older manifests: "video" alone), in
/// the order a browser plays them best: mp4, webm, gif, then any other format by name.
std::vector<EpisodeVideo> EpisodeVideos(const ManifestEpisode& episode);
/// The same for one --layers video of an episode.
std::vector<EpisodeVideo> EpisodeVideos(const EpisodeLayer& layer);

/// A worker's failure: the episodes it could not record, and why.
struct ManifestFailure {
  int worker = 0;
  std::vector<int> episodes;
  std::string message;
  bool operator==(const ManifestFailure& o) const {
    return worker == o.worker && episodes == o.episodes && message == o.message;
  }
};

/// Which shard of a run a manifest holds.
struct ManifestShard {
  int index = 0;
  int count = 1;
  std::optional<std::string> source;         ///< "--shard", "SLURM_ARRAY_TASK_ID"...; null: none
  std::optional<std::vector<int>> episodes;  ///< this shard's episodes (absent: not said)
  bool operator==(const ManifestShard& o) const {
    return index == o.index && count == o.count && source == o.source && episodes == o.episodes;
  }
};

/// A record run's manifest. Members a merged manifest (merged) does not have are marked "per
/// process": it has `shards` instead.
struct Manifest {
  int schema_version = kManifestSchemaVersion;  ///< as read (0: from before versions)
  std::string env_id;
  uint64_t seed = 0;
  std::string policy;
  std::optional<std::string> from;  ///< record --from: the run or file replayed
  int episodes_requested = 0;
  int steps_per_episode = 0;
  int sheet_every = 0;
  std::vector<ManifestEpisode> episodes;             ///< in index order
  std::vector<int> missing;                          ///< per process: episodes not recorded
  std::vector<ManifestFailure> failures;             ///< per process
  std::optional<ManifestShard> shard;                ///< per process; absent before sharding
  int jobs = 1;                                      ///< per process
  std::string worker_mode;                           ///< per process
  std::vector<ManifestWorker> workers;               ///< per process: each worker's GL setup
  ManifestGpu gpu;                                   ///< per process: request, choice, devices
  nlohmann::json assets = nlohmann::json::object();  ///< kind, origin, path, sha256
  std::string model_file;
  std::string camera;
  /// the cameras of --camera, one --camera value each (CameraText): a list, since a free
  /// camera's own commas make the comma string above ambiguous to split
  std::vector<std::string> cameras;
  /// --obs-camera: the dataset's images, {"size": [W, H], "layers", "overlay", "cameras":
  /// [{"name", "camera"}]}; null without images
  nlohmann::json obs;
  std::string overlay;
  int msaa = 0;  ///< the samples used
  std::string msaa_reason;
  ManifestBackend backend;          ///< name, device, gl_vendor...
  std::vector<std::string> layers;  ///< "rgb" and the --layers
  ManifestVideo video;              ///< codec, crf, fps, width, formats...
  nlohmann::json versions = nlohmann::json::object();
  ManifestTimings timings_s;
  long frames = 0;
  bool interrupted = false;
  std::vector<int> incomplete_episodes;
  std::optional<std::string> signal;  ///< "SIGINT", "SIGTERM"; null: none
  std::string command_line;
  RunParameters parameters;  ///< parameters.recorded is false when the file has none
  bool resumed = false;
  bool merged = false;                              ///< written by merge-manifests
  nlohmann::json shards = nlohmann::json::array();  ///< merged: each shard's record
  nlohmann::json extra = nlohmann::json::object();  ///< members not known here, kept

  bool operator==(const Manifest& o) const;
  bool operator!=(const Manifest& o) const { return !(*this == o); }
};

/// The manifest as JSON (the writer). Writes the current schema version.
nlohmann::json ManifestToJson(const Manifest& manifest);
/// A manifest from JSON (the reader). Throws ManifestError, without a file name, for what is not a
/// record manifest (not an object, no env_id or episodes, a member of the wrong type) and for a
/// schema version newer than kManifestSchemaVersion.
Manifest ManifestFromJson(const nlohmann::json& json);

/// An episode entry as JSON, and back (ManifestEpisode's part of the reader and writer).
nlohmann::json ManifestEpisodeToJson(const ManifestEpisode& episode);
/// Throws ManifestError for an entry without an integer index or a member of the wrong type.
ManifestEpisode ManifestEpisodeFromJson(const nlohmann::json& json);

/// Reads the manifest file at `path`. Throws ManifestError naming the file when it cannot be read,
/// is not JSON, is not a record manifest or has a newer schema version ("'PATH' has manifest schema
/// version 2; this fetchscope reads versions 0 to 1: use a newer fetchscope"), and UsageError when
/// it is not a regular file or holds more than kMaxJsonFileBytes (base/confined_file.h). Messages
/// name the file and the byte where its JSON breaks, never its bytes.
Manifest ReadManifest(const std::filesystem::path& path);
/// Writes `manifest` to `path` atomically, as DumpJson writes JSON (two-space indent, newline).
void WriteManifest(const std::filesystem::path& path, const Manifest& manifest);

}  // namespace fetchscope
