// The EpisodeOutput interface (run/episode_output.h) and its Minari dataset (run/minari_output.h):
// episodes arrive in episode order whatever order they finish in, a dataset appears under its
// final name only by Finish, and Abort, a throw or destruction leave nothing under that name (an
// older dataset of the id stays as it was); the one builder of the writer's options says what
// each command's dataset metadata holds.
#include "run/episode_output.h"

#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "base/errors.h"
#include "dataset/minari_reader.h"
#include "dataset/minari_writer.h"
#include "run/minari_output.h"
#include "src/env_spec.h"
#include "src/observation_layout.h"
#include "src/trajectory.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

const EnvSpec& Reach() { return FindEnvSpec("FetchReach-v4"); }

// episode `index` of `steps` steps; observation[0] of row t is index + t / 100, so that each row
// says which episode it came from
EpisodeRecord MakeEpisode(int index, int steps) {
  EpisodeRecord e;
  e.index = index;
  for (int t = 0; t <= steps; ++t) {
    StepRecord s;
    s.t = t;
    s.obs.observation.assign(ObservationSize(false), 0.25);
    s.obs.observation[0] = index + t / 100.0;
    s.obs.achieved_goal = {1, 2, 3};
    s.obs.desired_goal = {1, 2, 3.5};
    if (t > 0) {
      s.action = Action{};
      s.action->value = {0.5, -0.5, 2.0, 0};  // 2.0 is stored clipped to 1
      s.reward = -1.0 * index;
    }
    e.steps.push_back(s);
  }
  return e;
}

OutputRun RolloutRun(int steps = 5) {
  OutputRun run;
  run.command = "rollout";
  run.spec = &Reach();
  run.seed = 42;
  run.seed_text = "42";
  run.policy = "random";
  run.episodes = 3;
  run.steps = steps;
  return run;
}

MinariRequest Request(const fs::path& root, const std::string& id = "ns/out-v0") {
  MinariRequest request;
  request.dataset_id = id;
  request.root = root;
  return request;
}

// everything in `folder` and below, as relative paths
std::vector<std::string> Listing(const fs::path& folder) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& entry : fs::recursive_directory_iterator(folder, ec)) {
    out.push_back(fs::relative(entry.path(), folder).string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// An output that records what it was given, and throws where told to.
class Recorder : public EpisodeOutput {
 public:
  void Begin(const OutputRun& run) override { calls.push_back("begin " + run.command); }
  void Add(const EpisodeRecord& episode) override {
    if (static_cast<int>(added.size()) == throw_at) {
      if (interrupt) throw MinariInterrupted(SIGINT, "interrupted (SIGINT)");
      throw RunError("disk full");
    }
    added.push_back(episode.index);
    calls.push_back("add " + std::to_string(episode.index));
  }
  std::string Finish() override {
    calls.push_back("finish");
    return "done";
  }
  void Abort() override { calls.push_back("abort"); }

  std::vector<int> added;
  std::vector<std::string> calls;
  int throw_at = -1;  // Add throws when this many episodes were added
  bool interrupt = false;
};

TEST(EpisodeOutputTest, EpisodesArriveInEpisodeOrderWhateverOrderTheyFinish) {
  Recorder out;
  EpisodesInOrder in_order({0, 1, 2, 5}, out);
  in_order.Done(MakeEpisode(2, 1));
  in_order.Done(MakeEpisode(5, 1));
  EXPECT_TRUE(out.added.empty());  // episode 0 is not there yet
  in_order.Done(MakeEpisode(0, 1));
  EXPECT_EQ(out.added, (std::vector<int>{0}));
  in_order.Done(MakeEpisode(1, 1));
  EXPECT_EQ(out.added, (std::vector<int>{0, 1, 2, 5}));
  EXPECT_EQ(in_order.added(), 4u);
  EXPECT_FALSE(in_order.stopped());
}

TEST(EpisodeOutputTest, AnInterruptedOutputTakesNothingMore) {
  Recorder out;
  out.throw_at = 1;
  out.interrupt = true;
  EpisodesInOrder in_order({0, 1, 2}, out);
  in_order.Done(MakeEpisode(0, 1));
  in_order.Done(MakeEpisode(1, 1));  // interrupted here
  EXPECT_TRUE(in_order.stopped());
  out.throw_at = -1;
  in_order.Done(MakeEpisode(2, 1));
  EXPECT_EQ(out.added, (std::vector<int>{0}));
  EXPECT_EQ(in_order.added(), 1u);
}

TEST(EpisodeOutputTest, AnOtherFailureOfTheOutputIsThrown) {
  Recorder out;
  out.throw_at = 0;
  EpisodesInOrder in_order({0}, out);
  EXPECT_THROW(in_order.Done(MakeEpisode(0, 1)), RunError);
  EXPECT_FALSE(in_order.stopped());
}

TEST(EpisodeOutputTest, WriteEpisodesSortsByIndexAndAbortsOnAThrow) {
  Trajectory t;
  t.env_id = Reach().id;
  t.episodes = {MakeEpisode(3, 2), MakeEpisode(0, 4), MakeEpisode(1, 1)};
  EXPECT_EQ(LongestEpisodeSteps(t), 4);
  Recorder out;
  EXPECT_EQ(WriteEpisodes(t, RolloutRun(), out), "done");
  EXPECT_EQ(out.calls,
            (std::vector<std::string>{"begin rollout", "add 0", "add 1", "add 3", "finish"}));
  Recorder failing;
  failing.throw_at = 2;
  EXPECT_THROW(WriteEpisodes(t, RolloutRun(), failing), RunError);
  EXPECT_EQ(failing.calls, (std::vector<std::string>{"begin rollout", "add 0", "add 1", "abort"}));
}

TEST(MinariOutputTest, FinishPutsTheEpisodesInOrderUnderTheFinalName) {
  TempDir tmp;
  MinariOutput out(Request(tmp.path()));
  out.Begin(RolloutRun(7));
  EXPECT_FALSE(fs::exists(tmp.path() / "ns/out-v0"));  // written under a temporary name
  for (int k : {0, 1, 2}) out.Add(MakeEpisode(k, 3 + k));
  EXPECT_FALSE(fs::exists(tmp.path() / "ns/out-v0"));
  const std::string path = out.Finish();
  EXPECT_EQ(fs::path(path), tmp.path() / "ns/out-v0");
  const MinariDataset d = ReadMinariDataset("ns/out-v0", tmp.path());
  ASSERT_EQ(d.episodes.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    const MinariEpisode& e = d.episodes[k];
    EXPECT_EQ(e.id, k);
    EXPECT_EQ(e.steps(), 3 + k);
    EXPECT_DOUBLE_EQ(e.observation[0], k);  // episode k's first row
    EXPECT_EQ(e.actions[2], 1.0f);          // clipped to the action space
    // only episode 0 was reset with the run's seed; the others continued its generator
    EXPECT_EQ(e.seed, k == 0 ? std::optional<uint64_t>(42) : std::nullopt);
  }
  EXPECT_EQ(d.metadata.max_episode_steps, 7);
  EXPECT_EQ(d.metadata.algorithm_name, "random");
  // nothing else is left beside it: no temporary folder
  EXPECT_EQ(Listing(tmp.path() / "ns"),
            (std::vector<std::string>{"namespace_metadata.json", "out-v0", "out-v0/data",
                                      "out-v0/data/main_data.hdf5", "out-v0/data/metadata.json"}));
}

TEST(MinariOutputTest, AbortLeavesNoDatasetOfTheFinalName) {
  TempDir tmp;
  MinariOutput out(Request(tmp.path()));
  out.Begin(RolloutRun());
  out.Add(MakeEpisode(0, 3));
  out.Add(MakeEpisode(1, 3));
  out.Abort();
  EXPECT_FALSE(fs::exists(tmp.path() / "ns/out-v0"));
  EXPECT_EQ(Listing(tmp.path()), std::vector<std::string>{});  // nor its folders or temp files
  EXPECT_THROW(out.Finish(), RunError);                        // nothing begun any more
}

TEST(MinariOutputTest, DestructionBeforeFinishLeavesNothing) {
  TempDir tmp;
  {
    MinariOutput out(Request(tmp.path()));
    out.Begin(RolloutRun());
    out.Add(MakeEpisode(0, 3));
  }
  EXPECT_EQ(Listing(tmp.path()), std::vector<std::string>{});
}

TEST(MinariOutputTest, AnAbortedOverwriteKeepsTheOldDataset) {
  TempDir tmp;
  Trajectory old;
  old.env_id = Reach().id;
  old.seed = 42;
  old.episodes = {MakeEpisode(0, 2)};
  MinariOutput first(Request(tmp.path()));
  WriteEpisodes(old, RolloutRun(), first);
  const std::string before = testing::ReadFile(tmp.path() / "ns/out-v0/data/main_data.hdf5");

  MinariRequest again = Request(tmp.path());
  MinariOutput refused(again);
  EXPECT_THROW(refused.Begin(RolloutRun()), UsageError);  // exists, no --overwrite

  again.overwrite = true;
  MinariOutput out(again);
  out.Begin(RolloutRun());
  out.Add(MakeEpisode(0, 5));
  out.Abort();
  EXPECT_EQ(testing::ReadFile(tmp.path() / "ns/out-v0/data/main_data.hdf5"), before);
  EXPECT_EQ(ReadMinariDataset("ns/out-v0", tmp.path()).episodes.at(0).steps(), 2);
}

TEST(MinariOutputTest, AnEpisodeBeforeBeginOrOfTheWrongWidthIsRefused) {
  TempDir tmp;
  MinariOutput out(Request(tmp.path()));
  EXPECT_THROW(out.Add(MakeEpisode(0, 1)), RunError);  // before Begin
  out.Begin(RolloutRun());
  out.Add(MakeEpisode(0, 1));
  EpisodeRecord wide = MakeEpisode(1, 1);
  wide.steps[1].obs.observation.push_back(0);  // not the env's observation width
  EXPECT_THROW(out.Add(wide), RunError);
  out.Abort();
  EXPECT_EQ(Listing(tmp.path()), std::vector<std::string>{});
}

// The one place the writer's options are made: what each command's dataset says of its run.
TEST(MinariOutputTest, TheOptionsOfEachCommandsDataset) {
  MinariRequest request = Request("/datasets", "fetchscope/FetchReach/x-v0");
  request.author = "Ada";
  request.author_email = "ada@example.org";
  request.overwrite = true;
  OutputRun run = RolloutRun(30);
  MinariWriteOptions o = MinariOptionsFor(request, run);
  EXPECT_EQ(o.dataset_id, "fetchscope/FetchReach/x-v0");
  EXPECT_EQ(o.root, fs::path("/datasets"));
  EXPECT_TRUE(o.overwrite);
  EXPECT_EQ(o.spec, &Reach());
  EXPECT_EQ(o.author, "Ada");
  EXPECT_EQ(o.author_email, "ada@example.org");
  EXPECT_EQ(o.algorithm_name, "random");
  EXPECT_EQ(o.max_episode_steps, 30);
  EXPECT_EQ(o.code_permalink, "fetchscope " FETCHSCOPE_VERSION
                              " rollout --env-id FetchReach-v4 --policy random --seed 42 "
                              "--episodes 3 --steps 30");
  EXPECT_EQ(o.description, "FetchReach-v4 episodes played by fetchscope's random policy");

  run.command = "record";
  run.seed_text = "0x2a";  // the seed as given
  o = MinariOptionsFor(Request("/d"), run);
  EXPECT_EQ(o.author, "fetchscope");  // no --minari-author
  EXPECT_EQ(o.author_email, "");
  EXPECT_EQ(o.code_permalink, "fetchscope " FETCHSCOPE_VERSION
                              " record --env-id FetchReach-v4 --policy random --seed 42 "
                              "--episodes 3 --steps 30");
  EXPECT_EQ(o.description,
            "FetchReach-v4 episodes recorded by fetchscope (policy random, seed 0x2a)");

  run.command = "export";
  run.policy = "";  // a trajectory that does not say
  run.source = "out/run1";
  o = MinariOptionsFor(Request("/d"), run);
  EXPECT_EQ(o.algorithm_name, "unknown");
  EXPECT_EQ(o.code_permalink, "fetchscope " FETCHSCOPE_VERSION " export out/run1");
  EXPECT_EQ(o.description,
            "FetchReach-v4 episodes recorded by fetchscope (policy unknown, seed 0x2a)");
}

}  // namespace
}  // namespace fetchscope
