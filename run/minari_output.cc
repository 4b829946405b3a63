#include "run/minari_output.h"

#include "base/errors.h"
#include "dataset/minari_trajectory.h"
#include "src/observation_layout.h"

namespace fetchscope {

MinariWriteOptions MinariOptionsFor(const MinariRequest& request, const OutputRun& run) {
  MinariWriteOptions o;
  o.dataset_id = request.dataset_id;
  o.root = request.root;
  o.overwrite = request.overwrite;
  o.spec = run.spec;
  o.algorithm_name = run.policy.empty() ? "unknown" : run.policy;
  if (!request.author.empty()) o.author = request.author;
  o.author_email = request.author_email;
  o.max_episode_steps = run.steps;  // gym.make(id, max_episode_steps=--steps)
  o.pixels = request.pixels;
  const std::string version = "fetchscope " FETCHSCOPE_VERSION " ";
  if (run.command == "export") {
    o.code_permalink = version + "export " + run.source;
  } else {  // one shape for rollout and record, without the binary's path or --jobs
    o.code_permalink = version + run.command + " --env-id " + run.spec->id + " --policy " +
                       run.policy + " --seed " + std::to_string(run.seed) + " --episodes " +
                       std::to_string(run.episodes) + " --steps " + std::to_string(run.steps);
  }
  o.description =
      run.command == "rollout"
          ? run.spec->id + " episodes played by fetchscope's " + o.algorithm_name + " policy"
          : run.spec->id + " episodes recorded by fetchscope (policy " + o.algorithm_name +
                ", seed " + run.seed_text + ")";
  return o;
}

void CheckMinariOutput(const MinariRequest& request, const OutputRun& run) {
  CheckMinariDestination(MinariOptionsFor(request, run));
}

void MinariOutput::Begin(const OutputRun& run) {
  writer_.reset();
  writer_ = std::make_unique<MinariWriter>(MinariOptionsFor(request_, run));
  seed_ = run.seed;
  episode_seeds_ = run.episode_seeds;
  width_ = ObservationSize(run.spec->has_object);
}

void MinariOutput::Add(const EpisodeRecord& episode) {
  if (!writer_) throw RunError("Minari dataset '" + request_.dataset_id + "': not begun");
  // episode 0 was reset with the run's seed; the others continued its generator
  std::optional<uint64_t> seed = episode.index == 0 ? std::optional<uint64_t>(seed_) : std::nullopt;
  if (const auto own = episode_seeds_.find(episode.index); own != episode_seeds_.end()) {
    seed = own->second;  // a re-rendered dataset's episodes keep their own seeds
  }
  const MinariEpisode e = ToMinariEpisode(episode, seed, width_);
  if (!request_.pixels) {
    writer_->Add(e);
    return;
  }
  const std::filesystem::path staged = StagingFileOf(request_.staging, episode.index);
  const StagedEpisode images = LoadStagedEpisode(staged, *request_.pixels, e.steps() + 1);
  writer_->Add(e, &images);
}

void MinariOutput::SetSelection(const nlohmann::json& selection) {
  if (writer_) writer_->SetSelection(selection);
}

std::string MinariOutput::Finish() {
  if (!writer_) throw RunError("Minari dataset '" + request_.dataset_id + "': not begun");
  written_ = writer_->Commit().string();
  writer_.reset();
  return written_;
}

}  // namespace fetchscope
