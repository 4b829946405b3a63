// The scripted policies' trajectories (src/scripted_policy.cc): PickAndPlace carries the block
// without dropping and re-grasping it, Push stops once the block is in the goal.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "src/assets.h"
#include "src/env_spec.h"
#include "src/episode.h"
#include "src/fetch_env.h"
#include "src/policy.h"

namespace fetchscope {
namespace {

EpisodeRecord Play50(FetchEnv& env, Policy& policy, uint64_t seed) {
  return RunEpisode(env, policy, 0, seed, 50);
}

// How often the block's height turns from a fall of more than 1 cm back into a rise of more
// than 1 cm once it has left the table: a sawtooth (lift, dip, lift again) counts once per
// tooth; lifting, carrying and setting down count none.
int HeightReversals(const EpisodeRecord& e, double table_z) {
  int reversals = 0;
  bool lifted = false, falling = false;
  double peak = 0, trough = 0;
  for (const StepRecord& s : e.steps) {
    const double z = s.obs.achieved_goal[2];
    if (!lifted) {
      if (z < table_z + 0.01) continue;
      lifted = true;
      peak = z;
    }
    if (!falling) {
      peak = std::max(peak, z);
      if (peak - z > 0.01) {
        falling = true;
        trough = z;
      }
    } else {
      trough = std::min(trough, z);
      if (z - trough > 0.01) {
        ++reversals;
        falling = false;
        peak = z;
      }
    }
  }
  return reversals;
}

TEST(ScriptedPolicy, PickAndPlaceCarriesTheBlockSmoothly) {
  const EnvSpec& spec = FindEnvSpec("FetchPickAndPlace-v4");
  FetchEnv env(spec, ResolveAssets("bundled"));
  PolicyContext context;
  auto policy = MakePolicy(PolicySpec::Scripted(), spec, context);
  int successes = 0;
  for (uint64_t seed = 0; seed < 20; ++seed) {
    const EpisodeRecord e = Play50(env, *policy, seed);
    const double table_z = env.height_offset();
    std::ostringstream z;
    for (const auto& s : e.steps) z << s.obs.achieved_goal[2] << " ";
    // held blocks move up and sideways; they never fall back by centimetres between steps
    EXPECT_EQ(HeightReversals(e, table_z), 0) << "seed " << seed << ": z " << z.str();
    successes += e.steps.back().is_success;
  }
  EXPECT_GE(successes, 14);
}

TEST(ScriptedPolicy, PushStopsOnceItSucceeds) {
  const EnvSpec& spec = FindEnvSpec("FetchPush-v4");
  FetchEnv env(spec, ResolveAssets("bundled"));
  PolicyContext context;
  auto policy = MakePolicy(PolicySpec::Scripted(), spec, context);
  int succeeded = 0;
  for (uint64_t seed = 0; seed < 20; ++seed) {
    const EpisodeRecord e = Play50(env, *policy, seed);
    int first = -1;
    for (size_t t = 0; t < e.steps.size(); ++t) {
      if (e.steps[t].is_success) {
        first = static_cast<int>(t);
        break;
      }
    }
    if (first < 0) continue;
    ++succeeded;
    // every action taken from a successful state is a stop: no displacement
    for (size_t t = first + 1; t < e.steps.size(); ++t) {
      if (!e.steps[t - 1].is_success) continue;
      const auto& a = e.steps[t].action->value;
      EXPECT_EQ(a[0], 0.0) << "seed " << seed << " step " << t;
      EXPECT_EQ(a[1], 0.0) << "seed " << seed << " step " << t;
      EXPECT_EQ(a[2], 0.0) << "seed " << seed << " step " << t;
    }
    // and the block stays where it succeeded: it ends a success
    EXPECT_TRUE(e.steps.back().is_success) << "seed " << seed;
  }
  EXPECT_GE(succeeded, 16);
}

}  // namespace
}  // namespace fetchscope
