// The manifest's typed sections: "video" (how the files were encoded), "backend" (the GL setup),
// "gpu" (the device request and choice), "workers" (each worker's setup and episodes) and
// "timings_s" (where the time went). Part of the one manifest reader and writer (run/manifest.h).
//
// Each member is optional: a section says what the manifest says (older manifests say less) and is
// written back with exactly those members. A member is read into its field only when writing the
// field back gives the very same JSON text (a 1 where a 1.0 is expected stays as it was); members
// this build does not know, or of another type, are kept in `extra` and written back unchanged.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "encode/episode_result.h"

namespace fetchscope {

/// "video"."gif": the GIF's frame rate and width.
struct ManifestVideoGif {
  std::optional<int> fps;
  std::optional<int> width;
  nlohmann::json extra = nlohmann::json::object();
  bool operator==(const ManifestVideoGif& o) const;
};

/// "video": the encoder of each format's files and the settings of the run.
struct ManifestVideo {
  std::optional<std::string> codec;  ///< every format's codec in --format order: "libx264, gif"
  std::optional<std::map<std::string, std::string>> codecs;  ///< format -> codec
  std::optional<std::string> codec_reason;
  std::optional<int> crf;
  std::optional<std::string> preset;
  std::optional<int> fps;
  std::optional<int> width;
  std::optional<int> height;
  std::optional<int> encoded_width;
  std::optional<int> encoded_height;
  std::optional<int> encoder_threads;
  std::optional<std::string> x264_params;
  std::optional<int> encoders_per_worker;
  std::optional<std::string> container;             ///< the first format
  std::optional<std::vector<std::string>> formats;  ///< --format, in order
  std::optional<ManifestVideoGif> gif;
  std::optional<std::string> pix_fmt;
  nlohmann::json extra = nlohmann::json::object();  ///< members not known here
  bool operator==(const ManifestVideo& o) const;
};

/// "backend": the GL setup of the first worker that started.
struct ManifestBackend {
  std::optional<std::string> name;  ///< "egl", "osmesa"
  std::optional<std::string> device;
  std::optional<std::string> gl_vendor;
  std::optional<std::string> gl_renderer;
  std::optional<std::string> gl_version;
  nlohmann::json extra = nlohmann::json::object();
  bool operator==(const ManifestBackend& o) const;
};

/// "gpu": the --gpu request, the choice made and the EGL devices chosen.
struct ManifestGpu {
  std::optional<std::string> request;
  std::optional<std::string> choice;
  std::optional<std::vector<int>> devices;
  nlohmann::json extra = nlohmann::json::object();
  bool operator==(const ManifestGpu& o) const;
};

/// One of "workers": what the worker's runner reported when it started (its GL setup), and the
/// episodes it recorded. A worker that reported nothing has its index and episodes alone.
struct ManifestWorker {
  std::optional<int> worker;  ///< 0-based
  std::optional<long> pid;
  std::optional<std::string> backend;
  std::optional<std::string> device;
  std::optional<std::string> device_selection;
  std::optional<std::string> gl_vendor;
  std::optional<std::string> gl_renderer;
  std::optional<std::string> gl_version;
  std::optional<int> msaa;  ///< the samples used
  std::optional<std::string> msaa_reason;
  std::optional<std::string> readback;
  std::optional<std::vector<int>> episodes;
  nlohmann::json extra = nlohmann::json::object();
  bool operator==(const ManifestWorker& o) const;
};

/// "timings_s": seconds by phase (summed over episodes but wall), and the CPU account.
struct ManifestTimings {
  std::optional<double> wall;      ///< the run's wall-clock time (merged: the slowest shard's)
  std::optional<double> wall_sum;  ///< merged: the shards' wall times summed
  std::optional<double> sim;
  std::optional<double> render;
  std::optional<double> encode;
  std::optional<double> write;
  std::optional<std::map<std::string, double>> cpu_s;             ///< CPU seconds by stage
  std::optional<std::map<std::string, double>> cpu_ms_per_frame;  ///< the same per frame, in ms
  nlohmann::json extra = nlohmann::json::object();
  bool operator==(const ManifestTimings& o) const;
};

/// Each section as JSON (the writer's part) and back (the reader's). The readers throw
/// ManifestError for a section that is not an object ("workers": not an array of objects).
nlohmann::json ManifestVideoToJson(const ManifestVideo& video);
ManifestVideo ManifestVideoFromJson(const nlohmann::json& json);
nlohmann::json ManifestBackendToJson(const ManifestBackend& backend);
ManifestBackend ManifestBackendFromJson(const nlohmann::json& json);
nlohmann::json ManifestGpuToJson(const ManifestGpu& gpu);
ManifestGpu ManifestGpuFromJson(const nlohmann::json& json);
nlohmann::json ManifestWorkerToJson(const ManifestWorker& worker);
ManifestWorker ManifestWorkerFromJson(const nlohmann::json& json);
nlohmann::json ManifestWorkersToJson(const std::vector<ManifestWorker>& workers);
std::vector<ManifestWorker> ManifestWorkersFromJson(const nlohmann::json& json);
nlohmann::json ManifestTimingsToJson(const ManifestTimings& timings);
ManifestTimings ManifestTimingsFromJson(const nlohmann::json& json);
/// An episode entry's "hindsight" (EpisodeHindsight), the same way.
nlohmann::json EpisodeHindsightToJson(const EpisodeHindsight& hindsight);
EpisodeHindsight EpisodeHindsightFromJson(const nlohmann::json& json);

}  // namespace fetchscope
