// golden check in CI (issue 48): the three exit statuses, the JUnit XML (read by python3's
// xml.etree) and JSON reports, the same-backend tolerance catching a block's red 0.2 -> 0.25
// while a cross-backend set keeps the measured 32 levels, the assets-changed line, a state
// difference named by quantity (a table raised 2 mm), masks, --require-genuine, goldens
// without metadata, a capped msaa, update saying what changed, and a scene under a fixed
// randomized look (issue 49).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>

#include "encode/png_io.h"
#include "inspect/image_diff.h"
#include "tests/test_util.h"

namespace fs = std::filesystem;

namespace fetchscope {
namespace {

using testing::CommandResult;
using testing::ReadFile;
using testing::RunCommand;
using testing::SourceDir;
using testing::TempDir;

// A copy of the committed golden folder to edit, with its scenes' assets changeable.
class Goldens {
 public:
  Goldens() {
    fs::copy(SourceDir() / "golden", dir(), fs::copy_options::recursive);
    manifest_ = nlohmann::json::parse(ReadFile(dir() / "manifest.json"));
  }
  fs::path dir() const { return tmp_.path() / "golden"; }
  fs::path out() const { return tmp_.path() / "out"; }
  fs::path root() const { return tmp_.path(); }
  nlohmann::json& Scene(const std::string& name) {
    for (auto& s : manifest_["scenes"]) {
      if (s["name"] == name) return s;
    }
    throw std::runtime_error("no scene " + name);
  }
  void SaveManifest() { std::ofstream(dir() / "manifest.json") << manifest_.dump(2); }
  // the bundled models as an envs/assets folder ASSETS beside the manifest, `file`'s text
  // `from` replaced by `to`; scene `scene` uses it
  void EditedAssets(const std::string& scene, const std::string& file, const std::string& from,
                    const std::string& to) {
    const fs::path fetch = dir() / "edited" / "fetch";
    fs::create_directories(fetch);
    for (const auto& entry : fs::directory_iterator(SourceDir() / "models")) {
      if (entry.path().extension() == ".xml") {
        fs::copy(entry.path(), fetch / entry.path().filename(),
                 fs::copy_options::overwrite_existing);
      }
    }
    std::string text = ReadFile(fetch / file);
    const size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
    std::ofstream(fetch / file) << text;
    Scene(scene)["assets"] = "edited";
    SaveManifest();
  }
  // `fetchscope golden CMD --golden-dir ... --out ... ARGS`; genuine scenes find no assets
  CommandResult Run(const std::string& cmd, const std::string& args) const {
    return RunCommand("FETCHSCOPE_SHARED_DIR=" + root().string() + "/no-shared " +
                      std::string(FETCHSCOPE_BIN) + " golden " + cmd + " --golden-dir " +
                      dir().string() + " --out " + out().string() + " " + args);
  }

 private:
  TempDir tmp_;
  nlohmann::json manifest_;
};

constexpr char kRed[] = R"(name="block_mat" rgba="0.2 0.2 0.2 1")";
constexpr char kRedPlus[] = R"(name="block_mat" rgba="0.25 0.2 0.2 1")";

TEST(GoldenExitCodes, PassIs0RegressionIs1UnusableIs2) {
  Goldens g;
  EXPECT_EQ(g.Run("check", "--backend osmesa --only reach_reset").exit_code, 0);

  // a regression: the state golden moved
  nlohmann::json state = nlohmann::json::parse(ReadFile(g.dir() / "reach_reset_state.json"));
  state["steps"][0]["desired_goal"][1] = state["steps"][0]["desired_goal"][1].get<double>() + 0.01;
  std::ofstream(g.dir() / "reach_reset_state.json") << state.dump();
  const CommandResult regressed = g.Run("check", "--backend osmesa --only reach_reset");
  EXPECT_EQ(regressed.exit_code, 1) << regressed.output;

  // a malformed manifest: one line naming the member, exit 2
  Goldens bad_manifest;
  bad_manifest.Scene("reach_reset")["width"] = "wide";
  bad_manifest.SaveManifest();
  const CommandResult malformed = bad_manifest.Run("check", "--backend osmesa");
  EXPECT_EQ(malformed.exit_code, 2) << malformed.output;
  EXPECT_NE(malformed.output.find("\"width\" must be an integer"), std::string::npos)
      << malformed.output;

  // broken XML in a scene's assets: that scene cannot be checked, exit 2 (not a regression)
  Goldens broken;
  broken.EditedAssets("push_reset_external", "push.xml", "<worldbody>", "<worldbody><oops");
  const CommandResult xml =
      broken.Run("check", "--backend osmesa --only reach_reset,push_reset_external");
  EXPECT_EQ(xml.exit_code, 2) << xml.output;
  EXPECT_NE(xml.output.find("push_reset_external  ERROR"), std::string::npos) << xml.output;
  EXPECT_NE(xml.output.find("cannot be checked"), std::string::npos) << xml.output;

  // a GL that cannot be used: an EGL device that does not exist
  const CommandResult gl = g.Run("check", "--backend egl --gpu 4000 --only reach_reset");
  EXPECT_EQ(gl.exit_code, 2) << gl.output;
  // a bad --tolerance names what is accepted, before any rendering
  const CommandResult tol = g.Run("check", "--tolerance threshold=8,rms=1");
  EXPECT_EQ(tol.exit_code, 2) << tol.output;
  EXPECT_NE(tol.output.find("unknown member 'rms'"), std::string::npos) << tol.output;
}

TEST(GoldenReports, JunitHasOneTestcasePerSceneReadByPython) {
  Goldens g;
  g.Scene("reach_reset")["camera"] = "free:azimuth=134";  // fails in pixels
  g.SaveManifest();
  const fs::path junit = g.root() / "reports" / "golden.xml";
  fs::create_directories(junit.parent_path());
  const CommandResult r =
      g.Run("check",
            "--backend osmesa --only reach_reset,slide_reset,genuine_reach_reset "
            "--junit " +
                junit.string() + " --json " + (g.root() / "golden.json").string());
  ASSERT_EQ(r.exit_code, 1) << r.output;
  // python3's ElementTree: testcases, their failure and skipped elements, and the failure's
  // image paths existing
  const std::string script = R"(
import os, sys, xml.etree.ElementTree as ET
suite = ET.parse(sys.argv[1]).getroot().find('testsuite')
print('tests', suite.get('tests'), 'failures', suite.get('failures'), 'skipped', suite.get('skipped'))
for case in suite.findall('testcase'):
    f = case.find('failure')
    state = 'failure' if f is not None else ('skipped' if case.find('skipped') is not None else 'ok')
    print('case', case.get('name'), state)
    if f is not None:
        print('message', f.get('message'))
        for line in f.text.splitlines():
            if line.startswith('image: '):
                print('image', os.path.exists(line[7:]))
)";
  std::ofstream(g.root() / "read.py") << script;
  const CommandResult py =
      RunCommand("/usr/bin/python3 " + (g.root() / "read.py").string() + " " + junit.string());
  ASSERT_EQ(py.exit_code, 0) << py.output;
  EXPECT_NE(py.output.find("tests 3 failures 1 skipped 1"), std::string::npos) << py.output;
  EXPECT_NE(py.output.find("case reach_reset failure"), std::string::npos) << py.output;
  EXPECT_NE(py.output.find("case slide_reset ok"), std::string::npos) << py.output;
  EXPECT_NE(py.output.find("case genuine_reach_reset skipped"), std::string::npos) << py.output;
  EXPECT_NE(py.output.find("message state equal, pixels differ"), std::string::npos) << py.output;
  EXPECT_NE(py.output.find("image True"), std::string::npos) << py.output;
  EXPECT_EQ(py.output.find("image False"), std::string::npos) << py.output;

  const nlohmann::json j = nlohmann::json::parse(ReadFile(g.root() / "golden.json"));
  EXPECT_EQ(j["failed"], 1);
  EXPECT_EQ(j["passed"], 1);
  EXPECT_EQ(j["skipped"], 1);
  EXPECT_EQ(j["scenes"][0]["scene"], "reach_reset");
  EXPECT_GT(j["scenes"][0]["changed_region"]["width"].get<int>(), 0);
  EXPECT_TRUE(fs::exists(g.out() / j["scenes"][0]["images"]["diff"].get<std::string>()));
  EXPECT_TRUE(fs::exists(g.out() / "index.html"));
}

TEST(GoldenTolerance, SameBackendCatchesRedPlusFiveHundredthsCrossBackendKeeps32Levels) {
  Goldens g;
  g.EditedAssets("push_reset_external", "fetch_shared.xml", kRed, kRedPlus);
  const CommandResult same = g.Run("check", "--backend osmesa --only push_reset_external");
  EXPECT_EQ(same.exit_code, 1) << same.output;
  EXPECT_NE(same.output.find("model appearance"), std::string::npos) << same.output;
  // the changed assets are said first, before the table
  const size_t assets = same.output.find("the assets changed since these goldens were made");
  EXPECT_LT(assets, same.output.find("scene  ")) << same.output;
  // the change is 15-18 levels: under the cross-backend threshold
  const std::smatch m = [&] {
    std::smatch found;
    std::regex_search(same.output, found,
                      std::regex(R"(push_reset_external +FAIL +\S+ +\S+ +(\d+))"));
    return found;
  }();
  ASSERT_EQ(m.size(), 2u) << same.output;
  EXPECT_LT(std::stoi(m[1]), 32);
  EXPECT_GT(std::stoi(m[1]), 8);

  // the same goldens said to be made on another renderer: the measured cross-backend
  // tolerance (32 levels) applies and says so, and this change passes it
  for (const auto& entry : fs::directory_iterator(g.dir())) {
    if (entry.path().string().find("_meta.json") == std::string::npos) continue;
    nlohmann::json meta = nlohmann::json::parse(ReadFile(entry.path()));
    meta["backend"] = "egl";
    meta["gl_renderer"] = "NVIDIA H200/PCIe/SSE2";
    std::ofstream(entry.path()) << meta.dump();
  }
  const CommandResult cross =
      g.Run("check",
            "--backend osmesa --only push_reset_external,reach_reset,slide_reset "
            "--json " +
                (g.root() / "r.json").string());
  EXPECT_EQ(cross.exit_code, 0) << cross.output;
  const nlohmann::json j = nlohmann::json::parse(ReadFile(g.root() / "r.json"));
  for (const auto& s : j["scenes"]) {
    EXPECT_EQ(s["tolerance"]["threshold"], 32) << s.dump();
    EXPECT_NE(s["tolerance"]["why"].get<std::string>().find("NVIDIA H200"), std::string::npos);
  }
  // an explicit --tolerance overrides both
  EXPECT_EQ(
      g.Run("check", "--backend osmesa --only push_reset_external --tolerance same").exit_code, 1);
  EXPECT_EQ(g.Run("check", "--backend osmesa --only push_reset_external --tolerance threshold=20")
                .exit_code,
            0);
}

TEST(GoldenDiagnosis, TableRaisedTwoMillimetresIsNamedByQuantity) {
  Goldens g;
  g.EditedAssets("push_reset_external", "push.xml", R"(<body name="table0" pos="1.3 0.75 0.2">)",
                 R"(<body name="table0" pos="1.3 0.75 0.202">)");
  const CommandResult r = g.Run("check", "--backend osmesa --only push_reset_external");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("state differs (physics or model)"), std::string::npos) << r.output;
  // the largest position change is the object, by about the 2 mm the table rose
  EXPECT_TRUE(
      std::regex_search(r.output, std::regex(R"(state: object_pos\.z \+(1\.9\d|2\.0\d) mm)")))
      << r.output;
  EXPECT_NE(r.output.find("grip_pos.z +"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("the assets changed"), std::string::npos) << r.output;

  // update says the same by name, and writes a review page of the change
  const CommandResult u = g.Run("update", "--backend osmesa --only push_reset_external");
  ASSERT_EQ(u.exit_code, 0) << u.output;
  EXPECT_TRUE(
      std::regex_search(u.output, std::regex(R"(state: object_pos\.z \+(1\.9\d|2\.0\d) mm)")))
      << u.output;
  EXPECT_NE(u.output.find("pixels: max diff"), std::string::npos) << u.output;
  EXPECT_NE(ReadFile(g.out() / "index.html").find("object_pos.z"), std::string::npos);
  EXPECT_TRUE(fs::exists(g.out() / "push_reset_external_golden.png"));
  EXPECT_EQ(g.Run("check", "--backend osmesa --only push_reset_external").exit_code, 0);
}

TEST(GoldenMasks, AMaskedRegionIsLeftOut) {
  Goldens g;
  Image golden = ReadPng((g.dir() / "slide_reset.png").string());
  for (int y = 100; y < 124; ++y) {
    for (int x = 150; x < 174; ++x) {
      uint8_t* p = &golden.pixels[(static_cast<size_t>(y) * golden.width + x) * 3];
      p[0] = p[1] = p[2] = 0;
    }
  }
  WritePng((g.dir() / "slide_reset.png").string(), golden.width, golden.height, 3, 8,
           golden.pixels.data());
  EXPECT_EQ(g.Run("check", "--backend osmesa --only slide_reset").exit_code, 1);
  g.Scene("slide_reset")["mask"] = {{148, 98, 30, 30}};
  g.SaveManifest();
  const CommandResult masked = g.Run("check", "--backend osmesa --only slide_reset");
  EXPECT_EQ(masked.exit_code, 0) << masked.output;
  g.Scene("slide_reset")["mask"] = {{300, 98, 30, 30}};  // beyond the 320-wide frame
  g.SaveManifest();
  const CommandResult outside = g.Run("check", "--backend osmesa --only slide_reset");
  EXPECT_EQ(outside.exit_code, 2) << outside.output;
  EXPECT_NE(outside.output.find("reaches outside the 320x240 frame"), std::string::npos)
      << outside.output;
}

TEST(GoldenCheck, RequireGenuineFailsWhenGenuineScenesAreSkipped) {
  Goldens g;
  const CommandResult r =
      g.Run("check", "--backend osmesa --only reach_reset,genuine_reach_reset --require-genuine");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--require-genuine: 1 genuine-asset scene(s) (genuine_reach_reset)"),
            std::string::npos)
      << r.output;
}

TEST(GoldenCheck, GoldensWithoutMetadataStillCheckWithANote) {
  Goldens g;
  for (const auto& entry : fs::directory_iterator(g.dir())) {
    if (entry.path().string().find("_meta.json") != std::string::npos) fs::remove(entry.path());
  }
  const CommandResult r = g.Run("check", "--backend osmesa --only reach_reset,slide_reset");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("2 scene(s) have no NAME_meta.json"), std::string::npos) << r.output;
}

TEST(GoldenCheck, AnMsaaTheDriverCapsIsReported) {
  Goldens g;
  g.Scene("reach_reset")["msaa"] = 16;  // llvmpipe (OSMesa) offers fewer samples
  g.SaveManifest();
  const fs::path json = g.root() / "r.json";
  const CommandResult r =
      g.Run("check", "--backend osmesa --only reach_reset --json " + json.string());
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex(R"(msaa 16 asked, (\d+) used: )")))
      << r.output;
  EXPECT_LT(std::stoi(m[1]), 16);
  EXPECT_NE(
      nlohmann::json::parse(ReadFile(json))["scenes"][0]["notes"].dump().find("msaa 16 asked"),
      std::string::npos);
}

// "randomize" and "look_seed": push_reset_external_look is push_reset_external under one drawn
// look. The draw is applied (more than a tenth of the pixels differ by over 32 levels), at check
// time too (another look_seed fails in pixels), and never touches the physics (the two state
// goldens are equal but for the scene's name).
TEST(GoldenLook, AFixedDrawIsAppliedAndLeavesTheStateAlone) {
  Goldens g;
  const Image plain = ReadPng((g.dir() / "push_reset_external.png").string());
  const Image look = ReadPng((g.dir() / "push_reset_external_look.png").string());
  ASSERT_EQ(plain.width, look.width);
  ASSERT_EQ(plain.height, look.height);
  const ImageDiffStats d =
      CompareRgb(plain.pixels.data(), look.pixels.data(), plain.width, plain.height, 32);
  EXPECT_GT(d.fraction_over, 0.10) << d.fraction_over;
  nlohmann::json a = nlohmann::json::parse(ReadFile(g.dir() / "push_reset_external_state.json"));
  nlohmann::json b =
      nlohmann::json::parse(ReadFile(g.dir() / "push_reset_external_look_state.json"));
  a.erase("scene");
  b.erase("scene");
  EXPECT_EQ(a, b);

  EXPECT_EQ(g.Run("check", "--backend osmesa --only push_reset_external_look").exit_code, 0);
  g.Scene("push_reset_external_look")["look_seed"] = 12;
  g.SaveManifest();
  const CommandResult other = g.Run("check", "--backend osmesa --only push_reset_external_look");
  EXPECT_EQ(other.exit_code, 1) << other.output;
  EXPECT_NE(other.output.find("state equal, pixels differ"), std::string::npos) << other.output;
}

// A malformed look field: one line naming the member and what is accepted, exit 2.
TEST(GoldenLook, AMalformedLookFieldIsOneLineExit2) {
  const struct {
    const char* member;
    nlohmann::json value;
    bool drop_randomize;
    const char* says;
  } cases[] = {
      {"randomize", "colours,camera", false,
       "\"randomize\": 'colours' is not a kind (did you mean 'colors'?)"},
      {"randomize", 3, false, "\"randomize\" must be a string"},
      {"look_seed", -1, false, "\"look_seed\" must be a non-negative integer"},
      {"look_seed", 5, true, "\"look_seed\" needs \"randomize\""},
  };
  for (const auto& c : cases) {
    Goldens g;
    nlohmann::json& scene = g.Scene("push_reset_external_look");
    scene[c.member] = c.value;
    if (c.drop_randomize) scene.erase("randomize");
    g.SaveManifest();
    const CommandResult r = g.Run("check", "--backend osmesa --only reach_reset");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(c.says), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("scene 'push_reset_external_look'"), std::string::npos) << r.output;
    int lines = 0;
    for (char ch : r.output) lines += ch == '\n';
    EXPECT_EQ(lines, 1) << r.output;
  }
}

}  // namespace
}  // namespace fetchscope
