// numpy's default random generator, bit-exact, so `--seed S` reproduces
// Gymnasium's env.reset(seed=S) and action_space.sample().
#pragma once

#include <array>
#include <cstdint>

namespace fetchscope {

/// numpy.random.Generator(PCG64(SeedSequence(seed))), bit-exact for the calls Gymnasium makes.
/// The algorithm is written out in the fetch-env reference, section 3.2.
class NumpyGenerator {
 public:
  /// Seeds like numpy's SeedSequence(seed) for a non-negative integer seed (seeds beyond
  /// 64 bits are not needed).
  explicit NumpyGenerator(uint64_t seed);

  /// PCG64 XSL-RR output: numpy's bit_generator.random_raw().
  uint64_t NextUint64();

  /// A double in [0, 1): (x >> 11) * 2^-53, numpy's Generator.random().
  double NextDouble();

  /// low + (high - low) * NextDouble(), no fused multiply-add: numpy's uniform(low, high).
  double Uniform(double low, double high);

  /// gymnasium Box(-1,1,(n,),float32).sample(): n uniform(-1,1) doubles, each cast to float.
  std::array<float, 4> SampleActionBox();

 private:
  unsigned __int128 state_ = 0;  // PCG64 state
  unsigned __int128 inc_ = 0;    // PCG64 stream increment (always odd)

  void Step();
};

}  // namespace fetchscope
