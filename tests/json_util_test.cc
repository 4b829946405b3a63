// JSON helpers: doubles round-trip bit for bit and read like Python's, non-finite values stay
// strict RFC 8259.
#include "base/json_util.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <vector>

#include "src/rng.h"

namespace fetchscope {
namespace {

uint64_t Bits(double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof(bits));
  return bits;
}

double FromBits(uint64_t bits) {
  double v;
  std::memcpy(&v, &bits, sizeof(v));
  return v;
}

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(JsonUtilTest, JsonDoubleKeepsFiniteNumbersAndNamesTheOthers) {
  EXPECT_TRUE(JsonDouble(0.5).is_number_float());
  EXPECT_EQ(JsonDouble(0.5).get<double>(), 0.5);
  EXPECT_EQ(JsonDouble(kInf), "inf");
  EXPECT_EQ(JsonDouble(-kInf), "-inf");
  EXPECT_EQ(JsonDouble(std::nan("")), "nan");
  EXPECT_EQ(JsonDouble(-std::nan("")), "nan");
  EXPECT_TRUE(std::signbit(JsonDouble(-0.0).get<double>()));
}

TEST(JsonUtilTest, JsonVectorConvertsEachElement) {
  const double values[] = {1.0, -kInf, 2.5};
  EXPECT_EQ(DumpJson(JsonVector(values, 3), -1), "[1.0,\"-inf\",2.5]");
  EXPECT_EQ(DumpJson(JsonVector(values, 0), -1), "[]");
}

// The sparse reward is -0.0 in Gymnasium: it must survive writing and reading.
TEST(JsonUtilTest, NegativeZeroStaysNegative) {
  const std::string text = DumpJson(nlohmann::json{{"reward", -0.0}}, -1);
  EXPECT_EQ(text, "{\"reward\":-0.0}");
  EXPECT_TRUE(std::signbit(nlohmann::json::parse(text)["reward"].get<double>()));
}

TEST(JsonUtilTest, NonFiniteNumbersInATreeAreNeverNull) {
  nlohmann::json tree = {{"a", {1.0, std::nan(""), kInf}}, {"b", {{"c", -kInf}}}};
  EXPECT_EQ(DumpJson(tree, -1), "{\"a\":[1.0,\"nan\",\"inf\"],\"b\":{\"c\":\"-inf\"}}");
}

// Bit patterns of every kind (normal, subnormal, huge, tiny, both signs) parse back exactly.
TEST(JsonUtilTest, ThousandsOfDoublesRoundTripBitExact) {
  NumpyGenerator rng(99);
  std::vector<double> values = {0.0,
                                -0.0,
                                std::numeric_limits<double>::denorm_min(),
                                -std::numeric_limits<double>::denorm_min(),
                                std::numeric_limits<double>::min(),
                                std::numeric_limits<double>::max(),
                                std::numeric_limits<double>::lowest(),
                                std::numeric_limits<double>::epsilon(),
                                0.1,
                                1.0 / 3.0};
  while (values.size() < 3000) {
    uint64_t bits = rng.NextUint64();
    if (values.size() % 3 == 0) bits &= 0x800FFFFFFFFFFFFFULL;         // subnormal
    if (values.size() % 3 == 1) values.push_back(rng.Uniform(-2, 2));  // everyday magnitudes
    const double v = FromBits(bits);
    if (std::isfinite(v)) values.push_back(v);
  }
  for (int indent : {-1, 2}) {
    const nlohmann::json back =
        nlohmann::json::parse(DumpJson(JsonVector(values.data(), values.size()), indent));
    ASSERT_EQ(back.size(), values.size());
    for (size_t i = 0; i < values.size(); ++i) {
      ASSERT_TRUE(back[i].is_number_float()) << back[i];
      ASSERT_EQ(Bits(back[i].get<double>()), Bits(values[i])) << FormatDouble(values[i]);
    }
  }
}

// FormatDouble gives Python's repr() text (and so json.dumps'), for the samples written by
// tools/make_rng_vectors.py and for every double the numpy vectors hold.
TEST(JsonUtilTest, FormatDoubleMatchesPythonRepr) {
  std::ifstream in(FETCHSCOPE_SOURCE_DIR "/tests/data/rng_vectors.json");
  ASSERT_TRUE(in) << "run tools/make_rng_vectors.py";
  const nlohmann::json vectors = nlohmann::json::parse(in);
  std::vector<nlohmann::json> samples(vectors["python_float_repr"].begin(),
                                      vectors["python_float_repr"].end());
  for (const auto& seed : vectors["seeds"]) {
    for (const auto& d : seed["next_double"]) samples.push_back(d);
    for (const auto& d : seed["uniform_m015_015"]) samples.push_back(d);
  }
  ASSERT_GT(samples.size(), 800u);
  for (const auto& sample : samples) {
    const double v = FromBits(std::stoull(sample["bits"].get<std::string>(), nullptr, 16));
    EXPECT_EQ(FormatDouble(v), sample["repr"].get<std::string>());
  }
}

TEST(JsonUtilTest, FormatDoubleSwitchPoints) {
  EXPECT_EQ(FormatDouble(1e16), "1e+16");
  EXPECT_EQ(FormatDouble(1e15), "1000000000000000.0");
  EXPECT_EQ(FormatDouble(0.0001), "0.0001");
  EXPECT_EQ(FormatDouble(0.00001), "1e-05");
  EXPECT_EQ(FormatDouble(-1.0), "-1.0");
  EXPECT_EQ(FormatDouble(-0.0), "-0.0");
  EXPECT_EQ(FormatDouble(12.5), "12.5");
  EXPECT_EQ(FormatDouble(1.5e300), "1.5e+300");
  EXPECT_EQ(FormatDouble(4.1752050594835e+78), "4.1752050594835e+78");  // nlohmann: ...5004e+78
  EXPECT_EQ(FormatDouble(-kInf), "-inf");
}

// Apart from doubles the layout is nlohmann's own, for every indent.
TEST(JsonUtilTest, LayoutMatchesNlohmannDump) {
  const nlohmann::json doc = {
      {"env_id", "FetchReach-v4"},
      {"seed", 42},
      {"big", 18446744073709551615ULL},
      {"neg", -7},
      {"ok", true},
      {"none", nullptr},
      {"empty_list", nlohmann::json::array()},
      {"empty_obj", nlohmann::json::object()},
      {"nested", {{"a", {1, 2, {3, 4}}}, {"s", "quote\" slash\\ tab\t nl\n ctl\x01 é"}}},
  };
  for (int indent : {-1, 0, 1, 2, 4}) {
    EXPECT_EQ(DumpJson(doc, indent), doc.dump(indent)) << "indent " << indent;
  }
  const nlohmann::json floats = {{"x", {0.5, 2.0}}, {"y", {{"z", 0.25}}}};
  EXPECT_EQ(DumpJson(floats), floats.dump(2));
  EXPECT_EQ(DumpJson(nlohmann::json(3.0)), "3.0");
}

TEST(JsonUtilTest, InvalidUtf8IsReplacedNotThrown) {
  const nlohmann::json doc = {{"path", std::string("/data/\xff\xfe/assets")}};
  std::string text;
  ASSERT_NO_THROW(text = DumpJson(doc, -1));
  EXPECT_EQ(text, "{\"path\":\"/data/\xEF\xBF\xBD\xEF\xBF\xBD/assets\"}");
  EXPECT_TRUE(nlohmann::json::accept(text));
}

}  // namespace
}  // namespace fetchscope
