// What one recorded episode produced (EpisodeResult): its manifest entry (ManifestEpisode: files,
// frames, outcome, layers, hindsight counts) and what the parent sums up without keeping per
// episode (the worker that recorded it, its timings and CPU account). The episode sink fills it
// (encode/episode_sink.h); it travels as JSON only over the worker channel (run/record_run.h's
// EpisodeResultToJson); the manifest (run/manifest.h) keeps the entry.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace fetchscope {

/// One format's file in "videos": the file and the frames in it (-1: not given).
struct VideoFile {
  std::string file;
  int frames = -1;
  bool operator==(const VideoFile& o) const { return file == o.file && frames == o.frames; }
};

/// An episode's extra video of record --layers ("depth", "segmentation").
struct EpisodeLayer {
  std::string video;                                  ///< the first format's file
  std::map<std::string, VideoFile> videos;            ///< format -> file
  std::string legend;                                 ///< segmentation: the legend file ("" none)
  nlohmann::json details = nlohmann::json::object();  ///< depth: "scales", "mapping"...
  bool operator==(const EpisodeLayer& o) const {
    return video == o.video && videos == o.videos && legend == o.legend && details == o.details;
  }
};

/// An episode entry's "hindsight": relabelled successes (of k per transition) against the
/// episode's own successful transitions. Members as the manifest has them (see
/// run/manifest_sections.h); `extra` keeps those not known here.
struct EpisodeHindsight {
  std::optional<int> relabelled_successes;
  std::optional<int> original_successes;
  std::optional<int> k;
  std::optional<int> transitions;
  nlohmann::json extra = nlohmann::json::object();
  bool operator==(const EpisodeHindsight& o) const {
    return relabelled_successes == o.relabelled_successes &&
           original_successes == o.original_successes && k == o.k && transitions == o.transitions &&
           extra == o.extra;
  }
};

/// One recorded episode: its files and outcome, as the manifest's "episodes" keeps it.
struct ManifestEpisode {
  int index = 0;
  std::string video;                        ///< the first format's file ("" not given)
  std::map<std::string, VideoFile> videos;  ///< format -> file (absent before --format)
  std::string sheet;                        ///< contact sheet file
  std::string trajectory;                   ///< trajectory JSON file
  std::optional<int> frames;                ///< frames rendered
  std::optional<int> steps;                 ///< steps taken
  std::optional<bool> complete;  ///< false: cut short by a signal; absent in older manifests
  std::optional<double> episode_return;             ///< "return"
  bool is_success = false;                          ///< at the last step
  std::map<std::string, EpisodeLayer> layers;       ///< record --layers, by layer name
  std::optional<EpisodeHindsight> hindsight;        ///< record's hindsight counts
  nlohmann::json extra = nlohmann::json::object();  ///< "divergence" and members not known here

  /// Complete: marked so, or (older manifests without the flag) with all `steps_per_episode`.
  bool IsComplete(int steps_per_episode) const {
    return complete.value_or(steps.value_or(-1) == steps_per_episode);
  }
  /// Every file name the entry holds (videos, sheet, trajectory, layer videos and legend), for
  /// reading or rewriting in place; empty names are skipped.
  std::vector<std::string*> Files();
  /// Every file name, read-only.
  std::vector<std::string> FileNames() const;

  bool operator==(const ManifestEpisode& o) const;
  bool operator!=(const ManifestEpisode& o) const { return !(*this == o); }
};

/// Where an episode's time went, on the worker: seconds by phase (the render thread's sim and
/// render, the sink's encode and write) and CPU seconds by stage (base/cpu_clock.h's CpuStages).
struct EpisodeTimings {
  double sim = 0;
  double render = 0;
  double encode = 0;
  double write = 0;
  std::map<std::string, double> cpu_s;
  bool operator==(const EpisodeTimings& o) const {
    return sim == o.sim && render == o.render && encode == o.encode && write == o.write &&
           cpu_s == o.cpu_s;
  }
};

/// What one episode produced: the entry the manifest keeps, and what the parent adds up.
struct EpisodeResult {
  ManifestEpisode entry;
  int worker = 0;          ///< the worker that recorded it (the manifest's "workers" lists it)
  EpisodeTimings timings;  ///< summed into the manifest's "timings_s"
  bool operator==(const EpisodeResult& o) const {
    return entry == o.entry && worker == o.worker && timings == o.timings;
  }
};

}  // namespace fetchscope
