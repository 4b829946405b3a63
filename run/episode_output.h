// What receives a run's finished episodes: one interface, fed by record (the run folder's
// episodes, after the run), rollout (each episode as the scheduler reports it) and export (a
// run folder or trajectory file). The Minari dataset (run/minari_output.h) is one output; every
// command that writes one goes through it, so a dataset's options are made in one place.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "src/env_spec.h"
#include "src/episode.h"
#include "src/trajectory.h"

namespace fetchscope {

/// The run whose episodes an output receives, as the command resolved it: what an output
/// describes its episodes with (a dataset's metadata) before the first one arrives.
struct OutputRun {
  std::string command;            ///< the command that made them: "record", "rollout", "export"
  const EnvSpec* spec = nullptr;  ///< the env they come from
  uint64_t seed = 0;              ///< episode 0's reset seed (the others continue its generator)
  std::string seed_text;          ///< the seed as the user gave it
  std::string policy;             ///< the policy as given ("" when unknown)
  int episodes = 0;               ///< the episodes asked for (--episodes)
  int steps = 0;                  ///< the TimeLimit they ran under (--steps)
  std::string source;             ///< export: the run folder or file exported ("" otherwise)
  /// record --from DATASET: each episode's own reset seed (nullopt: none), by index, which the
  /// new dataset keeps; empty otherwise (episode 0 has `seed`, the others continue it)
  std::map<int, std::optional<uint64_t>> episode_seeds;
};

/// Receives finished episodes, in episode order (ascending index), between Begin and Finish.
/// What it writes appears under its final name by Finish, complete, or not at all: Abort, a
/// throw from any call, and destruction before Finish leave nothing of it under that name (an
/// older output of that name stays as it was). Add and Finish throw MinariInterrupted
/// (dataset/minari_writer.h: a RunError with the signal) where SIGINT/SIGTERM asked to stop.
class EpisodeOutput {
 public:
  virtual ~EpisodeOutput() = default;
  /// Before the first episode: checks the destination and opens what is written, under a
  /// temporary name. Throws UsageError/RunError naming the destination.
  virtual void Begin(const OutputRun& run) = 0;
  /// The next finished episode: its index is above every one added before it.
  virtual void Add(const EpisodeRecord& episode) = 0;
  /// Every episode added: puts the output in place under its final name, and returns that name.
  virtual std::string Finish() = 0;
  /// Drops what was written; nothing is left under the final name. Safe to call at any point.
  virtual void Abort() = 0;
  /// Before Finish: which of the run's episodes were kept and why (--keep successful), stored
  /// with the output ({"keep", "tried", "kept", "seed", "episodes": [run indices]}).
  virtual void SetSelection(const nlohmann::json& selection) { (void)selection; }
};

/// Which of a run's episodes an output holds, and why: --keep successful (only the episodes whose
/// last step is a success go on, renumbered in order) and a shard of the run (--shard I/N). Where
/// either applies, Finish tells `inner` (SetSelection): {"keep": "all" | "successful", "shard":
/// [I, N] (sharded only), "run": {"env_id", "seed", "policy", "steps", "episodes"}, "tried",
/// "kept", "seed", "episodes": [the kept episodes' run indices]}, which merge-datasets reads to put
/// shards back together. Refuses to write an output of no episode.
class SelectedEpisodes : public EpisodeOutput {
 public:
  SelectedEpisodes(EpisodeOutput& inner, bool keep_successful, int shard_index, int shard_count)
      : inner_(inner),
        keep_successful_(keep_successful),
        shard_index_(shard_index),
        shard_count_(shard_count) {}
  void Begin(const OutputRun& run) override;
  void Add(const EpisodeRecord& episode) override;
  std::string Finish() override;
  void Abort() override { inner_.Abort(); }
  int tried() const { return tried_; }                    ///< episodes offered
  const std::vector<int>& kept() const { return kept_; }  ///< their run indices

 private:
  EpisodeOutput& inner_;
  bool keep_successful_;
  int shard_index_, shard_count_;
  nlohmann::json run_;
  uint64_t seed_ = 0;
  int tried_ = 0;
  std::vector<int> kept_;
};

/// Episodes that finish in any order (the scheduler reports them as workers finish), handed to
/// an output in the run's order: each is added as soon as those before it are. After the output
/// is interrupted (MinariInterrupted) it takes nothing more and remembers the signal; the run
/// ends as interrupted.
class EpisodesInOrder {
 public:
  /// `order`: the run's episode indices, ascending; `output` already begun.
  EpisodesInOrder(std::vector<int> order, EpisodeOutput& output)
      : order_(std::move(order)), output_(output) {}

  /// Episode `episode.index` finished.
  void Done(EpisodeRecord episode);

  bool stopped() const { return stopped_; }  ///< the output was interrupted while adding
  size_t added() const { return next_; }     ///< episodes handed to the output

 private:
  std::vector<int> order_;
  EpisodeOutput& output_;
  size_t next_ = 0;  // order_[next_] is the next episode to add
  std::map<int, EpisodeRecord> pending_;
  bool stopped_ = false;
};

/// The steps of `trajectory`'s longest episode: the TimeLimit of a run whose episodes were all
/// played to their end (export's, which knows no --steps).
int LongestEpisodeSteps(const Trajectory& trajectory);

/// `trajectory`'s episodes, in index order, through `output`: Begin(run), Add each, Finish.
/// Returns Finish's name; throws as those do (the output aborted, nothing left). `on_episode`,
/// if set, is called after each episode is added (progress).
std::string WriteEpisodes(const Trajectory& trajectory, const OutputRun& run, EpisodeOutput& output,
                          const std::function<void()>& on_episode = {});

}  // namespace fetchscope
