// Images for exec: policies (docs/guide/your-policy.md, "Images for a vision policy"): the line
// and the bytes a child receives with --obs-camera and --exec-fields on record, rollout and
// serve's live env, checked against the Minari pixel dataset of the same run and against
// `fetchscope render` (tests/exec/check_wire.py); lines without the options as they always were;
// children that break the framing; the example that reaches the goal from its images.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tests/serve_client.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using serve_client::Api;
using testing::PythonWithPil;
using testing::ReadFile;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::ServeProcess;
using testing::SourceDir;
using testing::TempDir;

// --policy for tests/exec/wire_dump.py keeping what it receives in `dump`.
std::string Dumper(const std::string& py, const fs::path& dump, const std::string& mode = "ok") {
  return " --policy \"exec:" + py + " '" + (SourceDir() / "tests/exec/wire_dump.py").string() +
         "' '" + dump.string() + "' " + mode + "\"";
}

std::vector<std::string> Lines(const fs::path& file) {
  std::vector<std::string> lines;
  std::istringstream in(ReadFile(file));
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST(ExecImages, TheBytesAreTheDatasetsImagesAndRendersPixelsWithTheFieldsAsked) {
  const std::string py = PythonWithPil();
  if (py.empty()) GTEST_SKIP() << "python3-h5py, python3-numpy or python3-pil is not installed";
  unsetenv("DISPLAY");
  TempDir tmp;
  // a fixed and a tracking camera, every layer; record writes the dataset of the same run
  auto r = RunFetchscope(
      "record --env-id FetchPush-v4 --seed 3 --episodes 1 --steps 12 --no-sheets"
      " --obs-camera external_camera_0 --obs-camera grip=track --obs-size 64x48"
      " --obs-layers rgb,depth,segmentation --exec-fields grip_pos,object_pos"
      " --minari tt/exec-v0 --minari-root " +
      (tmp.path() / "ds").string() + " --out " + (tmp.path() / "run").string() +
      Dumper(py, tmp.path() / "dump"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (int t : {0, 6, 12}) {
    for (const auto& [name, camera] :
         {std::pair<std::string, std::string>{"external_camera_0", "external_camera_0"},
          {"grip", "track"}}) {
      r = RunFetchscope("render --env-id FetchPush-v4 --seed 3 --policy replay:" +
                        (tmp.path() / "run/episode_000.json").string() + " --steps " +
                        std::to_string(t) + " --overlay none --width 64 --height 48 --camera " +
                        camera + " -o " +
                        (tmp.path() / (name + "_t" + std::to_string(t) + ".png")).string());
      ASSERT_EQ(r.exit_code, 0) << r.output;
    }
  }
  r = RunCommand(py + " " + (SourceDir() / "tests/exec/check_wire.py").string() + " " +
                 (tmp.path() / "dump").string() + " " + (tmp.path() / "ds/tt/exec-v0").string() +
                 " " + tmp.path().string() + " 0,6,12 grip_pos,object_pos 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("ok"), std::string::npos) << r.output;
}

// The first line FetchPush-v4 seed 5 sends an exec: child, as fetchscope 86c9322 (before images
// existed) wrote it.
constexpr const char* kLineBeforeImages =
    R"({"achieved_goal":[1.439706868458675,0.8413310857777938,0.42470209084782223],)"
    R"("desired_goal":[1.3528036596477033,0.6846892628832881,0.424699749459536],)"
    R"("observation":[1.3481594395275929,0.7489509090129297,0.4136188313052402,)"
    R"(1.439706868458675,0.8413310857777938,0.42470209084782223,0.09154742893108203,)"
    R"(0.0923801767648641,0.011083259542582047,-1.5093744119550198e-06,)"
    R"(0.0012516140130654288,-8.824496851530596e-08,1.357614899755962e-07,)"
    R"(4.215747623831871e-15,0.0009310811113972394,-4.119622667467307e-05,)"
    R"(3.899823320502581e-05,5.0390716527889025e-08,-7.752417927199184e-08,)"
    R"(-9.380960872998312e-19,-0.0009310830464900114,4.1194968864370967e-05,)"
    R"(7.829532519964237e-06,3.7973449392020433e-07,4.39302281425115e-05],"t":0})";

TEST(ExecImages, WithoutObsCameraTheLinesAreAsBeforeAndExecFieldsCutThem) {
  TempDir tmp;
  const fs::path script = tmp.path() / "dump.sh";
  std::ofstream(script) << "while read line; do printf '%s\\n' \"$line\" >> \"$1\"; "
                           "echo 0.5 -0.25 0.2 0; done\n";
  auto run = [&](const std::string& file, const std::string& extra) {
    const auto r = RunFetchscope(
        "rollout --env-id FetchPush-v4 --seed 5 --episodes 1 --steps 3 --policy 'exec:sh " +
        script.string() + " " + (tmp.path() / file).string() + "'" + extra);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return Lines(tmp.path() / file);
  };
  const std::vector<std::string> all = run("all.txt", "");
  ASSERT_EQ(all.size(), 3u);
  EXPECT_EQ(all[0], kLineBeforeImages);
  EXPECT_EQ(run("all_named.txt", " --exec-fields all"), all);
  const std::vector<std::string> cut = run("cut.txt", " --exec-fields desired_goal,object_rel_pos");
  ASSERT_EQ(cut.size(), 3u);
  for (size_t t = 0; t < 3; ++t) {
    const json full = json::parse(all[t]), part = json::parse(cut[t]);
    EXPECT_EQ(part.size(), 3u) << cut[t];
    EXPECT_EQ(part["t"], t);
    EXPECT_EQ(part["desired_goal"], full["desired_goal"]);
    const std::vector<double> obs = full["observation"];
    EXPECT_EQ(part["object_rel_pos"].get<std::vector<double>>(),
              std::vector<double>(obs.begin() + 6, obs.begin() + 9));
  }
}

TEST(ExecImages, ServesLiveEnvSendsTheSameLinesAndBytesAsRollout) {
  const std::string py = PythonWithPil();
  if (py.empty()) GTEST_SKIP() << "python3-numpy is not installed";
  unsetenv("DISPLAY");
  TempDir tmp;
  const std::string obs =
      " --obs-camera external_camera_0 --obs-camera grip=track --obs-size 40x32"
      " --obs-layers rgb,depth,segmentation --exec-fields grip_pos";
  const auto r = RunFetchscope("rollout --env-id FetchReach-v4 --seed 4 --episodes 1 --steps 3" +
                               obs + Dumper(py, tmp.path() / "rollout"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  {
    ServeProcess serve("--env-id FetchReach-v4 --seed 4" + obs + Dumper(py, tmp.path() / "live"),
                       tmp.path());
    ASSERT_TRUE(serve.started()) << serve.log();
    Api api(serve);
    const std::string s = api.NewSession();
    api.Json(api.Post("/api/live/start?session=" + s + "&env=0"));
    for (int i = 0; i < 3; ++i) api.Json(api.Post("/api/live/step?session=" + s));
  }
  EXPECT_EQ(Lines(tmp.path() / "live/lines.jsonl"), Lines(tmp.path() / "rollout/lines.jsonl"));
  int images = 0;
  for (const auto& entry : fs::directory_iterator(tmp.path() / "rollout")) {
    if (entry.path().extension() != ".bin") continue;
    ++images;
    const fs::path live = tmp.path() / "live" / entry.path().filename();
    EXPECT_TRUE(fs::exists(live)) << live;
    EXPECT_TRUE(ReadFile(live) == ReadFile(entry.path())) << entry.path().filename();
  }
  EXPECT_EQ(images, 3 * 2 * 3);  // steps x cameras x layers
}

TEST(ExecImages, ChildrenThatBreakTheFramingAndBadFieldsAreOneLine) {
  const std::string py = PythonWithPil();
  if (py.empty()) GTEST_SKIP() << "python3 is not installed";
  unsetenv("DISPLAY");
  TempDir tmp;
  const std::string base =
      "rollout --env-id FetchReach-v4 --episodes 1 --steps 2 --obs-camera external_camera_0 "
      "--obs-size 160x120";
  const struct {
    std::string args, expect;
  } cases[] = {
      // reads half of the first image and answers: named, whether the rest was still being
      // written or lay unread in the pipe
      {base + Dumper(py, tmp.path() / "early", "early"),
       "answered step 0 before reading its images"},
      {base + Dumper(py, tmp.path() / "die", "die"),
       "exited with status 3 before answering step 0"},
      {base + Dumper(py, tmp.path() / "f1") + " --exec-fields grip_poss",
       "--exec-fields: unknown field 'grip_poss' (did you mean 'grip_pos'?)"},
      {base + Dumper(py, tmp.path() / "f2") + " --exec-fields object_pos",
       "unknown field 'object_pos' (this task has no object)"},
      {base + Dumper(py, tmp.path() / "f3") + " --exec-fields grip_pos,grip_pos",
       "'grip_pos' is given twice"},
      {"rollout --env-id FetchReach-v4 --policy zero --exec-fields grip_pos",
       "--policy zero reads no lines"},
      {"rollout --env-id FetchReach-v4 --policy zero --obs-camera external_camera_0",
       "or --policy exec:CMD"},
      {"serve --env-id FetchReach-v4 --port 0 --obs-camera external_camera_0",
       "--obs-camera sends images to an exec: policy here"},
  };
  for (const auto& c : cases) {
    const auto r = RunFetchscope(c.args);
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_NE(r.output.find(c.expect), std::string::npos) << c.args << "\n" << r.output;
    EXPECT_EQ(r.output.find("terminate"), std::string::npos) << r.output;
    // fetchscope's own verdict is one line (a dying child's traceback comes before it)
    const std::string last = r.output.substr(r.output.rfind("fetchscope: error:"));
    EXPECT_EQ(testing::LineCount(last), 1) << c.args << "\n" << r.output;
  }
}

// examples/policies/pixel_reach.py: the goal from the segmentation, depth, intrinsics and poses
// alone (desired_goal withheld); a mistake in any of them sends the arm elsewhere.
TEST(ExecImages, PixelReachReachesTheGoalFromItsImagesAlone) {
  const std::string py = PythonWithPil();
  if (py.empty()) GTEST_SKIP() << "python3-numpy is not installed";
  unsetenv("DISPLAY");
  TempDir tmp;
  const fs::path out = tmp.path() / "reach.json";
  // 50 goals; the arm is there within 20 steps
  const auto r = RunFetchscope(
      "rollout --env-id FetchReach-v4 --seed 0 --episodes 50 --steps 20 --policy \"exec:" + py +
      " '" + (SourceDir() / "examples/policies/pixel_reach.py").string() +
      "'\" --obs-camera front=external_camera_0"
      " --obs-camera side=free:lookat=1.34,0.75,0.53,distance=1.0,azimuth=-90,elevation=-35"
      " --obs-layers depth,segmentation --obs-size 96x80 --exec-fields grip_pos --json-out " +
      out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json trajectories = json::parse(ReadFile(out));
  int successes = 0;
  for (const json& e : trajectories["episodes"]) successes += e["is_success"].get<bool>();
  std::cout << "pixel_reach: " << successes << " of 50 episodes reached the goal\n";
  EXPECT_GE(successes, 45) << r.output;
}

}  // namespace
}  // namespace fetchscope
