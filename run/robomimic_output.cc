#include "run/robomimic_output.h"

#include "base/errors.h"
#include "dataset/minari_trajectory.h"
#include "src/observation_layout.h"

namespace fetchscope {
namespace {

RobomimicWriteOptions OptionsFor(const RobomimicRequest& r, const OutputRun* run) {
  RobomimicWriteOptions o;
  o.file = r.file;
  o.overwrite = r.overwrite;
  o.next_obs = r.next_obs;
  o.valid_fraction = r.valid_fraction;
  o.pixels = r.pixels;
  if (run) {
    o.spec = run->spec;
    o.max_episode_steps = run->steps;
  }
  return o;
}

}  // namespace

void CheckRobomimicOutput(const RobomimicRequest& request) {
  CheckRobomimicDestination(OptionsFor(request, nullptr));
}

void RobomimicOutput::Begin(const OutputRun& run) {
  writer_.reset();
  writer_ = std::make_unique<RobomimicWriter>(OptionsFor(request_, &run));
  width_ = ObservationSize(run.spec->has_object);
}

void RobomimicOutput::Add(const EpisodeRecord& episode) {
  if (!writer_) throw RunError("robomimic file '" + request_.file.string() + "': not begun");
  const MinariEpisode e = ToMinariEpisode(episode, std::nullopt, width_);
  const StagedEpisode staged = LoadStagedEpisode(StagingFileOf(request_.staging, episode.index),
                                                 *request_.pixels, e.steps() + 1);
  writer_->Add(e, staged);
}

std::string RobomimicOutput::Finish() {
  if (!writer_) throw RunError("robomimic file '" + request_.file.string() + "': not begun");
  const std::string path = writer_->Commit().string();
  writer_.reset();
  return path;
}

void EpisodeOutputs::Begin(const OutputRun& run) {
  for (EpisodeOutput* o : outputs_) o->Begin(run);
}

void EpisodeOutputs::Add(const EpisodeRecord& episode) {
  for (EpisodeOutput* o : outputs_) o->Add(episode);
}

std::string EpisodeOutputs::Finish() {
  std::string names;
  for (EpisodeOutput* o : outputs_) names += (names.empty() ? "" : ", ") + o->Finish();
  return names;
}

void EpisodeOutputs::Abort() {
  for (EpisodeOutput* o : outputs_) o->Abort();
}

}  // namespace fetchscope
