// Black-box tests of `fetchscope probe-actions`: what the action components measurably do on
// the bundled models (real MuJoCo), the report's files, and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "encode/contact_sheet.h"
#include "encode/png_io.h"
#include "inspect/probe.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::ReadFile;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::TempDir;
namespace fs = std::filesystem;
using nlohmann::json;

// Runs probe-actions for `env_id` (no rendering) and returns the report, keyed probes included.
struct Report {
  json full;
  std::map<std::string, json> probes;
  std::string table;
};

Report Probe(const std::string& env_id, const std::string& extra = "") {
  TempDir tmp;
  const fs::path out = tmp.path() / "report.json";
  auto r = RunFetchscope("probe-actions --env-id " + env_id + " --json-out " + out.string() + " " +
                         extra);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  Report report;
  report.table = r.output;
  report.full = json::parse(ReadFile(out));
  for (const auto& p : report.full["probes"]) report.probes[p["name"].get<std::string>()] = p;
  return report;
}

bool HasFlag(const json& probe, const std::string& prefix) {
  for (const auto& f : probe["flags"]) {
    if (f.get<std::string>().rfind(prefix, 0) == 0) return true;
  }
  return false;
}

TEST(ProbeActionsTest, PickAndPlaceAxesMoveAlongTheirAxis) {
  const Report r = Probe("FetchPickAndPlace-v4");
  EXPECT_EQ(r.full["env_id"], "FetchPickAndPlace-v4");
  EXPECT_EQ(r.full["steps"], 10);
  for (const char* name : {"+x", "-x", "+y", "-y", "+z", "-z"}) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(r.probes.count(name));
    const json& p = r.probes.at(name);
    EXPECT_GT(p["cosine"].get<double>(), 0.9);
    const double norm = p["mean_step_displacement"]["norm"].get<double>();
    EXPECT_GT(norm, 0.005);
    EXPECT_LT(norm, 0.05);
    EXPECT_FALSE(HasFlag(p, "cosine below"));
    EXPECT_DOUBLE_EQ(p["commanded_displacement"].get<double>(), 0.05);
    EXPECT_NEAR(p["achieved_ratio"].get<double>(), p["along_axis"].get<double>() / 0.05, 1e-12);
    EXPECT_LT(p["cross_axis_drift"].get<double>(), norm);
    // the vector's sign on the commanded axis matches the command
    const int axis = name[1] - 'x';
    const double v = p["mean_step_displacement"]["vector"][axis].get<double>();
    EXPECT_EQ(v > 0, name[0] == '+');
  }
  const double step = r.full["summary"]["step_size_at_unit_action"].get<double>();
  EXPECT_GT(step, 0.005);
  EXPECT_LT(step, 0.05);
  // the human-readable table lists every probe
  const std::string sweep = r.full["sweep_axis"];
  for (const std::string& name : {std::string("+x"), std::string("-z"), std::string("grip+"),
                                  std::string("grip-"), sweep + "@0.25", sweep + "@2"}) {
    EXPECT_NE(r.table.find(std::string("\n") + name + " "), std::string::npos) << name;
  }
}

TEST(ProbeActionsTest, PickAndPlaceGripSignsOpposeAndReportWhichOpens) {
  const Report r = Probe("FetchPickAndPlace-v4");
  const json& open = r.probes.at("grip+");
  const json& close = r.probes.at("grip-");
  EXPECT_EQ(open["command"], json({0.0, 0.0, 0.0, 1.0}));
  EXPECT_EQ(close["command"], json({0.0, 0.0, 0.0, -1.0}));
  EXPECT_GT(close["preparation_steps"].get<int>(), 0);  // opened first, so it can close
  const double d_open = open["finger_delta"].get<double>();
  const double d_close = close["finger_delta"].get<double>();
  EXPECT_GT(d_open, 0.01);
  EXPECT_LT(d_close, -0.01);
  EXPECT_FALSE(HasFlag(open, "gripper blocked"));
  EXPECT_FALSE(HasFlag(close, "gripper blocked"));
  const json& s = r.full["summary"];
  EXPECT_EQ(s["gripper_blocked"], false);
  EXPECT_EQ(s["opening_sign"], "+");
  EXPECT_NE(s["opens_fingers"].get<std::string>().find("action[3] > 0 opens"), std::string::npos);
  EXPECT_NE(s["gripper"].get<std::string>().find("free"), std::string::npos);
}

TEST(ProbeActionsTest, ReachAndPushBlockTheGripper) {
  for (const char* env : {"FetchReach-v4", "FetchPush-v4"}) {
    SCOPED_TRACE(env);
    const Report r = Probe(env);
    for (const char* name : {"grip+", "grip-"}) {
      SCOPED_TRACE(name);
      const json& p = r.probes.at(name);
      EXPECT_TRUE(HasFlag(p, "gripper blocked"));
      // the command moves nothing; the fingers are forced shut whatever action[3] says
      EXPECT_LT(std::fabs(p["finger_delta_from_command"].get<double>()), 1e-4);
      EXPECT_LT(std::fabs(p["finger_delta"].get<double>()), 2e-3);
    }
    const json& s = r.full["summary"];
    EXPECT_EQ(s["gripper_blocked"], true);
    EXPECT_EQ(s["opening_sign"], nullptr);
    EXPECT_NE(s["gripper"].get<std::string>().find("blocked"), std::string::npos);
    EXPECT_EQ(r.full["finger_indices"],
              std::string(env) == "FetchReach-v4" ? json({3, 4}) : json({9, 10}));
  }
}

TEST(ProbeActionsTest, MagnitudeSweepSaturatesAboveOne) {
  const Report r = Probe("FetchPickAndPlace-v4", "--magnitudes 0.25,1,2,3.5 --sweep-axis -y");
  EXPECT_EQ(r.full["sweep_axis"], "-y");
  const double small = r.probes.at("-y@0.25")["along_axis"].get<double>();
  const double unit = r.probes.at("-y@1")["along_axis"].get<double>();
  EXPECT_DOUBLE_EQ(unit, r.probes.at("-y")["along_axis"].get<double>());  // the same command
  EXPECT_LT(small, 0.75 * unit);
  for (const char* name : {"-y@2", "-y@3.5"}) {
    SCOPED_TRACE(name);
    const json& p = r.probes.at(name);
    EXPECT_NEAR(p["along_axis"].get<double>(), unit, 1e-9);
    EXPECT_TRUE(HasFlag(p, "saturated"));
    EXPECT_DOUBLE_EQ(p["commanded_displacement"].get<double>(), 0.05);  // clipped to 1
  }
  EXPECT_FALSE(HasFlag(r.probes.at("-y@1"), "saturated"));
  EXPECT_DOUBLE_EQ(r.probes.at("-y@0.25")["commanded_displacement"].get<double>(), 0.0125);
  EXPECT_EQ(r.probes.at("-y@0.25")["command"], json({0.0, -0.25, 0.0, 0.0}));
  EXPECT_EQ(r.full["summary"]["saturation_above_one"].get<std::string>().rfind("yes", 0), 0u);
  EXPECT_EQ(r.probes.count("-y@0.5"), 0u);  // only the magnitudes asked for
}

TEST(ProbeActionsTest, OutWritesReportAndSheet) {
  TempDir tmp;
  const fs::path out = tmp.path() / "probe";
  auto r = RunFetchscope(
      "probe-actions --env-id FetchPickAndPlace-v4 --steps 4 --magnitudes 1,2 "
      "--width 96 --height 96 --msaa 0 --out " +
      out.string() + " --json-out " + (tmp.path() / "copy").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string report = ReadFile(out / "probe_actions.json");
  ASSERT_FALSE(report.empty());
  EXPECT_EQ(ReadFile(tmp.path() / "copy_probe_actions.json"), report);
  const json j = json::parse(report);
  EXPECT_EQ(j["steps"], 4);
  EXPECT_EQ(j["sheet"], "probe_actions_sheet.png");
  const size_t probes = j["probes"].size();
  EXPECT_EQ(probes, 10u);  // 6 axes, 2 grip, 2 magnitudes
  // a grid of pairs (each probe's first and last frame, then the grasp's closed and lifted):
  // 11 pairs, 2 per row, so 4 columns and 6 rows, near square rather than an 11-row strip
  const Image sheet = ReadPng((out / "probe_actions_sheet.png").string());
  EXPECT_EQ(ProbeSheetColumns(2 * (probes + 1)), 4);
  EXPECT_EQ(sheet.width, kSheetMargin + 4 * (96 + kSheetMargin));
  const SheetLayout layout = ContactSheetLayout(96);
  EXPECT_EQ(sheet.height, layout.title_bar_height +
                              6 * (kSheetMargin + 96 + layout.label_bar_height) + kSheetMargin);
  EXPECT_LT(sheet.height, 2 * sheet.width);
  // any number of probes: pairs never split across rows, and never a two-column strip
  for (std::size_t pairs = 1; pairs <= 40; ++pairs) {
    const int columns = ProbeSheetColumns(2 * pairs);
    EXPECT_EQ(columns % 2, 0) << pairs;
    const double rows = std::ceil(2.0 * pairs / columns);
    EXPECT_LE(rows, columns + 2.0) << pairs << " pairs: a strip";
  }
  // no stray files beside the two
  int files = 0;
  for (const auto& e : fs::directory_iterator(out)) {
    (void)e;
    ++files;
  }
  EXPECT_EQ(files, 2);
}

TEST(ProbeActionsTest, JsonOutNamingAndNoFilesWithoutOut) {
  TempDir tmp;
  auto r = RunCommand("cd " + tmp.path().string() + " && " + FETCHSCOPE_BIN +
                      " probe-actions --env-id FetchReach-v4 --steps 2 --magnitudes 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("gripper: blocked"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::is_empty(tmp.path()));
  r = RunFetchscope("probe-actions --env-id FetchReach-v4 --steps 2 --magnitudes 1 --json-out " +
                    (tmp.path() / "named.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(tmp.path() / "named.json"));
}

TEST(ProbeActionsTest, SameSeedSameReport) {
  TempDir tmp;
  const std::string args =
      "probe-actions --env-id FetchPush-v4 --seed 3 --steps 3 --magnitudes 2 --json-out ";
  ASSERT_EQ(RunFetchscope(args + (tmp.path() / "a.json").string()).exit_code, 0);
  ASSERT_EQ(RunFetchscope(args + (tmp.path() / "b.json").string()).exit_code, 0);
  EXPECT_EQ(ReadFile(tmp.path() / "a.json"), ReadFile(tmp.path() / "b.json"));
}

TEST(ProbeActionsTest, BadInputIsAUsageError) {
  struct Case {
    std::string args;
    std::string mention;
  };
  const Case cases[] = {
      {"--steps 0", "--steps"},
      {"--steps 51", "--steps"},
      {"--magnitudes ''", "--magnitudes"},
      {"--magnitudes abc", "--magnitudes"},
      {"--magnitudes nan", "--magnitudes"},
      {"--magnitudes 0", "--magnitudes"},
      {"--magnitudes 1,-2", "--magnitudes"},
      {"--magnitudes 1,,2", "--magnitudes"},
      {"--magnitudes 1,", "--magnitudes"},
      {"--magnitudes inf", "--magnitudes"},
      {"--env-id FetchNope-v4", "FetchNope"},
      {"--sweep-axis z", "--sweep-axis"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.args);
    auto r = RunFetchscope("probe-actions " + c.args);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(c.mention), std::string::npos) << r.output;
    // one clear line, no table
    EXPECT_EQ(r.output.find('\n'), r.output.size() - 1) << r.output;
  }
}

}  // namespace
}  // namespace fetchscope
