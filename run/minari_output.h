// The Minari dataset as an EpisodeOutput (run/episode_output.h): the one place that turns a
// command's --minari options and its run into the writer's options (dataset/minari_writer.h),
// for record --minari, rollout --minari and export alike.
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "dataset/minari_writer.h"
#include "dataset/pixel_obs.h"
#include "run/episode_output.h"

namespace fetchscope {

/// Where a dataset goes and who made it, as the command's options give it.
struct MinariRequest {
  std::string dataset_id;      ///< --minari, e.g. "fetchscope/FetchPush/scripted-v0"
  std::filesystem::path root;  ///< MinariRoot(--minari-root)
  bool overwrite = false;      ///< --overwrite: replace an existing dataset of that id
  std::string author;          ///< --minari-author ("": "fetchscope")
  std::string author_email;    ///< --minari-author-email ("": none)
  /// --obs-camera: the images each episode's staging file holds (run/pixel_recorder.h), in
  /// the folder `staging`; null: state only
  const PixelLayout* pixels = nullptr;
  std::filesystem::path staging;
};

/// The writer's options for `run`'s episodes: the metadata's algorithm (the policy, "unknown"
/// when none), description, code_permalink and max_episode_steps (the run's steps). The
/// code_permalink of rollout and record has one shape: "fetchscope VERSION COMMAND --env-id ID
/// --policy P --seed S --episodes N --steps T" (the options that shape the data, resolved; not
/// the binary's path, --jobs or output folders, which do not); export's names what it exported.
MinariWriteOptions MinariOptionsFor(const MinariRequest& request, const OutputRun& run);

/// Checks `request`'s destination for `run` now, before a long run (CheckMinariDestination:
/// UsageError for an existing id without --overwrite, RunError for an unwritable folder).
void CheckMinariOutput(const MinariRequest& request, const OutputRun& run);

/// Writes the episodes as the Minari dataset `request` names (MinariWriter): under a hidden
/// temporary folder from Begin, renamed into place by Finish. Episode 0 is stored with the
/// run's seed, the others (which continue its generator) without one.
class MinariOutput : public EpisodeOutput {
 public:
  explicit MinariOutput(MinariRequest request) : request_(std::move(request)) {}
  void Begin(const OutputRun& run) override;
  void Add(const EpisodeRecord& episode) override;
  std::string Finish() override;
  void Abort() override { writer_.reset(); }
  void SetSelection(const nlohmann::json& selection) override;

  const MinariRequest& request() const { return request_; }
  /// The dataset's folder, once Finish has put it in place ("" before).
  const std::string& written() const { return written_; }

 private:
  MinariRequest request_;
  std::unique_ptr<MinariWriter> writer_;  // between Begin and Finish
  std::string written_;
  uint64_t seed_ = 0;
  std::map<int, std::optional<uint64_t>> episode_seeds_;  // OutputRun::episode_seeds
  int width_ = 0;                                         // observation values per row
};

}  // namespace fetchscope
