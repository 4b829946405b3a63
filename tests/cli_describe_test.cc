// `describe`, black box: the D1 schema of every env id, where it differs from the course
// chapter (measured), and --json-out naming a folder or an unwritable file.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::CommandResult;
using testing::LinesWith;
using testing::ReadFile;
using testing::RunFetchscope;
using testing::RunFetchscopeStdout;
using testing::TempDir;
namespace fs = std::filesystem;

const char* kIds[] = {"FetchReach-v4",     "FetchReachDense-v4",   "FetchPush-v4",
                      "FetchPushDense-v4", "FetchPickAndPlace-v4", "FetchPickAndPlaceDense-v4",
                      "FetchSlide-v4",     "FetchSlideDense-v4"};

TEST(Cli, DescribeEveryId) {
  TempDir tmp;
  for (const char* id : kIds) {
    const std::string prefix = (tmp.path() / id).string();
    auto r = RunFetchscope(std::string("describe --env-id ") + id + " --json-out " + prefix);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    auto j = nlohmann::json::parse(ReadFile(prefix + "_describe.json"));
    const bool reach = std::string(id).find("Reach") != std::string::npos;
    const bool pick = std::string(id).find("PickAndPlace") != std::string::npos;
    EXPECT_EQ(j["action_space"]["shape"][0], 4);
    EXPECT_EQ(j["action_space"]["dtype"], "float32");
    // the chapter's D1 layout: one bound per element, the Boxes directly under
    // observation_space, infinities as strict-JSON strings
    EXPECT_EQ(j["action_space"]["low"], nlohmann::json::parse("[-1.0, -1.0, -1.0, -1.0]"));
    EXPECT_EQ(j["action_space"]["high"], nlohmann::json::parse("[1.0, 1.0, 1.0, 1.0]"));
    const auto& spaces = j["observation_space"];
    EXPECT_EQ(spaces.size(), 3u) << spaces.dump();
    const int n = reach ? 10 : 25;
    EXPECT_EQ(spaces["observation"]["shape"], nlohmann::json::array({n}));
    EXPECT_EQ(spaces["observation"]["labels"].size(), static_cast<size_t>(n));
    for (const char* key : {"achieved_goal", "desired_goal"}) {
      EXPECT_EQ(spaces[key]["type"], "Box");
      EXPECT_EQ(spaces[key]["dtype"], "float64");
      EXPECT_EQ(spaces[key]["shape"], nlohmann::json::array({3}));
      EXPECT_EQ(spaces[key]["low"], nlohmann::json::array({"-inf", "-inf", "-inf"}));
    }
    EXPECT_EQ(spaces["observation"]["high"], std::vector<std::string>(n, "inf"));
    EXPECT_EQ(spaces["observation"]["low"], std::vector<std::string>(n, "-inf"));
    EXPECT_EQ(j["action_space"]["labels"].size(), 4u);
    const std::string grip = j["action_space"]["labels"][3]["meaning"];
    if (pick) {
      EXPECT_NE(grip.find("> 0 OPENS"), std::string::npos) << grip;
    } else {
      EXPECT_NE(grip.find("ignored"), std::string::npos) << grip;
    }
    EXPECT_EQ(j["distance_threshold"], 0.05);
    EXPECT_EQ(j["max_episode_steps"], 50);
    EXPECT_EQ(j["n_substeps"], 20);
    EXPECT_EQ(j["assets"]["sha256"].get<std::string>().size(), 64u);
  }
  auto r = RunFetchscopeStdout("describe --env-id auto");
  ASSERT_EQ(r.exit_code, 0);
  EXPECT_EQ(nlohmann::json::parse(r.output)["env_id"], "FetchReachDense-v4");
}

// an output path that cannot be used as given is the command line's fault (exit-codes.md)
TEST(Cli, UnwritableOutputIsAUsageError) {
  auto r = RunFetchscope("describe --json-out /proc/nope/x.json");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("/proc/nope"), std::string::npos) << r.output;
}

// The number after `prefix` on `line` (e.g. "finger width +"), or NaN.
double NumberAfter(const std::string& line, const std::string& prefix) {
  const size_t at = line.find(prefix);
  if (at == std::string::npos) return NAN;
  return std::atof(line.c_str() + at + prefix.size());
}

TEST(RoughEdges, DescribeSaysWhereTheGripperDiffersFromTheChapterWithAMeasurement) {
  TempDir tmp;
  // PickAndPlace: a[3] > 0 opens the fingers, measured by stepping the env
  CommandResult r = RunFetchscope("describe --env-id FetchPickAndPlace-v4 --json-out " +
                                  (tmp.path() / "pp").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::vector<std::string> lines = LinesWith(r.output, "the chapter says");
  ASSERT_EQ(lines.size(), 1u) << r.output;
  EXPECT_NE(lines[0].find("a[3] > 0 opens the fingers"), std::string::npos) << lines[0];
  EXPECT_NE(lines[0].find("(the chapter says it closes them)"), std::string::npos) << lines[0];
  const double opened = NumberAfter(lines[0], "finger width ");
  EXPECT_GT(opened, 0.01) << lines[0];
  EXPECT_LT(opened, 0.11) << lines[0];
  const nlohmann::json pp = nlohmann::json::parse(ReadFile(tmp.path() / "pp_describe.json"));
  ASSERT_EQ(pp["chapter_differences"].size(), 1u) << pp["chapter_differences"];
  EXPECT_EQ(pp["chapter_differences"][0], lines[0].substr(lines[0].find("a[3]")));

  // Reach: a[3] does nothing (both directions measured)
  r = RunFetchscope("describe --json-out " + (tmp.path() / "reach").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  lines = LinesWith(r.output, "the chapter says");
  ASSERT_EQ(lines.size(), 1u) << r.output;
  EXPECT_NE(lines[0].find("a[3] is ignored in FetchReachDense-v4"), std::string::npos) << lines[0];
  EXPECT_EQ(NumberAfter(lines[0], "a difference of "), 0.0) << lines[0];
  // stdout JSON stays JSON, with the same line as a key; the line itself goes to stderr
  std::string err;
  r = RunFetchscopeStdout("describe", &err);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(err.find("differs from the chapter: a[3] is ignored in FetchReachDense-v4"),
            std::string::npos)
      << err;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  ASSERT_EQ(j["chapter_differences"].size(), 1u);
  EXPECT_NE(j["chapter_differences"][0].get<std::string>().find("the chapter says"),
            std::string::npos);
}

// `--json-out DIR/` names a folder: DIR/describe.json, not DIR/_describe.json.
TEST(RoughEdges, JsonOutEndingInASlashIsAFolder) {
  TempDir tmp;
  const CommandResult r =
      RunFetchscope("describe --json-out " + (tmp.path() / "results").string() + "/");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(tmp.path() / "results" / "describe.json")) << r.output;
  EXPECT_FALSE(fs::exists(tmp.path() / "results" / "_describe.json"));
}

}  // namespace
}  // namespace fetchscope
