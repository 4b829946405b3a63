#include "run/episode_output.h"

#include <algorithm>

#include "base/errors.h"
#include "dataset/minari_writer.h"

namespace fetchscope {

void EpisodesInOrder::Done(EpisodeRecord episode) {
  if (stopped_) return;  // SIGINT/SIGTERM: the run ends as interrupted, the output unwritten
  const int index = episode.index;
  pending_.emplace(index, std::move(episode));
  while (next_ < order_.size()) {
    const auto it = pending_.find(order_[next_]);
    if (it == pending_.end()) break;
    try {
      output_.Add(it->second);
    } catch (const MinariInterrupted&) {  // the scheduler reports the signal when it returns
      stopped_ = true;
      pending_.clear();
      return;
    }
    pending_.erase(it);
    ++next_;
  }
}

int LongestEpisodeSteps(const Trajectory& trajectory) {
  int steps = 0;
  for (const TrajectoryEpisode& e : trajectory.episodes) {
    steps = std::max(steps, static_cast<int>(e.steps.size()) - 1);
  }
  return steps;
}

std::string WriteEpisodes(const Trajectory& trajectory, const OutputRun& run, EpisodeOutput& output,
                          const std::function<void()>& on_episode) {
  std::vector<const TrajectoryEpisode*> episodes;
  for (const TrajectoryEpisode& e : trajectory.episodes) episodes.push_back(&e);
  std::sort(
      episodes.begin(), episodes.end(),
      [](const TrajectoryEpisode* a, const TrajectoryEpisode* b) { return a->index < b->index; });
  try {
    output.Begin(run);
    for (const TrajectoryEpisode* e : episodes) {
      output.Add(*e);
      if (on_episode) on_episode();
    }
    return output.Finish();
  } catch (...) {
    output.Abort();
    throw;
  }
}

void SelectedEpisodes::Begin(const OutputRun& run) {
  seed_ = run.seed;
  run_ = {{"env_id", run.spec->id},
          {"seed", run.seed},
          {"policy", run.policy},
          {"steps", run.steps},
          {"episodes", run.episodes}};
  inner_.Begin(run);
}

void SelectedEpisodes::Add(const EpisodeRecord& episode) {
  ++tried_;
  if (keep_successful_ && (episode.steps.empty() || !episode.steps.back().is_success)) return;
  kept_.push_back(episode.index);
  inner_.Add(episode);
}

std::string SelectedEpisodes::Finish() {
  if (kept_.empty()) {
    throw RunError("--keep successful: none of the " + std::to_string(tried_) +
                   " episode(s) ended in success; nothing written");
  }
  if (keep_successful_ || shard_count_ > 1) {
    nlohmann::json selection = {{"keep", keep_successful_ ? "successful" : "all"}};
    if (shard_count_ > 1) selection["shard"] = {shard_index_, shard_count_};
    selection["run"] = run_;
    selection["tried"] = tried_;
    selection["kept"] = kept_.size();
    selection["seed"] = seed_;
    selection["episodes"] = kept_;
    inner_.SetSelection(selection);
  }
  return inner_.Finish();
}

}  // namespace fetchscope
