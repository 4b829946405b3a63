// fetchscope serve's live episodes saved and re-rendered, black box: the real binary on --port 0.
// A saved session's printed record command re-renders it byte for byte: the trajectory's bytes,
// and for a reset placed by hand (goal=, object=) every frame's pixels too.
#include <gtest/gtest.h>
#include <httplib.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "encode/png_io.h"
#include "tests/serve_client.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using serve_client::Api;
using serve_client::Encode;
using serve_client::ExpectRefusal;
using serve_client::RecordRun;
using testing::ReadFile;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::ServeProcess;
using testing::TempDir;

// Runs the record command a save printed (fetchscope on PATH, as the guide has it).
int RunPrinted(const std::string& command) {
  const std::string path = fs::path(FETCHSCOPE_BIN).parent_path().string();
  return RunCommand("PATH='" + path + "':\"$PATH\" " + command + " --quiet").exit_code;
}

TEST(ServeLiveTest, ASavedSessionReRendersByteForByteWithThePrintedCommand) {
  TempDir dir;
  const fs::path run = RecordRun(dir.path(), 2, 12);
  ServeProcess serve("'" + run.string() +
                         "' --env-id FetchPickAndPlace-v4 --seed 3 --policy "
                         "scripted --save-dir '" +
                         (dir.path() / "saved dir").string() + "'",
                     dir.path());
  ASSERT_TRUE(serve.started()) << serve.log();
  Api api(serve);
  const std::string s = api.NewSession();
  // a live env: the policy, keys, a step back, the policy again
  api.Json(api.Post("/api/live/start?session=" + s + "&env=1"));
  for (int i = 0; i < 6; ++i) api.Json(api.Post("/api/live/step?session=" + s));
  api.Json(api.Post("/api/live/step?session=" + s + "&action=0.5,0,0,1"));
  api.Json(api.Post("/api/live/step?session=" + s + "&action=0,-0.25,1,-1"));
  EXPECT_EQ(api.Json(api.Post("/api/live/back?session=" + s))["steps"], 7);
  const json last = api.Json(api.Post("/api/live/step?session=" + s));
  EXPECT_EQ(last["steps"], 8);
  const json saved =
      api.Json(api.Post("/api/live/save?session=" + s + "&camera=external_camera_0&overlay=" +
                        Encode("goal,achieved") + "&width=64&height=48"));
  const std::string command = saved.value("command", "");
  EXPECT_NE(command.find("--camera external_camera_0 --overlay goal,achieved --width 64"),
            std::string::npos)
      << command;
  EXPECT_NE(command.find("'replay:"), std::string::npos) << command;  // "saved dir": quoted
  if (RunCommand("command -v fetchscope").exit_code != 0) {
    // fetchscope is not on PATH here: the command names the binary by its path and runs as is
    const std::string bin = fs::canonical(FETCHSCOPE_BIN).string();
    EXPECT_EQ(command.rfind(bin + " record ", 0), 0u) << command;
  }
  ASSERT_EQ(RunPrinted(command), 0) << command;
  const std::string session_json = saved["files"][0];
  EXPECT_EQ(ReadFile(saved["episode_file"].get<std::string>()), ReadFile(session_json));
  // the CSV beside it replays the same actions from the same reset
  const auto csv = RunFetchscope(
      "rollout --env-id FetchPickAndPlace-v4 --seed 3 --steps 8 --signals contacts "
      "--policy 'replay:" +
      saved["files"][1].get<std::string>() + "'");
  ASSERT_EQ(csv.exit_code, 0) << csv.output;
  EXPECT_EQ(json::parse(csv.output)["episodes"][0]["steps"],
            json::parse(ReadFile(session_json))["episodes"][0]["steps"]);

  // continued from step 4 of the run's episode 1 (a reset that continues the generator)
  api.Json(api.Post("/api/live/start?session=" + s + "&source=0&episode=1&t=4"));
  for (const char* a : {"1,0,0,0", "0,0,-1,-1", "0,0,0,1"}) {
    api.Json(api.Post("/api/live/step?session=" + s + "&action=" + a));
  }
  const json again = api.Json(api.Post("/api/live/save?session=" + s + "&width=64&height=48"));
  ASSERT_EQ(RunPrinted(again.value("command", "")), 0) << again.dump();
  EXPECT_EQ(fs::path(again["episode_file"].get<std::string>()).filename(), "episode_001.json");
  EXPECT_EQ(ReadFile(again["episode_file"].get<std::string>()),
            ReadFile(again["files"][0].get<std::string>()));
}

// A reset placed by hand: the block typed where it starts, the goal too. The saved session
// records it ("reset": placed), its printed command is record --from the session, and that run's
// trajectory is the session's bytes and its lossless frames are serve's frames, pixel for pixel.
TEST(ServeLiveTest, APlacedResetIsSavedAndReRenderedPixelForPixel) {
  TempDir dir;
  ServeProcess serve("--env-id FetchPush-v4 --seed 3 --policy scripted --save-dir '" +
                         (dir.path() / "saved").string() + "'",
                     dir.path());
  ASSERT_TRUE(serve.started()) << serve.log();
  Api api(serve);
  const std::string s = api.NewSession();
  const std::string view =
      "&camera=external_camera_0&overlay=" + Encode("goal,achieved") + "&width=64&height=48";
  const auto frame = [&](int t) {
    const auto r = api.Get("/api/frame?session=" + s +
                           "&source=live&format=png&t=" + std::to_string(t) + view);
    EXPECT_TRUE(r && r->status == 200) << (r ? r->body : "no answer");
    return r ? DecodePng(r->body) : Image{};
  };
  const json drawn = api.Json(api.Post("/api/live/start?session=" + s + "&env=0"));
  const Image drawn_frame = frame(0);
  const json start = api.Json(
      api.Post("/api/live/start?session=" + s + "&env=0&object=1.2,0.9&goal=1.4,0.6,0.42"));
  const json& reset = start["rows"][0];
  EXPECT_TRUE(start["placed"].get<bool>());
  EXPECT_EQ(reset["observation"][3], 1.2);
  EXPECT_EQ(reset["observation"][4], 0.9);
  EXPECT_EQ(reset["observation"][5], drawn["rows"][0]["observation"][5]);  // resting as drawn
  EXPECT_EQ(reset["desired_goal"], json::array({1.4, 0.6, 0.42}));
  EXPECT_NE(reset["observation"][3], drawn["rows"][0]["observation"][3]);
  EXPECT_FALSE(frame(0).pixels == drawn_frame.pixels) << "the block did not move in the frame";
  for (int i = 0; i < 10; ++i) api.Json(api.Post("/api/live/step?session=" + s));
  api.Json(api.Post("/api/live/step?session=" + s + "&action=0.5,-0.5,0,1"));
  const json saved = api.Json(api.Post("/api/live/save?session=" + s + view));
  const std::string command = saved.value("command", "");
  const std::string session_json = saved["files"][0];
  EXPECT_NE(command.find(" record --from " + session_json + " "), std::string::npos) << command;
  EXPECT_EQ(json::parse(ReadFile(session_json))["episodes"][0]["reset"],
            json::parse(R"({"rule": "placed", "goal": [1.4, 0.6, 0.42],
                            "object_position": [1.2, 0.9, )" +
                        reset["observation"][5].dump() + "], \"object_euler\": " +
                        json(std::vector<double>(reset["observation"].begin() + 11,
                                                 reset["observation"].begin() + 14))
                            .dump() +
                        "}"));

  ASSERT_EQ(RunPrinted(command + " --format apng"), 0) << command;
  EXPECT_EQ(ReadFile(saved["episode_file"].get<std::string>()), ReadFile(session_json));
  // replay: would play the actions from the seed's own reset: refused, naming record --from
  const auto replay = RunFetchscope("rollout --policy 'replay:" + session_json + "'");
  EXPECT_EQ(replay.exit_code, 2) << replay.output;
  EXPECT_EQ(testing::LineCount(replay.output), 1) << replay.output;
  EXPECT_NE(replay.output.find("placed by hand (serve), which replay: cannot make"),
            std::string::npos)
      << replay.output;
  EXPECT_NE(replay.output.find("accepted: record --from " + session_json), std::string::npos)
      << replay.output;
  const std::string py = testing::PythonWithPil();
  if (py.empty()) GTEST_SKIP() << "python3 with PIL not found: the frames are not compared";
  const fs::path apng = fs::path(saved["record_out"].get<std::string>()) / "episode_000.apng";
  const auto split = RunCommand(
      py +
      " -c 'import sys; from PIL import Image\n"
      "im = Image.open(sys.argv[1])\n"
      "for t in range(im.n_frames):\n"
      "    im.seek(t); im.convert(\"RGB\").save(\"%s/frame_%02d.png\" % (sys.argv[2], t))\n"
      "print(im.n_frames)' '" +
      apng.string() + "' '" + dir.path().string() + "'");
  ASSERT_EQ(split.exit_code, 0) << split.output;
  EXPECT_EQ(std::stoi(split.output), 12);
  for (int t : {0, 1, 6, 11}) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%02d.png", t);
    EXPECT_TRUE(ReadPng((dir.path() / name).string()).pixels == frame(t).pixels) << "step " << t;
  }
}

// Placing is checked before anything starts: one line naming the value and what is accepted.
TEST(ServeLiveTest, APlacementOffTheTableOrMalformedIsRefusedInOneLine) {
  TempDir dir;
  ServeProcess serve("--env-id FetchPush-v4 --seed 3", dir.path());
  ASSERT_TRUE(serve.started()) << serve.log();
  Api api(serve);
  const std::string s = api.NewSession();
  const std::string start = "/api/live/start?session=" + s + "&env=0";
  ExpectRefusal(api.Post(start + "&object=3,0.9"), 400,
                "x = 3 is off the table; accepted: 1.050..1.550", "object off the table");
  ExpectRefusal(api.Post(start + "&goal=1.3,0.7,1.2"), 400, "z = 1.2 is off the table",
                "goal high");
  ExpectRefusal(api.Post(start + "&goal=1,2"), 400, "'1,2' has 2 numbers; accepted: x,y,z",
                "goal of 2");
  ExpectRefusal(api.Post(start + "&object=1.2,nan"), 400, "not 2 or 3 comma-separated finite",
                "nan");
  ExpectRefusal(api.Post(start + "&object=1,2,3,4"), 400, "not 2 or 3", "object of 4");
  ExpectRefusal(api.Post("/api/live/start?session=" + s + "&source=0&episode=0&t=0&goal=1,1,1"),
                400, "give them with env", "goal with a served step");
  ExpectRefusal(api.Post("/api/live/step?session=" + s), 409, "no live episode", "nothing started");
}

}  // namespace
}  // namespace fetchscope

namespace fetchscope {
namespace {

// The look control: a step of a randomized recording drawn with its stored look (render's frame
// of that draw, pixel for pixel), plainly, or under another draw (the same seed, the same
// frame); a live episode continued from it saves the look it shows, and the printed command
// (record --from the session) redraws it.
TEST(ServeLiveTest, TheLookControlRedrawsAStepPlainAsRecordedOrUnderAnotherDraw) {
  TempDir dir;
  const auto rec = RunFetchscope(
      "record --env-id FetchPush-v4 --policy scripted --seed 4 --steps 6 --width 96 --height 96 "
      "--randomize colors,textures --no-report --quiet --out '" +
      (dir.path() / "run").string() + "'");
  ASSERT_EQ(rec.exit_code, 0) << rec.output;
  const json stored =
      json::parse(ReadFile((dir.path() / "run" / "episode_000.json").string()))["episodes"][0];
  ServeProcess serve("'" + (dir.path() / "run").string() + "' --save-dir '" +
                         (dir.path() / "saved").string() + "'",
                     dir.path());
  ASSERT_TRUE(serve.started()) << serve.log();
  Api api(serve);
  const std::string s = api.NewSession();
  const std::string at =
      "/api/frame?session=" + s +
      "&source=0&episode=0&t=3&width=96&height=96&format=png&overlay=" + Encode("goal,achieved");
  const auto get = [&](const std::string& look) {
    const auto r = api.Get(at + (look.empty() ? "" : "&look=" + look));
    EXPECT_TRUE(r && r->status == 200) << (r ? r->body : "no answer");
    return std::make_pair(r->body, r->get_header_value("X-Fetchscope-Look"));
  };
  const auto own = get(""), recorded = get("recorded"), plain = get("plain"), seven = get("7");
  EXPECT_EQ(own, recorded);
  EXPECT_EQ(json::parse(own.second), stored["look"]);
  EXPECT_EQ(plain.second, "");
  EXPECT_NE(plain.first, own.first);
  EXPECT_EQ(seven, get("7"));
  EXPECT_NE(seven.first, own.first);
  EXPECT_NE(json::parse(seven.second)["seed"], stored["look"]["seed"]);
  EXPECT_EQ(json::parse(seven.second)["kinds"], json::array({"colors", "textures"}));
  ExpectRefusal(api.Get(at + "&look=shiny"), 400,
                "parameter look 'shiny' is not a look; accepted: plain, recorded", "bad look");

  // the stored look is render's draw of that episode: the same pixels
  const fs::path png = dir.path() / "render.png";
  const auto r = RunFetchscope("render --env-id FetchPush-v4 --seed 4 --policy 'replay:" +
                               (dir.path() / "run" / "episode_000.json").string() +
                               "' --steps 3 --width 96 --height 96 --overlay goal,achieved "
                               "--randomize colors,textures -o '" +
                               png.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(DecodePng(own.first).pixels == ReadPng(png.string()).pixels);

  // continued live and saved under the look on screen: record --from redraws it
  api.Json(api.Post("/api/live/start?session=" + s + "&source=0&episode=0&t=2"));
  api.Json(api.Post("/api/live/step?session=" + s + "&action=0.5,0,0,0"));
  const json saved = api.Json(
      api.Post("/api/live/save?session=" + s + "&width=96&height=96&overlay=goal,achieved&look=7"));
  const std::string command = saved.value("command", "");
  EXPECT_NE(command.find(" record --from "), std::string::npos) << command;
  ASSERT_EQ(RunPrinted(command), 0) << command;
  const json again = json::parse(ReadFile(saved["episode_file"].get<std::string>()));
  EXPECT_EQ(again["episodes"][0]["look"]["seed"], json::parse(seven.second)["seed"]);
}

}  // namespace
}  // namespace fetchscope

namespace fetchscope {
namespace {

// A run folder whose stored look is not one (edited, or hostile): its frames are refused in one
// line (409) naming the key, the plain look still draws, and the server goes on.
TEST(ServeLiveTest, AStoredLookThatIsNotOneIsRefusedInOneLine) {
  TempDir dir;
  const fs::path run = dir.path() / "run";
  ASSERT_EQ(RunFetchscope("record --env-id FetchReach-v4 --steps 2 --width 64 --height 64 "
                          "--randomize colors --no-report --quiet --out '" +
                          run.string() + "'")
                .exit_code,
            0);
  const fs::path file = run / "episode_000.json";
  json edited = json::parse(ReadFile(file.string()));
  edited["episodes"][0]["look"]["colors"]["object"] = "red";
  std::ofstream(file) << edited.dump();
  ServeProcess serve("'" + run.string() + "'", dir.path());
  ASSERT_TRUE(serve.started()) << serve.log();
  Api api(serve);
  const std::string at = "/api/frame?session=" + api.NewSession() +
                         "&source=0&episode=0&t=1&width=64&height=64&format=png";
  ExpectRefusal(api.Get(at), 409, "look.colors.object", "an edited look");
  ExpectRefusal(api.Get(at + "&look=4"), 409, "look.colors.object", "a draw over an edited look");
  const auto plain = api.Get(at + "&look=plain");
  ASSERT_TRUE(plain);
  EXPECT_EQ(plain->status, 200) << plain->body;
}

}  // namespace
}  // namespace fetchscope
