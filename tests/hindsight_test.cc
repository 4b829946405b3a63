// HER `future` relabelling (src/hindsight.h): bounds, distribution, determinism, rewards.
#include "src/hindsight.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

#include "src/assets.h"
#include "src/env_spec.h"
#include "src/fetch_env.h"

namespace fetchscope {
namespace {

double Dist(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                   (a[2] - b[2]) * (a[2] - b[2]));
}

// achieved goal at step i: (i * 0.011, 0, 0): 1.1 cm apart, so success (< 5 cm) iff |i - j| < 5
std::vector<std::array<double, 3>> Line(int steps) {
  std::vector<std::array<double, 3>> out;
  for (int i = 0; i <= steps; ++i) out.push_back({i * 0.011, 0, 0});
  return out;
}

HindsightEpisode Sample(const std::vector<std::array<double, 3>>& achieved,
                        const std::array<double, 3>& desired, uint64_t seed) {
  return SampleHindsight(
      achieved, desired, seed, kHindsightK,
      [](const auto& a, const auto& g) { return Dist(a, g) < 0.05 ? -0.0 : -1.0; },
      [](const auto& a, const auto& g) { return Dist(a, g) < 0.05; });
}

TEST(Hindsight, FutureIndicesLieAfterTheTransitionAndCoverTheRange) {
  const int T = 50;
  const auto achieved = Line(T);
  std::map<int, std::set<int>> seen;  // transition -> futures drawn over many seeds
  for (uint64_t seed = 0; seed < 200; ++seed) {
    const HindsightEpisode h = Sample(achieved, {9, 9, 9}, HindsightSeed(seed, 3));
    ASSERT_EQ(h.transitions.size(), static_cast<size_t>(T));
    for (int t = 0; t < T; ++t) {
      ASSERT_EQ(h.transitions[t].size(), static_cast<size_t>(kHindsightK));
      for (const HindsightGoal& g : h.transitions[t]) {
        ASSERT_GE(g.future, t + 1) << "t " << t;
        ASSERT_LE(g.future, T) << "t " << t;
        EXPECT_EQ(g.goal, achieved[g.future]);
        seen[t].insert(g.future);
      }
    }
  }
  // both ends of [t + 1, T] are reached
  for (int t : {0, 10, 40, 49}) {
    EXPECT_EQ(*seen[t].begin(), t + 1) << t;
    EXPECT_EQ(*seen[t].rbegin(), T) << t;
  }
  // the last transition can only relabel with the final achieved goal
  EXPECT_EQ(seen[T - 1], std::set<int>{T});
}

TEST(Hindsight, FutureIsUniform) {
  // transition 0 of a 10-step episode: futures 1..10, each about a tenth of the draws
  const auto achieved = Line(10);
  std::map<int, int> count;
  int n = 0;
  for (uint64_t seed = 0; seed < 2500; ++seed) {
    const HindsightEpisode h = Sample(achieved, {9, 9, 9}, seed);
    for (const HindsightGoal& g : h.transitions[0]) {
      ++count[g.future];
      ++n;
    }
  }
  ASSERT_EQ(count.size(), 10u);
  for (const auto& [future, c] : count) {
    EXPECT_NEAR(static_cast<double>(c) / n, 0.1, 0.015) << "future " << future;
  }
}

TEST(Hindsight, SameSeedSameGoalsOtherEpisodeOtherGoals) {
  const auto achieved = Line(50);
  auto futures = [&](uint64_t seed) {
    std::vector<int> out;
    const HindsightEpisode h = Sample(achieved, {9, 9, 9}, seed);
    for (const auto& tr : h.transitions) {
      for (const auto& g : tr) out.push_back(g.future);
    }
    return out;
  };
  EXPECT_EQ(futures(HindsightSeed(7, 2)), futures(HindsightSeed(7, 2)));
  EXPECT_NE(futures(HindsightSeed(7, 2)), futures(HindsightSeed(7, 3)));
  EXPECT_NE(futures(HindsightSeed(7, 2)), futures(HindsightSeed(8, 2)));
  EXPECT_NE(HindsightSeed(0, 1), HindsightSeed(1, 0));
}

TEST(Hindsight, RewardsAreComputedAgainstTheNextAchievedGoal) {
  const int T = 30;
  const auto achieved = Line(T);  // 1.1 cm per step
  const HindsightEpisode h = Sample(achieved, {9, 9, 9}, 11);
  EXPECT_EQ(h.original_successes, 0);  // the desired goal is far away
  int successes = 0;
  for (int t = 0; t < T; ++t) {
    for (const HindsightGoal& g : h.transitions[t]) {
      // ag_{t+1} against the goal achieved at `future`: 1.1 |future - (t + 1)| cm
      const bool near = g.future - (t + 1) < 5;
      EXPECT_EQ(g.success, near) << t << " " << g.future;
      EXPECT_EQ(g.reward, near ? -0.0 : -1.0);
      successes += g.success;
    }
  }
  EXPECT_EQ(h.relabelled_successes, successes);
  // a failed episode still teaches: the final transition relabels with its own outcome
  EXPECT_GE(h.relabelled_successes, kHindsightK);
}

TEST(Hindsight, OriginalSuccessesCountTheEpisodesOwnGoal) {
  const auto achieved = Line(20);  // the goal where step 20 ends: steps 16..20 succeed
  const HindsightEpisode h = Sample(achieved, achieved[20], 1);
  EXPECT_EQ(h.original_successes, 5);  // transitions 15..19 reach steps 16..20
}

TEST(Hindsight, EmptyEpisodeHasNoTransitions) {
  const HindsightEpisode h = Sample(Line(0), {0, 0, 0}, 1);
  EXPECT_TRUE(h.transitions.empty());
  EXPECT_EQ(h.relabelled_successes, 0);
}

TEST(Hindsight, FetchRewardsMatchComputeReward) {
  FetchEnv env(FindEnvSpec("FetchPush-v4"), ResolveAssets("bundled"));
  const std::vector<std::array<double, 3>> achieved = {
      {1.3, 0.7, 0.42}, {1.31, 0.7, 0.42}, {1.4, 0.7, 0.42}};
  const HindsightEpisode h = SampleHindsight(
      achieved, {0, 0, 0}, 5, kHindsightK,
      [&](const auto& a, const auto& g) { return env.ComputeReward(a, g); },
      [&](const auto& a, const auto& g) { return env.IsSuccess(a, g); });
  for (int t = 0; t < 2; ++t) {
    for (const HindsightGoal& g : h.transitions[t]) {
      EXPECT_EQ(g.reward, env.ComputeReward(achieved[t + 1], g.goal));
      EXPECT_EQ(g.success, g.reward == 0.0);  // sparse: 0 on success, -1 otherwise
    }
  }
}

}  // namespace
}  // namespace fetchscope
