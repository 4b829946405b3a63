// The robomimic file of --robomimic as an EpisodeOutput (run/episode_output.h): each episode's
// state fields from its trajectory, its images and MuJoCo states from the workers' staging
// files (run/pixel_recorder.h), written by dataset/robomimic_writer.h.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "dataset/robomimic_writer.h"
#include "run/episode_output.h"

namespace fetchscope {

/// Where the file goes and what it holds, as the command's options give it.
struct RobomimicRequest {
  std::filesystem::path file;           ///< --robomimic
  bool overwrite = false;               ///< --overwrite
  bool next_obs = true;                 ///< not --no-next-obs
  double valid_fraction = 0;            ///< --valid-fraction
  const PixelLayout* pixels = nullptr;  ///< the staged layout (states always)
  std::filesystem::path staging;        ///< the staging folder
};

/// Checks the destination now, before a long run (CheckRobomimicDestination).
void CheckRobomimicOutput(const RobomimicRequest& request);

/// Writes the episodes as robomimic's layout.
class RobomimicOutput : public EpisodeOutput {
 public:
  explicit RobomimicOutput(RobomimicRequest request) : request_(std::move(request)) {}
  void Begin(const OutputRun& run) override;
  void Add(const EpisodeRecord& episode) override;
  std::string Finish() override;
  void Abort() override { writer_.reset(); }
  void SetSelection(const nlohmann::json& selection) override {
    if (writer_) writer_->SetSelection(selection);
  }

 private:
  RobomimicRequest request_;
  std::unique_ptr<RobomimicWriter> writer_;
  int width_ = 0;
};

/// Several outputs as one (--minari and --robomimic together): each call goes to each in turn;
/// Finish finishes them in order and returns their names joined by ", " (one that fails after
/// another finished leaves the first in place: the error says which).
class EpisodeOutputs : public EpisodeOutput {
 public:
  explicit EpisodeOutputs(std::vector<EpisodeOutput*> outputs) : outputs_(std::move(outputs)) {}
  void Begin(const OutputRun& run) override;
  void Add(const EpisodeRecord& episode) override;
  std::string Finish() override;
  void Abort() override;
  void SetSelection(const nlohmann::json& selection) override {
    for (EpisodeOutput* o : outputs_) o->SetSelection(selection);
  }

 private:
  std::vector<EpisodeOutput*> outputs_;
};

}  // namespace fetchscope
