// probe-actions' per-step series, limits and steady state, checked against independent replays:
// the same constant actions played by `fetchscope rollout --policy replay:FILE` (with the
// contacts recorded by --signals contacts), from which the expected displacements, the stalled
// steps and the table contacts are computed here, following the definitions of
// docs/guide/action-semantics.md, not read from probe-actions.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/test_util.h"

namespace fetchscope {
namespace {

using nlohmann::json;
using testing::ReadFile;
using testing::RunFetchscope;
using testing::TempDir;
namespace fs = std::filesystem;

std::map<std::string, json> ProbeReport(const TempDir& tmp, const std::string& args,
                                        json* full = nullptr) {
  const fs::path out = tmp.path() / "probe.json";
  const auto r = RunFetchscope("probe-actions " + args + " --json-out " + out.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const json report = json::parse(ReadFile(out));
  std::map<std::string, json> probes;
  for (const json& p : report["probes"]) probes[p["name"].get<std::string>()] = p;
  if (full) *full = report;
  return probes;
}

// The trajectory's steps (t = 0 is the reset) after replaying `rows` (CSV lines) on `env_id`.
json Replay(const TempDir& tmp, const std::string& env_id, const std::vector<std::string>& rows) {
  static int count = 0;  // a new pair of files per replay
  const std::string name = "replay" + std::to_string(++count);
  const fs::path csv = tmp.path() / (name + ".csv");
  {
    std::ofstream f(csv);
    for (const auto& row : rows) f << row << "\n";
  }
  const fs::path out = tmp.path() / (name + ".json");
  const auto r = RunFetchscope(
      "rollout --env-id " + env_id + " --seed 0 --policy replay:" + csv.string() + " --steps " +
      std::to_string(rows.size()) + " --signals contacts --json-out " + out.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return json::parse(ReadFile(out))["episodes"][0]["steps"];
}

// Displacement of grip_pos (obs[0:3]) along `axis` with `sign`, per step t = 1.. (index t - 1).
std::vector<double> Along(const json& steps, int axis, double sign) {
  std::vector<double> d;
  for (size_t t = 1; t < steps.size(); ++t) {
    d.push_back(sign * (steps[t]["observation"][axis].get<double>() -
                        steps[t - 1]["observation"][axis].get<double>()));
  }
  return d;
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

bool HasLimit(const json& step, const std::string& limit) {
  const json& l = step["limits"];
  return std::find(l.begin(), l.end(), limit) != l.end();
}

bool RobotTouchesTable(const json& step) {
  for (const json& c : step["contacts"]["list"]) {
    const std::string b1 = c["body1"], b2 = c["body2"];
    if ((b1 == "table0" && b2.rfind("robot0:", 0) == 0) ||
        (b2 == "table0" && b1.rfind("robot0:", 0) == 0)) {
      return true;
    }
  }
  return false;
}

// The case: +x on Push moves about 30 mm a step on steps 2-5, then the arm runs out of
// reach. The steady state must be the replay's median of steps 2-5 and the reach flag must start
// at step 6, where the replayed step falls under half the command and under 3/4 of the best
// earlier step, and stay on.
TEST(ProbeSteps, PushPlusXSteadyStateIsTheReplayedSteps2To5AndReachFromStep6) {
  TempDir tmp;
  const auto probes = ProbeReport(tmp, "--env-id FetchPush-v4 --steps 10");
  const json& p = probes.at("+x");
  const std::vector<double> replay =
      Along(Replay(tmp, "FetchPush-v4", std::vector<std::string>(10, "1,0,0,0")), 0, 1.0);
  ASSERT_EQ(replay.size(), 10u);
  const double expected = Median({replay[1], replay[2], replay[3], replay[4]});
  ASSERT_TRUE(p["steady_state"].is_object()) << p.dump();
  EXPECT_NEAR(p["steady_state"]["along_axis"].get<double>(), expected, 0.002);
  EXPECT_NEAR(p["steady_state"]["along_axis"].get<double>(), expected, 1e-9);  // same physics
  EXPECT_EQ(p["steady_state"]["from_step"], 2);
  EXPECT_EQ(p["steady_state"]["to_step"], 5);
  EXPECT_EQ(p["first_limited_step"]["reach"], 6);
  EXPECT_TRUE(p["first_limited_step"]["table"].is_null());
  EXPECT_TRUE(p["first_limited_step"]["clip"].is_null());
  // the replay itself: steps 2-5 move more than half the 50 mm commanded, step 6 falls under
  // half and under 3/4 of the best earlier step, and so does every later step
  double best = replay[0];
  for (int t = 1; t < 10; ++t) {
    SCOPED_TRACE("step " + std::to_string(t + 1));
    const bool stalled = replay[t] < 0.025 && replay[t] < 0.75 * best;
    EXPECT_EQ(stalled, t >= 5) << replay[t];
    EXPECT_EQ(HasLimit(p["steps"][t], "reach"), stalled);
    EXPECT_NEAR(p["steps"][t]["along_axis"].get<double>(), replay[t], 1e-9);
    best = std::max(best, replay[t]);
  }
  EXPECT_FALSE(HasLimit(p["steps"][0], "reach"));
  // the old 10-step mean mixes both: well under the steady state
  EXPECT_LT(p["along_axis"].get<double>(), 0.8 * expected);
}

// -z is stopped by the table: on Push from step 1 (the gripper starts pressed on it, no steady
// state), on PickAndPlace from the first step after which the replay records a robot-table
// contact; a clipped command is flagged on every step; +z has no limit in 10 steps.
TEST(ProbeSteps, TableAndClipFlagsFollowTheReplayedContactsAndTheCommand) {
  TempDir tmp;
  json full;
  auto probes = ProbeReport(tmp, "--env-id FetchPush-v4 --magnitudes 1,2", &full);
  const json& push = probes.at("-z");
  const json replay = Replay(tmp, "FetchPush-v4", std::vector<std::string>(10, "0,0,-1,0"));
  EXPECT_TRUE(RobotTouchesTable(replay[1]));
  EXPECT_GT(replay[10]["observation"][2].get<double>(), 0.4);  // above the table top
  EXPECT_EQ(push["first_limited_step"]["table"], 1);
  EXPECT_TRUE(push["steady_state"].is_null());
  for (const json& s : push["steps"]) EXPECT_TRUE(HasLimit(s, "table")) << s.dump();
  for (const json& s : probes.at("+z")["steps"]) EXPECT_TRUE(s["limits"].empty()) << s.dump();
  const std::string axis = full["sweep_axis"];
  for (const json& s : probes.at(axis + "@2")["steps"]) EXPECT_TRUE(HasLimit(s, "clip"));
  for (const json& s : probes.at(axis + "@1")["steps"]) EXPECT_FALSE(HasLimit(s, "clip"));

  probes = ProbeReport(tmp, "--env-id FetchPickAndPlace-v4 --magnitudes 1");
  const json& pnp = probes.at("-z");
  const json down = Replay(tmp, "FetchPickAndPlace-v4", std::vector<std::string>(10, "0,0,-1,0"));
  int first_contact = 0;
  for (int t = 1; t <= 10 && !first_contact; ++t) {
    if (RobotTouchesTable(down[t])) first_contact = t;
  }
  ASSERT_GT(first_contact, 1);  // it starts 0.13 m above the table
  EXPECT_EQ(pnp["first_limited_step"]["table"], first_contact);
  const std::vector<double> d = Along(down, 2, -1.0);
  std::vector<double> before(d.begin() + 1, d.begin() + first_contact - 1);
  ASSERT_FALSE(before.empty());
  EXPECT_NEAR(pnp["steady_state"]["along_axis"].get<double>(), Median(before), 1e-9);
}

// The sweep runs along an axis with room, and there the steady state is proportional to |a|
// up to 1 (the same fraction of the command at every magnitude), then clipped.
TEST(ProbeSteps, SweepOnAnAxisWithRoomIsProportional) {
  TempDir tmp;
  json full;
  const auto probes = ProbeReport(tmp, "--env-id FetchPush-v4 --magnitudes 0.25,0.5,1,2", &full);
  const std::string axis = full["sweep_axis"];
  EXPECT_NE(axis, "+x");
  for (const json& s : probes.at(axis)["steps"]) EXPECT_TRUE(s["limits"].empty()) << axis;
  const double unit = probes.at(axis + "@1")["steady_state"]["along_axis"].get<double>();
  for (double m : {0.25, 0.5}) {
    char name[16];
    std::snprintf(name, sizeof(name), "%s@%g", axis.c_str(), m);
    SCOPED_TRACE(name);
    const double steady = probes.at(name)["steady_state"]["along_axis"].get<double>();
    EXPECT_NEAR(steady / m, unit, 0.05 * unit);
  }
  EXPECT_DOUBLE_EQ(probes.at(axis + "@2")["steady_state"]["along_axis"].get<double>(), unit);
  // on +x, where the arm runs out of reach, the sweep's 10-step means were not proportional
  const auto x = ProbeReport(tmp, "--env-id FetchPush-v4 --magnitudes 0.5,1 --sweep-axis +x");
  EXPECT_LT(x.at("+x@1")["along_axis"].get<double>(),
            0.8 * 2 * x.at("+x@0.5")["along_axis"].get<double>());
}

// One attribution for the fingers: finger_delta_from_command is the change minus the change of
// the same run with action[3] = 0. Axis probes have action[3] = 0, so nothing is due to it; grip-
// starts after its stated preparation, which a replay of the same actions reproduces.
TEST(ProbeSteps, FingerAttributionAndPreparationMatchReplays) {
  TempDir tmp;
  json full;
  const auto probes = ProbeReport(tmp, "--env-id FetchPickAndPlace-v4 --magnitudes 1", &full);
  EXPECT_NE(full["units"]["finger"].get<std::string>().find("gripper_state"), std::string::npos);
  for (const char* name : {"+x", "-x", "+y", "-y", "+z", "-z"}) {
    const json& p = probes.at(name);
    EXPECT_EQ(p["finger_delta_from_command"].get<double>(), 0.0) << name;
    double sum = 0;
    for (const json& s : p["steps"]) sum += s["finger_change"].get<double>();
    EXPECT_NEAR(sum, p["finger_delta"].get<double>(), 1e-12) << name;
  }
  const int fr = full["finger_indices"][0], fl = full["finger_indices"][1];
  const auto width = [&](const json& step) {
    return step["observation"][fr].get<double>() + step["observation"][fl].get<double>();
  };
  const json& close = probes.at("grip-");
  EXPECT_EQ(close["preparation"]["steps"], 5);
  EXPECT_EQ(close["preparation"]["action"], json({0.0, 0.0, 0.0, 1.0}));
  std::vector<std::string> rows(5, "0,0,0,1");
  rows.resize(15, "0,0,0,-1");
  const json replay = Replay(tmp, "FetchPickAndPlace-v4", rows);
  for (int t = 0; t < 10; ++t) {
    EXPECT_NEAR(close["steps"][t]["finger_width"].get<double>(), width(replay[6 + t]), 1e-12);
  }
  std::vector<std::string> zero(5, "0,0,0,1");
  zero.resize(15, "0,0,0,0");
  const json held = Replay(tmp, "FetchPickAndPlace-v4", zero);
  EXPECT_NEAR(close["finger_delta_without_command"].get<double>(), width(held[15]) - width(held[5]),
              1e-12);
  EXPECT_NEAR(close["finger_delta_from_command"].get<double>(),
              (width(replay[15]) - width(replay[5])) - (width(held[15]) - width(held[5])), 1e-12);
}

TEST(ProbeSteps, BadSweepAxisIsOneLine) {
  for (const char* bad : {"x", "+w", "''", "auto,+x"}) {
    SCOPED_TRACE(bad);
    const auto r = RunFetchscope(std::string("probe-actions --sweep-axis ") + bad);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("--sweep-axis"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("+x, -x, +y"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find('\n'), r.output.size() - 1) << r.output;
  }
}

}  // namespace
}  // namespace fetchscope
