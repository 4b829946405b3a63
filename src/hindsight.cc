#include "src/hindsight.h"

#include "src/rng.h"

namespace fetchscope {
namespace {

uint64_t SplitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

}  // namespace

uint64_t HindsightSeed(uint64_t run_seed, int episode) {
  // "HER" in the high bits keeps these streams apart from the env's and policy's seeds
  return SplitMix64(run_seed ^ SplitMix64(0x484552ull << 40 | static_cast<uint32_t>(episode)));
}

HindsightEpisode SampleHindsight(
    const std::vector<std::array<double, 3>>& achieved, const std::array<double, 3>& desired,
    uint64_t seed, int k,
    const std::function<double(const std::array<double, 3>&, const std::array<double, 3>&)>& reward,
    const std::function<bool(const std::array<double, 3>&, const std::array<double, 3>&)>&
        success) {
  HindsightEpisode out;
  const int T = static_cast<int>(achieved.size()) - 1;
  if (T <= 0) return out;
  NumpyGenerator rng(seed);
  out.transitions.resize(T);
  for (int t = 0; t < T; ++t) {
    const std::array<double, 3>& next = achieved[t + 1];  // ag_2 of the transition
    if (success(next, desired)) ++out.original_successes;
    for (int i = 0; i < k; ++i) {
      // her_sampler: future_offset = (uniform * (T - t)).astype(int); future_t = t + 1 + offset
      const int offset = static_cast<int>(rng.NextDouble() * (T - t));
      HindsightGoal g;
      g.future = t + 1 + offset;
      g.goal = achieved[g.future];
      g.reward = reward(next, g.goal);
      g.success = success(next, g.goal);
      out.relabelled_successes += g.success;
      out.transitions[t].push_back(g);
    }
  }
  return out;
}

}  // namespace fetchscope
