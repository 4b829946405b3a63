#include "src/rng.h"

namespace fetchscope {
namespace {

// SeedSequence constants (numpy/random/bit_generator.pyx).
constexpr uint32_t kInitA = 0x43b0d7e5;
constexpr uint32_t kMultA = 0x931e8875;
constexpr uint32_t kInitB = 0x8b51f9dd;
constexpr uint32_t kMultB = 0x58f38ded;
constexpr uint32_t kMixMultL = 0xca01f9dd;
constexpr uint32_t kMixMultR = 0x4973f715;
constexpr int kPoolSize = 4;

// The hash state `h` is shared across every hashmix call of one seeding.
uint32_t HashMix(uint32_t value, uint32_t& hash_const) {
  value ^= hash_const;
  hash_const *= kMultA;
  value *= hash_const;
  value ^= value >> 16;
  return value;
}

uint32_t Mix(uint32_t x, uint32_t y) {
  uint32_t result = kMixMultL * x - kMixMultR * y;
  result ^= result >> 16;
  return result;
}

// SeedSequence(seed).generate_state(4, uint64).
std::array<uint64_t, 4> SeedSequenceState(uint64_t seed) {
  // entropy words, least significant first; seed 0 is the single word 0
  uint32_t entropy[2] = {static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32)};
  const int n_words = (seed >> 32) != 0 ? 2 : 1;

  uint32_t pool[kPoolSize];
  uint32_t hash_const = kInitA;
  for (int i = 0; i < kPoolSize; ++i) {
    pool[i] = HashMix(i < n_words ? entropy[i] : 0u, hash_const);
  }
  for (int src = 0; src < kPoolSize; ++src) {
    for (int dst = 0; dst < kPoolSize; ++dst) {
      if (src != dst) pool[dst] = Mix(pool[dst], HashMix(pool[src], hash_const));
    }
  }

  uint32_t out32[8];
  uint32_t h = kInitB;
  for (int i = 0; i < 8; ++i) {
    uint32_t v = pool[i % kPoolSize];
    v ^= h;
    h *= kMultB;
    v *= h;
    v ^= v >> 16;
    out32[i] = v;
  }
  std::array<uint64_t, 4> out64;
  for (int j = 0; j < 4; ++j) {
    out64[j] =
        static_cast<uint64_t>(out32[2 * j]) | (static_cast<uint64_t>(out32[2 * j + 1]) << 32);
  }
  return out64;
}

unsigned __int128 Make128(uint64_t high, uint64_t low) {
  return (static_cast<unsigned __int128>(high) << 64) | low;
}

const unsigned __int128 kPcgMultiplier = Make128(2549297995355413924ULL, 4865540595714422341ULL);

}  // namespace

NumpyGenerator::NumpyGenerator(uint64_t seed) {
  const std::array<uint64_t, 4> words = SeedSequenceState(seed);
  const unsigned __int128 initstate = Make128(words[0], words[1]);
  const unsigned __int128 initseq = Make128(words[2], words[3]);
  // pcg_setseq_128_srandom_r
  state_ = 0;
  inc_ = (initseq << 1) | 1u;
  Step();
  state_ += initstate;
  Step();
}

void NumpyGenerator::Step() { state_ = state_ * kPcgMultiplier + inc_; }

uint64_t NumpyGenerator::NextUint64() {
  Step();
  const uint64_t high = static_cast<uint64_t>(state_ >> 64);
  const uint64_t low = static_cast<uint64_t>(state_);
  const uint64_t xored = high ^ low;
  const unsigned rot = static_cast<unsigned>(high >> 58);
  return (xored >> rot) | (xored << ((64u - rot) & 63u));
}

double NumpyGenerator::NextDouble() {
  return static_cast<double>(NextUint64() >> 11) * (1.0 / 9007199254740992.0);
}

double NumpyGenerator::Uniform(double low, double high) {
  // numpy rounds the product before the sum; the build's -ffp-contract=off keeps the
  // compiler from fusing them into an FMA on machines that have one
  return low + (high - low) * NextDouble();
}

std::array<float, 4> NumpyGenerator::SampleActionBox() {
  std::array<float, 4> sample;
  for (float& value : sample) value = static_cast<float>(Uniform(-1.0, 1.0));
  return sample;
}

}  // namespace fetchscope
