// serve's page in real headless Chromium (Debian's chromium driven by playwright-core from
// web/node_modules): web/test/check_serve.mjs (orbit, keys, save, sessions apart) and
// web/test/check_serve_debug.mjs (the step inspector, a grasp from the keys, play, pause and Save,
// sessions freed by closed pages, the reload warning). Skipped when node, chromium or
// playwright-core is absent.
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "tests/browser_util.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::BrowserTest;
using testing::Chromium;
using testing::ReadFile;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::ScreenshotPath;
using testing::SourceDir;
using testing::TempDir;

using testing::LastJson;
using testing::ReadJsonFile;

// A served run and what a check script found on its page.
struct ServedCheck {
  std::unique_ptr<testing::ServeProcess> serve;
  json result;  ///< an object, else the check failed (the failures are reported)
};

// Serves the run `record_args` records in `tmp`/run (with `serve_args`), drives the page with
// web/test/`script` (`script_args`, screenshots into `tmp`/shots) and returns what it found,
// checked to hold no error, console error, page error or failed response.
ServedCheck ServeAndCheck(const TempDir& tmp, const std::string& record_args,
                          const std::string& serve_args, const std::string& script,
                          const std::string& script_args) {
  ServedCheck c;
  const auto r =
      RunFetchscope("record " + record_args + " --quiet --out " + (tmp.path() / "run").string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  c.serve = std::make_unique<testing::ServeProcess>("'" + (tmp.path() / "run").string() + "' " +
                                                        serve_args + " --save-dir '" +
                                                        (tmp.path() / "saved").string() + "'",
                                                    tmp.path());
  if (!c.serve->started()) {
    ADD_FAILURE() << c.serve->log();
    return c;
  }
  const fs::path out = tmp.path() / "shots";
  fs::create_directories(out);
  const auto check = RunCommand("node " + (SourceDir() / "web" / "test" / script).string() +
                                " --url '" + c.serve->url + "' --out " + out.string() + " " +
                                script_args + " --chromium " + Chromium());
  c.result = LastJson(check.output);
  EXPECT_TRUE(c.result.is_object()) << check.output;
  if (!c.result.is_object()) return c;
  EXPECT_FALSE(c.result.contains("error")) << c.result["error"] << "\n" << c.serve->log();
  for (const char* list : {"console_errors", "page_errors", "failed_responses"}) {
    EXPECT_TRUE(c.result[list].empty()) << list << ": " << c.result[list];
  }
  return c;
}

// fetchscope serve's page over a localhost URL, as through ssh -L (web/test/check_serve.mjs): a
// drag orbits (the camera text, the --camera option and the frame change; JPEG while dragging, a
// lossless PNG at rest), hover names the body under the pointer, each key press is one env step
// that moves the gripper by what probe-actions measures for that action, the policy steps and
// steps back, Save prints a record command that re-renders the session byte for byte, and a
// second page gets its own session. No console error and no request leaves the server.
TEST_F(BrowserTest, ServePageOrbitsDrivesSavesAndKeepsSessionsApart) {
  TempDir tmp;
  const ServedCheck c = ServeAndCheck(
      tmp,
      "--env-id FetchReach-v4 --policy scripted --episodes 1 --steps 10 --width 64 --height 64",
      "--env-id FetchReach-v4 --seed 0 --width 480 --height 360", "check_serve.mjs",
      "--keys w,w,w,w,w --live-source 1");
  ASSERT_TRUE(c.result.is_object() && !c.result.contains("error"));
  const json& result = c.result;
  testing::ServeProcess& serve = *c.serve;
  const fs::path out = tmp.path() / "shots";
  EXPECT_TRUE(result["foreign_requests"].empty()) << result["foreign_requests"];
  EXPECT_EQ(result["url_after_token"].get<std::string>().find("token="), std::string::npos);
  EXPECT_EQ(result["first"]["errors"], 0) << result["first"];

  // the drag: a free camera the server parsed and showed as the page wrote it
  const json& drag = result["drag"];
  EXPECT_EQ(drag["camera_before"], "default");
  const std::string camera = drag["camera_after"];
  EXPECT_EQ(camera.rfind("free:lookat=1.3,0.75,0.55,distance=2.5,azimuth=", 0), 0u) << camera;
  EXPECT_EQ(drag["shown_camera"], camera);
  EXPECT_EQ(drag["camera_input"], camera);
  EXPECT_EQ(drag["camera_option"], "--camera '" + camera + "'");
  EXPECT_GE(drag["frames_during"].get<int>(), 1) << drag;
  const json formats = drag["formats"];
  EXPECT_NE(std::find(formats.begin(), formats.end(), "jpeg"), formats.end()) << drag;
  EXPECT_NE(ReadFile(out / "frame_before.png"), ReadFile(out / "frame_after.png"));
  std::cout << "drag: " << drag.dump() << std::endl;
  // the dragged view, as render draws it from that camera
  const fs::path rendered = tmp.path() / "dragged.png";
  auto r =
      RunFetchscope("render --env-id FetchReach-v4 --policy 'replay:" +
                    (tmp.path() / "run" / "episode_000.json").string() +
                    "' --width 480 --height 360 --camera '" + camera + "' -o " + rendered.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(result["hover"]["body"].get<std::string>().empty()) << result["hover"];

  // five +x key presses from the live env's reset: the gripper's mean step is probe-actions' +x
  const json& rows = result["live_rows"];
  ASSERT_EQ(rows.size(), 6u) << rows;
  double dx = 0;
  for (size_t t = 1; t < rows.size(); ++t)
    dx += rows[t][0].get<double>() - rows[t - 1][0].get<double>();
  dx /= 5;
  r = RunFetchscope("probe-actions --env-id FetchReach-v4 --seed 0 --steps 5 --out " +
                    (tmp.path() / "probe").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json probe = ReadJsonFile(tmp.path() / "probe" / "probe_actions.json");
  double along = -1;
  for (const json& p : probe["probes"]) {
    if (p["name"] == "+x") along = p["along_axis"];
  }
  std::cout << "+x key: " << dx << " m per step; probe-actions +x: " << along << " m per step"
            << std::endl;
  EXPECT_NEAR(dx, along,
              1e-5);  // keys act in float32 (the random policy's dtype), the probe in float64
  for (const json& a : result["live_actions"][0]) {
    if (!a.is_null()) {
      EXPECT_EQ(a, 1.0);
    }
  }
  for (int ms : result["key_step_ms"]) std::cout << "key step to the new frame: " << ms << " ms\n";
  EXPECT_EQ(result["after_policy_and_back"], 5);

  // Save: the printed command re-renders the session byte for byte
  const json& save = result["save"];
  const std::string command = save["command"];
  ASSERT_FALSE(command.empty()) << save;
  EXPECT_EQ(save["shown"], command);
  const std::string bin = fs::path(FETCHSCOPE_BIN).parent_path().string();
  r = RunCommand("PATH='" + bin + "':\"$PATH\" " + command + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << command << "\n" << r.output;
  EXPECT_EQ(ReadFile(save["episode_file"].get<std::string>()),
            ReadFile(save["files"][0].get<std::string>()));

  // the second page: a session of its own, without the first page's live episode
  EXPECT_NE(result["page_b"]["session"], result["page_a"]["session"]);
  EXPECT_FALSE(result["page_b"]["has_live"].get<bool>());
  EXPECT_EQ(serve.Stop(SIGINT), 130) << serve.log();
  fs::copy_file(out / "serve_page.png", ScreenshotPath(), fs::copy_options::overwrite_existing);
  std::cout << "<CTestMeasurementFile type=\"image/png\" name=\"screenshot\">"
            << ScreenshotPath().string() << "</CTestMeasurementFile>" << std::endl;
}

// serve as a debugger (web/test/check_serve_debug.mjs): the step inspector shows each step's
// values as the trajectory JSON holds them and plots a clicked field; overlays that cannot apply
// are disabled with their reason; a grasp made from the keys (a latched gripper, two-axis chords)
// holds through four lift presses; play stops at the TimeLimit, Save works while it plays and
// pause always pauses; unsaved steps make a closing page ask; 13 pages opened and closed one
// after another leave the 13th a live session (8 at most at once).
TEST_F(BrowserTest, ServeInspectsStepsHoldsAGraspAndFreesClosedPages) {
  TempDir tmp;
  const ServedCheck c = ServeAndCheck(
      tmp,
      "--env-id FetchPickAndPlace-v4 --policy scripted --seed 2 --episodes 6 --steps 50 "
      "--signals contacts --width 64 --height 64 --no-sheets",
      "--env-id FetchPickAndPlace-v4 --seed 5 --policy scripted --width 320 --height 240",
      "check_serve_debug.mjs", "--steps 3,17,40 --live-source 1");
  ASSERT_TRUE(c.result.is_object() && !c.result.contains("error"));
  const json& result = c.result;
  testing::ServeProcess& serve = *c.serve;
  const fs::path out = tmp.path() / "shots";

  // 1. the inspector's values are the trajectory's, field by field
  const json episode = ReadJsonFile(tmp.path() / "run" / "episode_000.json")["episodes"][0];
  for (int t : {3, 17, 40}) {
    const json& shown = result["inspector"][std::to_string(t)];
    const json& step = episode["steps"][t];
    ASSERT_TRUE(shown.is_object()) << t;
    EXPECT_EQ(shown["t"], t);
    EXPECT_EQ(shown["success"], step["is_success"]) << t;
    EXPECT_EQ(shown["reward"], step["reward"]) << t;
    for (int i = 0; i < 4; ++i)
      EXPECT_EQ(shown["action[" + std::to_string(i) + "]"], step["action"][i]);
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(shown["achieved_goal[" + std::to_string(i) + "]"], step["achieved_goal"][i]);
      EXPECT_EQ(shown["desired_goal[" + std::to_string(i) + "]"], step["desired_goal"][i]);
    }
    EXPECT_EQ(shown["obs[5] object_pos.z"], step["observation"][5]) << t;
    EXPECT_EQ(shown["obs[9] gripper_state.right"], step["observation"][9]) << t;
    int matched = 0;
    for (const auto& [field, value] : shown.items()) {
      if (field.rfind("obs[", 0) != 0) continue;
      EXPECT_EQ(value, step["observation"][std::stoi(field.substr(4))]) << field;
      ++matched;
    }
    EXPECT_EQ(matched, 25) << t;
    EXPECT_EQ(shown["contacts.left_finger_force"], step["contacts"]["left_finger_force"]) << t;
  }
  EXPECT_EQ(result["field_plot"]["field"], "obs[5] object_pos.z");
  EXPECT_EQ(result["field_plot"]["points"], "51");
  EXPECT_TRUE(result["overlays"]["labels"]["disabled"].get<bool>()) << result["overlays"];
  EXPECT_NE(result["overlays"]["labels"]["reason"].get<std::string>().find("one camera"),
            std::string::npos);
  EXPECT_TRUE(result["overlays"]["ghost"]["disabled"].get<bool>()) << result["overlays"];
  EXPECT_FALSE(result["overlays"]["hindsight"]["disabled"].get<bool>()) << result["overlays"];

  // 1b. the browser's filters leave the episodes the trajectories say
  std::set<int> failed, far, grasped;
  for (int k = 0; k < 6; ++k) {
    char name[32];
    std::snprintf(name, sizeof(name), "episode_%03d.json", k);
    const json steps = ReadJsonFile(tmp.path() / "run" / name)["episodes"][0]["steps"];
    const json& last = steps.back();
    if (!last["is_success"].get<bool>()) failed.insert(k);
    double d2 = 0;
    for (int i = 0; i < 3; ++i) {
      const double d =
          last["achieved_goal"][i].get<double>() - last["desired_goal"][i].get<double>();
      d2 += d * d;
    }
    if (std::sqrt(d2) > 0.05) far.insert(k);
    for (const json& step : steps) {
      const json& c = step["contacts"];
      if (c["left_finger_force"].get<double>() > 0 && c["right_finger_force"].get<double>() > 0) {
        grasped.insert(k);
        break;
      }
    }
  }
  const json& filters = result["filters"];
  auto shown = [&](const char* filter) {
    const json& f = filters[filter];
    return std::set<int>(f["episodes"].begin(), f["episodes"].end());
  };
  EXPECT_EQ(shown("success = no"), failed) << filters;
  EXPECT_EQ(shown("distance > 0.05"), far) << filters;
  EXPECT_EQ(shown("grasped"), grasped) << filters;
  EXPECT_FALSE(grasped.empty());
  EXPECT_NE(filters["bogus > 1"]["note"].get<std::string>().find("unknown column 'bogus'"),
            std::string::npos)
      << filters;
  const json headers = result["browser_headers"];
  for (const char* column :
       {"final dist. mm", "first success", "object moved mm", "grasped at", "dropped at"}) {
    EXPECT_NE(std::find(headers.begin(), headers.end(), column), headers.end())
        << column << headers;
  }

  // 1c. episode 1 beside episode 0, in step; the first difference is the first field that differs
  // at the first step where any does, in the inspector's order (their resets differ)
  const json e1 = ReadJsonFile(tmp.path() / "run" / "episode_001.json")["episodes"][0];
  std::string first_field;
  {
    const json& a = episode["steps"][0];
    const json& b = e1["steps"][0];
    std::vector<std::pair<std::string, std::pair<json, json>>> ordered;
    for (int i = 0; i < 3; ++i) {
      ordered.push_back({"achieved_goal[" + std::to_string(i) + "]",
                         {a["achieved_goal"][i], b["achieved_goal"][i]}});
    }
    for (int i = 0; i < 3; ++i) {
      ordered.push_back({"desired_goal[" + std::to_string(i) + "]",
                         {a["desired_goal"][i], b["desired_goal"][i]}});
    }
    for (const auto& [name, values] : ordered) {
      if (values.first != values.second) {
        first_field = name;
        break;
      }
    }
  }
  ASSERT_EQ(result["side_by_side"].size(), 2u);
  for (const json& s : result["side_by_side"]) {
    EXPECT_EQ(s["main"], s["other"]) << s;
    EXPECT_EQ(s["first_step"], "0") << s;
    EXPECT_EQ(s["first_field"], first_field) << s;
  }
  std::cout << "side by side: " << result["side_by_side"][0]["text"] << "\n";
  // each view its own camera: the second's set, the first's kept
  const json& cameras = result["side_by_side_cameras"];
  EXPECT_EQ(cameras["other"], "external_camera_0") << cameras;
  EXPECT_EQ(cameras["main"], cameras["main_before"]) << cameras;
  EXPECT_NE(cameras["main"], "external_camera_0") << cameras;

  // 1d. the look control: two draws (their seeds differ, all four kinds: the run has no look),
  // then the episode's own look, plain
  const json& looks = result["looks"];
  ASSERT_EQ(looks.size(), 3u) << looks;
  EXPECT_NE(looks[0]["seed"], "") << looks;
  EXPECT_NE(looks[1]["seed"], looks[0]["seed"]) << looks;
  EXPECT_NE(looks[0]["text"].get<std::string>().find("colors, textures, lighting, camera"),
            std::string::npos)
      << looks;
  EXPECT_EQ(looks[2]["seed"], "") << looks;
  EXPECT_EQ(looks[2]["text"], "plain") << looks;

  // 2. the grasp: closed on the block, it holds through four lifts (both fingers press it)
  EXPECT_GE(result["chords"].get<int>(), 1) << "no step moved along two axes at once";
  for (const json& n : result["press_steps"]) EXPECT_EQ(n, 1) << "a press, or a chord, took " << n;
  EXPECT_EQ(result["gripper_state"], "-1");
  const double closed_z = result["closed"]["observation"][5];
  for (const json& row : result["lifts"]) {
    EXPECT_GT(row["contacts"]["left_finger_force"].get<double>(), 0) << row["contacts"];
    EXPECT_GT(row["contacts"]["right_finger_force"].get<double>(), 0) << row["contacts"];
  }
  const double lifted_z = result["lifts"][3]["observation"][5];
  std::cout << "block z closed " << closed_z << " m, after four lifts " << lifted_z << " m\n";
  EXPECT_GT(lifted_z, closed_z + 0.02);
  for (const json& a : result["lift_actions"]) EXPECT_EQ(a[3], -1.0) << a;

  // 2b. a placed reset: the block where typed (on the table, as the seed's reset rests it), the
  // goal at the world point clicked on the table's top
  const json& fields = result["place_fields"];
  const json& placed = result["placed_reset"];
  EXPECT_TRUE(result["place_clicked_table"].get<bool>());
  EXPECT_EQ(placed["observation"][3], 1.25) << placed;
  EXPECT_EQ(placed["observation"][4], 0.85) << placed;
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(placed["desired_goal"][i].get<double>(), fields[2 + i].get<double>(), 1e-4) << i;
  }
  EXPECT_NEAR(placed["desired_goal"][2].get<double>(), 0.4, 0.01) << "not on the table's top";
  EXPECT_NE(result["placed_info"].get<std::string>().find("reset placed"), std::string::npos)
      << result["placed_info"];

  // 3. play stops at the TimeLimit; Save during play; every pause pauses
  EXPECT_EQ(result["stopped_at"], 50);
  EXPECT_FALSE(result["saved_during_play"]["command"].get<std::string>().empty())
      << result["saved_during_play"];
  ASSERT_EQ(result["pauses"].size(), 9u);
  for (const json& p : result["pauses"]) EXPECT_EQ(p["later"], p["paused"]) << p;

  // 4. closing with unsaved steps asks; 5. the 13th page still gets its live session
  EXPECT_EQ(result["unsaved_close_dialogs"], json::array({"beforeunload"}));
  EXPECT_EQ(result["last_page_live"], 0);
  for (const json& errors : result["pages"]) EXPECT_EQ(errors, 0);
  EXPECT_EQ(serve.Stop(SIGINT), 130) << serve.log();
  fs::copy_file(out / "grasp.png", ScreenshotPath(), fs::copy_options::overwrite_existing);
}

}  // namespace
}  // namespace fetchscope
