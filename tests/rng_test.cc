// NumpyGenerator against numpy 1.24.2: vectors written by tools/make_rng_vectors.py and the
// table in the fetch-env reference (section 3.2).
#include "src/rng.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace fetchscope {
namespace {

uint64_t DoubleBits(double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof(bits));
  return bits;
}

uint32_t FloatBits(float v) {
  uint32_t bits;
  std::memcpy(&bits, &v, sizeof(bits));
  return bits;
}

uint64_t Hex(const nlohmann::json& s) { return std::stoull(s.get<std::string>(), nullptr, 16); }

nlohmann::json LoadVectors() {
  std::ifstream in(FETCHSCOPE_SOURCE_DIR "/tests/data/rng_vectors.json");
  EXPECT_TRUE(in) << "tests/data/rng_vectors.json is missing: run tools/make_rng_vectors.py";
  return nlohmann::json::parse(in);
}

TEST(NumpyGeneratorTest, MatchesNumpyVectorsBitForBit) {
  const nlohmann::json vectors = LoadVectors();
  ASSERT_EQ(vectors["seeds"].size(), 7u);
  for (const auto& entry : vectors["seeds"]) {
    const uint64_t seed = std::stoull(entry["seed"].get<std::string>());
    SCOPED_TRACE("seed " + entry["seed"].get<std::string>());

    NumpyGenerator raw(seed);
    for (const auto& expected : entry["next_uint64"]) EXPECT_EQ(raw.NextUint64(), Hex(expected));

    NumpyGenerator doubles(seed);
    for (const auto& expected : entry["next_double"]) {
      const double got = doubles.NextDouble();
      EXPECT_EQ(DoubleBits(got), Hex(expected["bits"])) << expected["repr"];
      // the repr string is the same number, read by a correctly rounded parser
      EXPECT_EQ(DoubleBits(got), DoubleBits(std::stod(expected["repr"].get<std::string>())));
    }

    NumpyGenerator uniform(seed);
    for (const auto& expected : entry["uniform_m015_015"]) {
      EXPECT_EQ(DoubleBits(uniform.Uniform(-0.15, 0.15)), Hex(expected["bits"]))
          << expected["repr"];
    }

    NumpyGenerator box(seed);
    for (const auto& expected_sample : entry["box_sample_f32"]) {
      const std::array<float, 4> sample = box.SampleActionBox();
      ASSERT_EQ(expected_sample.size(), 4u);
      for (size_t i = 0; i < 4; ++i) {
        EXPECT_EQ(FloatBits(sample[i]), Hex(expected_sample[i]["bits"]))
            << expected_sample[i]["repr"];
      }
    }
  }
}

// Independent of the JSON file: the reference's table (numpy 1.24.2).
TEST(NumpyGeneratorTest, MatchesReferenceTable) {
  struct Row {
    uint64_t seed;
    std::vector<uint64_t> raw;
    std::vector<double> doubles;
  };
  const std::vector<Row> rows = {
      {0,
       {0xa30febcfd9c2825fULL, 0x4510bdf882d9d721ULL, 0x0a7d3da94ecde8b8ULL},
       {0.6369616873214543, 0.2697867137638703, 0.04097352393619469, 0.016527635528529094,
        0.8132702392002724}},
      {42,
       {0xc621fbcd16d92688ULL, 0x705a5661a791ffc1ULL, 0xdbcd12c26eda1624ULL},
       {0.7739560485559633, 0.4388784397520523, 0.8585979199113825, 0.6973680290593639,
        0.09417734788764953}},
      {1,
       {},
       {0.5118216247002567, 0.9504636963259353, 0.14415961271963373, 0.9486494471372439,
        0.31183145201048545}},
  };
  for (const Row& row : rows) {
    SCOPED_TRACE("seed " + std::to_string(row.seed));
    NumpyGenerator raw(row.seed);
    for (uint64_t expected : row.raw) EXPECT_EQ(raw.NextUint64(), expected);
    NumpyGenerator doubles(row.seed);
    for (double expected : row.doubles)
      EXPECT_EQ(DoubleBits(doubles.NextDouble()), DoubleBits(expected));
  }
}

// Reach seed 0 draws goal_u = uniform(-0.15, 0.15, size=3) (reference 3.2, per-task table).
TEST(NumpyGeneratorTest, ReachGoalOffsetsFromReference) {
  NumpyGenerator rng(0);
  EXPECT_NEAR(rng.Uniform(-0.15, 0.15), 0.041088506196, 5e-13);
  EXPECT_NEAR(rng.Uniform(-0.15, 0.15), -0.069063985871, 5e-13);
  EXPECT_NEAR(rng.Uniform(-0.15, 0.15), -0.137707942819, 5e-13);
  // PickAndPlace seed 1: 2 object draws, 3 goal draws, then the coin and the air height
  NumpyGenerator pick(1);
  for (int i = 0; i < 5; ++i) pick.Uniform(-0.15, 0.15);
  EXPECT_NEAR(pick.NextDouble(), 0.423326448973, 5e-13);
  EXPECT_NEAR(pick.Uniform(0.0, 0.45), 0.372466167219, 5e-13);
}

TEST(NumpyGeneratorTest, SameSeedSameStreamDifferentSeedDifferentStream) {
  NumpyGenerator a(7), b(7), c(8);
  for (int i = 0; i < 100; ++i) {
    const uint64_t x = a.NextUint64();
    EXPECT_EQ(x, b.NextUint64());
    EXPECT_NE(x, c.NextUint64());
  }
}

TEST(NumpyGeneratorTest, DoublesStayInUnitInterval) {
  NumpyGenerator rng(123);
  for (int i = 0; i < 100000; ++i) {
    const double u = rng.NextDouble();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
  }
}

}  // namespace
}  // namespace fetchscope
