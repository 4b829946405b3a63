// Replay files (--policy replay:FILE): the three formats, and one clear line for every bad input.
#include "src/replay_file.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "base/errors.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::TempDir;

std::string DataPath(const std::string& name) {
  return std::string(FETCHSCOPE_SOURCE_DIR) + "/tests/data/replay/" + name;
}

template <typename T>
std::string Bytes(const std::vector<T>& values) {
  return std::string(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
}

// An .npy file as numpy writes it: magic, version, little-endian header length, the dict
// padded with spaces to a multiple of 64 bytes and ended by '\n', then the data.
std::string Npy(const std::string& dict, const std::string& data, int major = 1) {
  const size_t prefix = 6 + 2 + (major == 1 ? 2 : 4);
  std::string header = dict;
  while ((prefix + header.size() + 1) % 64 != 0) header.push_back(' ');
  header.push_back('\n');
  std::string out = "\x93NUMPY";
  out.push_back(static_cast<char>(major));
  out.push_back('\0');
  const uint32_t length = static_cast<uint32_t>(header.size());
  for (size_t i = 0; i < (major == 1 ? 2u : 4u); ++i)
    out.push_back(static_cast<char>(length >> (8 * i)));
  return out + header + data;
}

std::string NpyF8(const std::vector<double>& values, const std::string& shape = "(2, 4)",
                  int major = 1) {
  return Npy("{'descr': '<f8', 'fortran_order': False, 'shape': " + shape + ", }", Bytes(values),
             major);
}

std::string NpyF4(const std::vector<float>& values, const std::string& shape = "(2, 4)") {
  return Npy("{'descr': '<f4', 'fortran_order': False, 'shape': " + shape + ", }", Bytes(values));
}

const std::vector<double> kEight = {0.1, -0.2, 0.3, -1.0, 1.5, 0.0, -0.0, 1e-300};

// ---- table of good inputs --------------------------------------------------------------------

struct GoodCase {
  std::string label;
  std::string format;
  std::string text;
  size_t rows;
  std::array<double, 4> last;  // the last row's values
  bool is_float32;
};

void PrintTo(const GoodCase& c, std::ostream* os) { *os << c.label; }

class GoodReplayTest : public ::testing::TestWithParam<GoodCase> {};

TEST_P(GoodReplayTest, Parses) {
  const GoodCase& c = GetParam();
  const std::vector<Action> actions = ParseReplayText(c.text, c.format, "in." + c.format);
  ASSERT_EQ(actions.size(), c.rows);
  for (size_t i = 0; i < 4; ++i) EXPECT_EQ(actions.back().value[i], c.last[i]) << i;
  for (const Action& a : actions) EXPECT_EQ(a.is_float32, c.is_float32);
}

INSTANTIATE_TEST_SUITE_P(
    Formats, GoodReplayTest,
    ::testing::Values(
        GoodCase{"csv_plain", "csv", "0.1,0.2,0.3,0.4\n-1,1,0,2.5\n", 2, {-1, 1, 0, 2.5}, false},
        GoodCase{"csv_header", "csv", "dx,dy,dz,gripper\n1,2,3,4\n", 1, {1, 2, 3, 4}, false},
        GoodCase{"csv_header_with_digits",
                 "csv",
                 "\n\na1, b2 ,c_3,inf_bound\n1,2,3,4\n",
                 1,
                 {1, 2, 3, 4},
                 false},
        GoodCase{"csv_crlf_spaces_blank_lines",
                 "csv",
                 "\r\n 1 , 2,3 ,4\r\n\r\n\n5,6,7,8",
                 2,
                 {5, 6, 7, 8},
                 false},
        GoodCase{"csv_bom_and_savetxt_comment",
                 "csv",
                 "\xEF\xBB\xBF# dx dy dz g\n1e-3,-2E2,+3,.5\n",
                 1,
                 {1e-3, -200, 3, 0.5},
                 false},
        GoodCase{"csv_full_precision",
                 "csv",
                 "0.1,0.30000000000000004,-0.0,5e-324\n",
                 1,
                 {0.1, 0.30000000000000004, -0.0, 5e-324},
                 false},
        GoodCase{"jsonl_arrays_and_objects",
                 "jsonl",
                 "[0.1, 0.2, 0.3, 0.4]\n\n{\"t\": 3, \"action\": [1, -1, 2.5, 0]}\n",
                 2,
                 {1, -1, 2.5, 0},
                 false},
        GoodCase{"json_whole_array",
                 "json",
                 "[[1,2,3,4],\n [5,6,7,8],\n {\"action\": [0.5,0,0,-1]}]\n",
                 3,
                 {0.5, 0, 0, -1},
                 false},
        GoodCase{"json_single_line", "json", "[0.25, 0, 0, 1]", 1, {0.25, 0, 0, 1}, false},
        GoodCase{"npy_f8_v1", "npy", NpyF8(kEight), 2, {1.5, 0.0, -0.0, 1e-300}, false},
        GoodCase{
            "npy_f8_v2", "npy", NpyF8(kEight, "(2, 4)", 2), 2, {1.5, 0.0, -0.0, 1e-300}, false},
        GoodCase{"npy_f8_v3_no_trailing_comma",
                 "npy",
                 Npy("{'descr': '<f8', 'fortran_order': False, 'shape': (2,4)}", Bytes(kEight), 3),
                 2,
                 {1.5, 0.0, -0.0, 1e-300},
                 false},
        GoodCase{"npy_f4",
                 "npy",
                 NpyF4({0.1f, 0.2f, 0.3f, 0.4f, -0.7f, 1.0f, 2.0f, -3.5f}),
                 2,
                 {static_cast<double>(-0.7f), 1.0, 2.0, -3.5},
                 true}),
    [](const ::testing::TestParamInfo<GoodCase>& info) { return info.param.label; });

// ---- table of bad inputs ---------------------------------------------------------------------

struct BadCase {
  std::string label;
  std::string format;
  std::string text;
  std::string error;  // expected substring of the message
};

void PrintTo(const BadCase& c, std::ostream* os) { *os << c.label; }

class BadReplayTest : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadReplayTest, FailsWithOneClearLine) {
  const BadCase& c = GetParam();
  const std::string name = "a." + c.format;
  try {
    ParseReplayText(c.text, c.format, name);
    FAIL() << "no error";
  } catch (const RunError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(c.error), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_NE(message.find(name), std::string::npos) << message;
    for (char ch : message) EXPECT_TRUE(ch >= 0x20 && ch < 0x7f) << "unprintable in: " << message;
  }
}

const std::string kGarbage = [] {
  std::string s;
  for (int i = 0; i < 512; ++i) s.push_back(static_cast<char>((i * 97 + 13) % 256));
  return s;
}();

INSTANTIATE_TEST_SUITE_P(
    Formats, BadReplayTest,
    ::testing::Values(
        BadCase{"csv_three_columns", "csv", "1,2,3,4\n1,2,3,4\n1,2,3\n",
                "a.csv line 3: expected 4 numbers separated by commas, got 3"},
        BadCase{"csv_five_columns", "csv", "1,2,3,4,5\n",
                "line 1: expected 4 numbers separated by commas, got 5"},
        BadCase{"csv_trailing_comma", "csv", "1,2,3,4,\n",
                "line 1: expected 4 numbers separated by commas, got 5"},
        BadCase{"csv_spaces_not_commas", "csv", "1 2 3 4\n",
                "line 1: expected 4 numbers separated by commas, got 1"},
        BadCase{"csv_nan", "csv", "1,2,3,4\n\n\n\n0,nan,0,0\n",
                "line 5: value 'nan' is not a finite number"},
        BadCase{"csv_inf", "csv", "-inf,0,0,0\n", "line 1: value '-inf' is not a finite number"},
        BadCase{"csv_overflow", "csv", "1e999,0,0,0\n", "value '1e999' is not a finite number"},
        BadCase{"csv_text_value", "csv", "1,2,abc,4\n", "line 1: value 'abc' is not a number"},
        BadCase{"csv_empty_value", "csv", "1,,3,4\n", "line 1: value '' is not a number"},
        BadCase{
            "csv_late_header", "csv", "1,2,3,4\ndx,dy,dz,g\n",
            "line 2: value 'dx' is not a number (a header line is allowed only as the first line)"},
        BadCase{"csv_empty", "csv", "", "a.csv is empty: expected at least one action row"},
        BadCase{"csv_header_only", "csv", "dx,dy,dz,gripper\n\n",
                "is empty: expected at least one action row"},
        BadCase{"csv_binary", "csv", kGarbage, "line 1:"},
        BadCase{"csv_nul_byte", "csv", std::string("1,2,3,4\n1,2\0,3,4\n", 17),
                "line 2: value '2\\x00'"},
        BadCase{"jsonl_short", "jsonl", "[1,2,3,4]\n[1,2,3]\n",
                "line 2: expected an array of 4 numbers, got 3"},
        BadCase{"jsonl_not_json", "jsonl", "[1,2,3,4]\n1,2,3,4\n",
                "line 2: not valid JSON: expected [dx, dy, dz, gripper]"},
        BadCase{"jsonl_nan_literal", "jsonl", "[NaN,0,0,0]\n", "line 1: not valid JSON"},
        BadCase{"jsonl_string_value", "jsonl", "[\"1\",0,0,0]\n",
                "line 1: value '\"1\"' is not a number"},
        BadCase{"jsonl_null_value", "jsonl", "[0,null,0,0]\n",
                "line 1: value 'null' is not a number"},
        BadCase{"jsonl_object_without_action", "jsonl", "{\"a\": [1,2,3,4]}\n",
                "line 1: object has no \"action\" member"},
        BadCase{"jsonl_scalar", "jsonl", "3\n", "line 1: got '3': expected [dx, dy, dz, gripper]"},
        BadCase{"jsonl_empty", "jsonl", "\n  \n", "is empty: expected at least one action row"},
        BadCase{"jsonl_binary", "jsonl", kGarbage, "line 1: not valid JSON"},
        BadCase{"json_array_bad_row", "json", "[[1,2,3,4],[1,2]]",
                "row index 1: expected an array of 4 numbers, got 2"},
        BadCase{"npy_int64", "npy",
                Npy("{'descr': '<i8', 'fortran_order': False, 'shape': (1, 4), }",
                    std::string(32, '\0')),
                ".npy dtype '<i8' is not supported: use float32 ('<f4') or float64 ('<f8')"},
        BadCase{"npy_big_endian", "npy",
                Npy("{'descr': '>f8', 'fortran_order': False, 'shape': (1, 4), }",
                    std::string(32, '\0')),
                "dtype '>f8' is big-endian: use little-endian float32 ('<f4') or float64 ('<f8')"},
        BadCase{"npy_structured", "npy",
                Npy("{'descr': [('x', '<f8')], 'fortran_order': False, 'shape': (4,), }",
                    std::string(32, '\0')),
                "structured dtypes are not supported"},
        BadCase{"npy_fortran", "npy",
                Npy("{'descr': '<f8', 'fortran_order': True, 'shape': (2, 4), }", Bytes(kEight)),
                "Fortran order"},
        BadCase{"npy_shape_1d", "npy", NpyF8({1, 2, 3, 4}, "(4,)"),
                ".npy shape (4,) is not supported: expected (T, 4)"},
        BadCase{"npy_shape_4x2", "npy", NpyF8(kEight, "(4, 2)"),
                ".npy shape (4, 2) is not supported: expected (T, 4)"},
        BadCase{"npy_shape_3d", "npy", NpyF8(kEight, "(1, 2, 4)"),
                "shape (1, 2, 4) is not supported"},
        BadCase{"npy_zero_rows", "npy", NpyF8({}, "(0, 4)"),
                "is empty: expected at least one action row"},
        BadCase{"npy_truncated_data", "npy", NpyF8({1, 2, 3, 4, 5}),
                "needs 64 bytes of data but the file has 40"},
        BadCase{"npy_trailing_data", "npy", NpyF8({1, 2, 3, 4, 5, 6, 7, 8, 9}),
                "needs 64 bytes of data but the file has 72"},
        BadCase{"npy_absurd_shape", "npy", NpyF8(kEight, "(999999999999999999, 4)"),
                "needs 31999999999999999968 bytes of data"},
        BadCase{"npy_nan", "npy", NpyF8({0, 0, 0, 0, 0, std::nan(""), 0, 0}),
                "row index 1 column 1: value 'nan' is not a finite number"},
        BadCase{"npy_f4_inf", "npy",
                NpyF4({0, 0, std::numeric_limits<float>::infinity(), 0}, "(1, 4)"),
                "row index 0 column 2: value 'inf' is not a finite number"},
        BadCase{"npy_missing_key", "npy", Npy("{'descr': '<f8', 'shape': (2, 4), }", Bytes(kEight)),
                "is missing"},
        BadCase{
            "npy_extra_key", "npy",
            Npy("{'descr': '<f8', 'fortran_order': False, 'shape': (2, 4), 'x': 1}", Bytes(kEight)),
            "unexpected key 'x'"},
        BadCase{"npy_header_too_long", "npy", std::string("\x93NUMPY\x01\x00\xff\xff{", 11),
                "truncated inside its header"},
        BadCase{"npy_version_9", "npy", std::string("\x93NUMPY\x09\x00\x10\x00", 10),
                "format version 9 is not supported"},
        BadCase{"npy_not_npy", "npy", "1,2,3,4\n", "not a .npy file"},
        BadCase{"npy_binary", "npy", kGarbage, "not a .npy file"},
        BadCase{"npy_garbage_header", "npy",
                std::string("\x93NUMPY\x01\x00\x08\x00\xff\xfe\x00{}()'x", 18),
                ".npy header is malformed"}),
    [](const ::testing::TestParamInfo<BadCase>& info) { return info.param.label; });

// Every prefix of valid files, and a corrupted copy, fails cleanly or parses: never crashes.
TEST(ReplayFileTest, TruncationsAndCorruptionsNeverCrash) {
  const std::vector<std::pair<std::string, std::string>> inputs = {
      {"npy", NpyF8(kEight)},
      {"npy", NpyF4({1, 2, 3, 4}, "(1, 4)")},
      {"csv", "dx,dy,dz,g\n1,2,3,4\n"},
      {"jsonl", "[1,2,3,4]\n{\"action\":[1,2,3,4]}\n"}};
  for (const auto& [format, text] : inputs) {
    for (size_t n = 0; n <= text.size(); ++n) {
      for (int flip = 0; flip < 2; ++flip) {
        std::string input = text.substr(0, n);
        if (flip && n > 0) input[n / 2] = static_cast<char>(input[n / 2] ^ 0x5a);
        try {
          ParseReplayText(input, format, "x");
        } catch (const RunError&) {
        }
      }
    }
  }
}

TEST(ReplayFileTest, UnknownFormatIsRunError) {
  EXPECT_THROW(ParseReplayText("1,2,3,4", "tsv", "x"), RunError);
}

// ---- files -----------------------------------------------------------------------------------

// The samples written by tools/make_rng_vectors.py hold the same 6 rows in every format.
TEST(ReplayFileTest, SampleFilesAgree) {
  const std::vector<Action> csv = ReadReplayFile(DataPath("replay.csv"));
  const std::vector<Action> jsonl = ReadReplayFile(DataPath("replay.jsonl"));
  const std::vector<Action> f64 = ReadReplayFile(DataPath("replay_f64.npy"));
  const std::vector<Action> f32 = ReadReplayFile(DataPath("replay_f32.npy"));
  ASSERT_EQ(csv.size(), 6u);
  ASSERT_EQ(jsonl.size(), 6u);
  ASSERT_EQ(f64.size(), 6u);
  ASSERT_EQ(f32.size(), 6u);
  for (size_t r = 0; r < 6; ++r) {
    EXPECT_FALSE(csv[r].is_float32);
    EXPECT_FALSE(jsonl[r].is_float32);
    EXPECT_FALSE(f64[r].is_float32);
    EXPECT_TRUE(f32[r].is_float32);
    for (size_t c = 0; c < 4; ++c) {
      // repr() text and float64 binary give identical bits
      EXPECT_EQ(csv[r].value[c], f64[r].value[c]);
      EXPECT_EQ(jsonl[r].value[c], f64[r].value[c]);
      // float32 rows are exactly the float cast of the float64 ones (numpy's astype)
      EXPECT_EQ(f32[r].value[c], static_cast<double>(static_cast<float>(f64[r].value[c])));
    }
  }
  // out-of-range values are kept: the env clips, as Gymnasium does
  EXPECT_EQ(f64[5].value[0], 1.5);
  EXPECT_EQ(f64[5].value[1], -2.0);
  EXPECT_EQ(csv[0].value[0], 0.25019093320933394);
}

TEST(ReplayFileTest, Float32NpyRoundTripsExactly) {
  std::vector<float> values;
  for (int i = 0; i < 40; ++i)
    values.push_back(std::nextafter(0.1f * static_cast<float>(i - 20), 2.0f));
  values.push_back(std::numeric_limits<float>::denorm_min());
  values.push_back(-0.0f);
  values.push_back(std::numeric_limits<float>::max());
  values.push_back(-1.0f);
  TempDir dir;
  const auto path = (dir.path() / "a.NPY").string();  // extension case does not matter
  std::ofstream(path, std::ios::binary) << NpyF4(values, "(11, 4)");
  const std::vector<Action> actions = ReadReplayFile(path);
  ASSERT_EQ(actions.size(), 11u);
  for (size_t i = 0; i < values.size(); ++i) {
    const Action& a = actions[i / 4];
    EXPECT_TRUE(a.is_float32);
    const float back = static_cast<float>(a.value[i % 4]);
    EXPECT_EQ(std::memcmp(&back, &values[i], sizeof(float)), 0) << i;
    EXPECT_EQ(a.value[i % 4], static_cast<double>(values[i]));
  }
  EXPECT_TRUE(std::signbit(actions[10].value[1]));
}

TEST(ReplayFileTest, FileErrorsNameTheFile) {
  TempDir dir;
  const std::string txt = (dir.path() / "actions.txt").string();
  std::ofstream(txt) << "1,2,3,4\n";
  try {
    ReadReplayFile(txt);
    FAIL() << "no error";
  } catch (const UsageError& e) {  // the name on the command line: exit 2
    EXPECT_NE(std::string(e.what()).find(
                  "unknown replay file extension '.txt': use .csv, .npy or .jsonl"),
              std::string::npos)
        << e.what();
  }
  try {
    ReadReplayFile((dir.path() / "missing.csv").string());
    FAIL() << "no error";
  } catch (const UsageError& e) {  // a path that cannot be used as given: exit 2
    EXPECT_NE(std::string(e.what()).find("missing.csv: No such file or directory"),
              std::string::npos)
        << e.what();
  }
  try {
    ReadReplayFile((dir.path() / "actions").string());
    FAIL() << "no error";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("actions has no extension: use .csv, .npy or .jsonl"),
              std::string::npos)
        << e.what();
  }
  std::filesystem::create_directory(dir.path() / "folder.csv");
  try {
    ReadReplayFile((dir.path() / "folder.csv").string());
    FAIL() << "no error";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("folder.csv: it is a folder"), std::string::npos)
        << e.what();
  }
  const std::string bad = (dir.path() / "bad.csv").string();
  std::ofstream(bad) << "1,2,3,4\n1,2,3\n";
  try {
    ReadReplayFile(bad);
    FAIL() << "no error";
  } catch (const RunError& e) {
    EXPECT_EQ(std::string(e.what()),
              "replay file " + bad + " line 2: expected 4 numbers separated by commas, got 3");
  }
}

}  // namespace
}  // namespace fetchscope
