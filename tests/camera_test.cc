// --camera and --overlay parsing, and the MuJoCo cameras they become.
#include "render/camera.h"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "base/errors.h"
#include "cli/view_options.h"
#include "render/overlay.h"
#include "src/mj_handles.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

// A tiny model with two named cameras and the body the track camera follows.
constexpr char kModelXml[] = R"(
<mujoco>
  <worldbody>
    <camera name="overhead" pos="0 0 3"/>
    <body name="robot0:gripper_link" pos="1 0.5 0.4">
      <geom type="sphere" size="0.05"/>
      <camera name="wrist_cam" pos="0 0 0.1"/>
    </body>
  </worldbody>
</mujoco>
)";

constexpr char kNoGripperXml[] = R"(
<mujoco><worldbody><geom type="sphere" size="0.05"/></worldbody></mujoco>
)";

MjModelPtr LoadString(const char* xml) {
  testing::TempDir dir;
  std::string path = (dir.path() / "model.xml").string();
  std::ofstream(path) << xml;
  char error[1000] = "";
  MjModelPtr model(mj_loadXML(path.c_str(), nullptr, error, sizeof(error)));
  EXPECT_TRUE(model) << error;
  return model;
}

const mjModel* Model() {
  static MjModelPtr model = LoadString(kModelXml);
  return model.get();
}

using K = CameraSpec::Kind;

// One valid spec and what it must parse to.
struct ValidCase {
  std::string spec;
  std::vector<K> kinds;
  std::vector<std::string> names;  // expected CameraSpec::name per camera ("" = don't care)
};

void PrintTo(const ValidCase& c, std::ostream* os) { *os << "'" << c.spec << "'"; }

class ValidCameraSpec : public ::testing::TestWithParam<ValidCase> {};

TEST_P(ValidCameraSpec, Parses) {
  const ValidCase& c = GetParam();
  std::vector<CameraSpec> cameras = ParseCameraList(c.spec, Model());
  ASSERT_EQ(cameras.size(), c.kinds.size()) << c.spec;
  for (size_t i = 0; i < cameras.size(); ++i) {
    EXPECT_EQ(cameras[i].kind, c.kinds[i]) << c.spec << " #" << i;
    if (i < c.names.size() && !c.names[i].empty()) {
      EXPECT_EQ(cameras[i].name, c.names[i]);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    Specs, ValidCameraSpec,
    ::testing::Values(
        ValidCase{"default", {K::kDefault}, {}}, ValidCase{"track", {K::kTrack}, {}},
        ValidCase{"free", {K::kFree}, {}}, ValidCase{"overhead", {K::kNamed}, {"overhead"}},
        ValidCase{"free:distance=1.5", {K::kFree}, {}},
        ValidCase{"free:lookat=1,0.7,0.5,distance=2,azimuth=90,elevation=-30", {K::kFree}, {}},
        ValidCase{"default,track", {K::kDefault, K::kTrack}, {}},
        ValidCase{"free:lookat=1,2,3,wrist_cam", {K::kFree, K::kNamed}, {"", "wrist_cam"}},
        ValidCase{"overhead,free:azimuth=-10,elevation=-5,default",
                  {K::kNamed, K::kFree, K::kDefault},
                  {"overhead"}},
        ValidCase{"free:elevation=-14.5,free:azimuth=3", {K::kFree, K::kFree}, {}},
        ValidCase{"default,default,default,default",
                  {K::kDefault, K::kDefault, K::kDefault, K::kDefault},
                  {}}));

TEST(CameraSpec, FreeKeysOverrideOnlyWhatTheyName) {
  std::vector<CameraSpec> cameras =
      ParseCameraList("free:lookat=1,0.7,0.5,elevation=-30,wrist_cam", Model());
  ASSERT_EQ(cameras.size(), 2u);
  const FreeCamera& f = cameras[0].free;
  EXPECT_DOUBLE_EQ(f.lookat[0], 1.0);
  EXPECT_DOUBLE_EQ(f.lookat[1], 0.7);
  EXPECT_DOUBLE_EQ(f.lookat[2], 0.5);
  EXPECT_DOUBLE_EQ(f.elevation, -30.0);
  EXPECT_DOUBLE_EQ(f.distance, 2.5);   // from the default camera
  EXPECT_DOUBLE_EQ(f.azimuth, 132.0);  // from the default camera
}

TEST(CameraSpec, DefaultIsGymnasiumsCamera) {
  CameraSpec spec = ParseCameraList("default", Model())[0];
  EXPECT_DOUBLE_EQ(spec.free.distance, 2.5);
  EXPECT_DOUBLE_EQ(spec.free.azimuth, 132.0);
  EXPECT_DOUBLE_EQ(spec.free.elevation, -14.0);
  EXPECT_DOUBLE_EQ(spec.free.lookat[0], 1.3);
  EXPECT_DOUBLE_EQ(spec.free.lookat[1], 0.75);
  EXPECT_DOUBLE_EQ(spec.free.lookat[2], 0.55);
}

// The kinds are listed once (CameraKinds): each parses by its name (free with a key), and a
// misspelt one is refused with the nearest kind and every kind's accepted forms.
TEST(CameraSpec, EveryKindOfTheListParsesAndIsNamedInTheRefusal) {
  ASSERT_EQ(CameraKinds().size(), 3u);
  for (const CameraKind& kind : CameraKinds()) {
    const std::string text =
        std::string(kind.completion) + (kind.completion.back() == ':' ? "azimuth=90" : "");
    EXPECT_NO_THROW(ParseCameraList(text, Model())) << text;
  }
  try {
    ParseCameraList("trak", Model());
    FAIL() << "'trak' should be rejected";
  } catch (const UsageError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("did you mean 'track'?"), std::string::npos) << message;
    for (const CameraKind& kind : CameraKinds()) {
      EXPECT_NE(message.find(std::string(kind.forms)), std::string::npos) << kind.name;
    }
  }
}

// One invalid spec and the substrings its message must hold.
struct InvalidCase {
  std::string spec;
  std::vector<std::string> expected;
};

void PrintTo(const InvalidCase& c, std::ostream* os) { *os << "'" << c.spec << "'"; }

class InvalidCameraSpec : public ::testing::TestWithParam<InvalidCase> {};

TEST_P(InvalidCameraSpec, ThrowsUsageErrorSayingWhy) {
  const InvalidCase& c = GetParam();
  try {
    ParseCameraList(c.spec, Model());
    FAIL() << "'" << c.spec << "' should be rejected";
  } catch (const UsageError& e) {
    std::string message = e.what();
    for (const std::string& s : c.expected) {
      EXPECT_NE(message.find(s), std::string::npos) << "'" << s << "' not in: " << message;
    }
    EXPECT_EQ(message.find('\n'), std::string::npos) << "one line: " << message;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Specs, InvalidCameraSpec,
    ::testing::Values(InvalidCase{"", {"empty entry"}},
                      InvalidCase{"default,,track", {"empty entry"}},
                      InvalidCase{"nope",
                                  {"camera 'nope' is not known",
                                   "model cameras: overhead, wrist_cam", "free:lookat=x,y,z"}},
                      InvalidCase{"default,Overhead", {"'Overhead'", "overhead, wrist_cam"}},
                      InvalidCase{"free:zoom=2", {"unknown key 'zoom'", "lookat, distance"}},
                      InvalidCase{"free:lookat=1,2", {"lookat needs three numbers"}},
                      InvalidCase{"free:lookat=1,2,x", {"lookat needs three numbers"}},
                      InvalidCase{"free:distance=-1", {"distance must be > 0"}},
                      InvalidCase{"free:distance=abc", {"distance needs a number", "'abc'"}},
                      InvalidCase{"free:distance=nan", {"distance needs a number"}},
                      InvalidCase{"free:azimuth=1,azimuth=2", {"key 'azimuth' given twice"}},
                      InvalidCase{"free:elevation=100", {"elevation must be within -90..90"}},
                      InvalidCase{"free:", {"expected key=value"}},
                      InvalidCase{"distance=2", {"camera 'distance=2' is not known"}}));

TEST(CameraSpec, TrackNeedsTheGripperBody) {
  MjModelPtr model = LoadString(kNoGripperXml);
  try {
    ParseCameraList("track", model.get());
    FAIL();
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("robot0:gripper_link"), std::string::npos) << e.what();
  }
  try {
    ParseCameraList("overhead", model.get());
    FAIL();
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("this model names none"), std::string::npos) << e.what();
  }
}

TEST(CameraSpec, BecomesMujocoCameras) {
  std::vector<CameraSpec> cameras =
      ParseCameraList("wrist_cam,track,free:distance=3,default", Model());
  mjvCamera named = ToMjvCamera(cameras[0], Model());
  EXPECT_EQ(named.type, mjCAMERA_FIXED);
  EXPECT_EQ(named.fixedcamid, mj_name2id(Model(), mjOBJ_CAMERA, "wrist_cam"));

  mjvCamera track = ToMjvCamera(cameras[1], Model());
  EXPECT_EQ(track.type, mjCAMERA_TRACKING);
  EXPECT_EQ(track.trackbodyid, mj_name2id(Model(), mjOBJ_BODY, "robot0:gripper_link"));
  EXPECT_GT(track.distance, 0.5);
  EXPECT_LT(track.distance, 2.0);

  mjvCamera free = ToMjvCamera(cameras[2], Model());
  EXPECT_EQ(free.type, mjCAMERA_FREE);
  EXPECT_DOUBLE_EQ(free.distance, 3.0);
  EXPECT_DOUBLE_EQ(free.azimuth, 132.0);

  mjvCamera standard = ToMjvCamera(cameras[3], Model());
  EXPECT_EQ(standard.type, mjCAMERA_FREE);
  EXPECT_DOUBLE_EQ(standard.lookat[0], 1.3);
  EXPECT_DOUBLE_EQ(standard.elevation, -14.0);
}

// track:body=NAME follows any body, with the tracking camera's pose keys; it ends at the next
// camera as a free camera does
TEST(CameraSpec, TrackFollowsTheBodyItNames) {
  std::vector<CameraSpec> cameras = ParseCameraList(
      "track:body=robot0:gripper_link,distance=0.6,azimuth=10,elevation=-45,overhead", Model());
  ASSERT_EQ(cameras.size(), 2u);
  EXPECT_EQ(cameras[0].kind, K::kTrack);
  EXPECT_EQ(cameras[0].body, "robot0:gripper_link");
  EXPECT_DOUBLE_EQ(cameras[0].free.distance, 0.6);
  EXPECT_DOUBLE_EQ(cameras[0].free.azimuth, 10);
  EXPECT_DOUBLE_EQ(cameras[0].free.elevation, -45);
  EXPECT_EQ(cameras[1].kind, K::kNamed);
  const mjvCamera mj = ToMjvCamera(cameras[0], Model());
  EXPECT_EQ(mj.type, mjCAMERA_TRACKING);
  EXPECT_DOUBLE_EQ(mj.distance, 0.6);
  for (const auto& [spec, says] : std::vector<std::pair<std::string, std::string>>{
           {"track:body=robot0:gripper_lnk", "did you mean 'robot0:gripper_link'"},
           {"track:body=", "body needs a body's name"},
           {"track:lookat=1,2,3", "unknown key 'lookat' (keys: body, distance"},
           {"free:body=world", "unknown key 'body' (keys: lookat, distance"}}) {
    try {
      ParseCameraList(spec, Model());
      ADD_FAILURE() << spec << " was accepted";
    } catch (const UsageError& e) {
      EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << spec << ": " << e.what();
    }
  }
}

// CameraText writes a camera as a --camera value that parses back to the same camera
TEST(CameraSpec, CameraTextParsesBackToTheSameCamera) {
  for (const std::string spec :
       {"default", "track", "overhead",
        "free:lookat=1.25,-0.5,0.6,distance=1.5,azimuth=-33.25,elevation=12",
        "track:body=robot0:gripper_link,distance=0.75,azimuth=200,elevation=-89.5"}) {
    const CameraSpec a = ParseCameraList(spec, Model())[0];
    const std::string text = CameraText(a);
    const std::vector<CameraSpec> back = ParseCameraList(text, Model());
    ASSERT_EQ(back.size(), 1u) << text;
    const CameraSpec& b = back[0];
    EXPECT_EQ(a.kind, b.kind) << text;
    EXPECT_EQ(a.body, b.body) << text;
    for (int k = 0; k < 3; ++k) EXPECT_EQ(a.free.lookat[k], b.free.lookat[k]) << text;
    EXPECT_EQ(a.free.distance, b.free.distance) << text;
    EXPECT_EQ(a.free.azimuth, b.free.azimuth) << text;
    EXPECT_EQ(a.free.elevation, b.free.elevation) << text;
  }
  EXPECT_EQ(CameraText(ParseCameraList("free:distance=2", Model())[0]),
            "free:lookat=1.3,0.75,0.55,distance=2,azimuth=132,elevation=-14");
  EXPECT_EQ(CameraText(ParseCameraList("track", Model())[0]), "track");
}

// --overlay
struct OverlayCase {
  std::string spec;
  OverlaySet expected;
};

void PrintTo(const OverlayCase& c, std::ostream* os) { *os << "'" << c.spec << "'"; }

class OverlaySpec : public ::testing::TestWithParam<OverlayCase> {};

TEST_P(OverlaySpec, Parses) {
  OverlaySet got = ParseOverlays(GetParam().spec);
  const OverlaySet& want = GetParam().expected;
  EXPECT_EQ(got.goal, want.goal);
  EXPECT_EQ(got.achieved, want.achieved);
  EXPECT_EQ(got.hud, want.hud);
  EXPECT_EQ(got.action, want.action);
  EXPECT_EQ(got.trail, want.trail);
  EXPECT_EQ(got.labels, want.labels);
  EXPECT_EQ(got.hindsight, want.hindsight);
}

INSTANTIATE_TEST_SUITE_P(
    Specs, OverlaySpec,
    ::testing::Values(OverlayCase{"default", {true, true, true, false, false, true, false}},
                      OverlayCase{"none", {false, false, false, false, false, false, false}},
                      OverlayCase{"goal", {true, false, false, false, false, false, false}},
                      OverlayCase{"hud,trail", {false, false, true, false, true, false, false}},
                      OverlayCase{"default,action", {true, true, true, true, false, true, false}},
                      OverlayCase{"labels,hindsight",
                                  {false, false, false, false, false, true, true}},
                      OverlayCase{"goal,achieved,hud,action,trail",
                                  {true, true, true, true, true, false, false}}));

TEST(OverlaySpec, RejectsUnknownNames) {
  for (const char* bad : {"sparkles", "goal,sparkles", "", "goal,", "GOAL"}) {
    try {
      ParseOverlays(bad);
      FAIL() << "'" << bad << "' should be rejected";
    } catch (const UsageError& e) {
      std::string message = e.what();
      EXPECT_NE(message.find("is not known"), std::string::npos) << message;
      EXPECT_NE(message.find("goal, achieved, hud, action, trail, labels, hindsight"),
                std::string::npos)
          << message;
    }
  }
}

TEST(HudPlacement, PositionsAndOpacityParse) {
  EXPECT_EQ(cli::ParseHudPosition("top-left"), HudPosition::kTopLeft);
  EXPECT_EQ(cli::ParseHudPosition("bottom-right"), HudPosition::kBottomRight);
  for (HudPosition p : {HudPosition::kTopLeft, HudPosition::kTopRight, HudPosition::kBottomLeft,
                        HudPosition::kBottomRight}) {
    EXPECT_EQ(cli::ParseHudPosition(HudPositionName(p)), p);
  }
  for (const char* bad : {"", "top", "TOP-LEFT", "center"}) {
    try {
      cli::ParseHudPosition(bad);
      FAIL() << bad;
    } catch (const UsageError& e) {
      EXPECT_NE(std::string(e.what()).find("top-left, top-right, bottom-left, bottom-right"),
                std::string::npos);
    }
  }
  EXPECT_EQ(cli::CheckHudOpacity(0), 0);
  EXPECT_EQ(cli::CheckHudOpacity(1), 1);
  EXPECT_THROW(cli::CheckHudOpacity(1.5), UsageError);
  EXPECT_THROW(cli::CheckHudOpacity(-0.1), UsageError);
  EXPECT_THROW(cli::CheckHudOpacity(NAN), UsageError);
}

TEST(HudPlacement, GrowsWithTheTileAndStaysInside) {
  FrameInfo info;
  info.title = "FetchPickAndPlace-v4";
  const HudText hud = FormatHud(info, OverlaySet{});
  EXPECT_EQ(HudTextPixels(480, 480), 13);
  EXPECT_EQ(HudTextPixels(1920, 1080), 29);
  EXPECT_EQ(HudTextPixels(2160, 3840), 58);
  const PixelRect tile{100, 50, 960, 960};
  for (HudPosition p : {HudPosition::kTopLeft, HudPosition::kTopRight, HudPosition::kBottomLeft,
                        HudPosition::kBottomRight}) {
    const auto box = PlaceHud(hud, tile, p);
    ASSERT_TRUE(box.has_value());
    EXPECT_GE(box->x, tile.x);
    EXPECT_GE(box->y, tile.y);
    EXPECT_LE(box->x + box->width, tile.x + tile.width);
    EXPECT_LE(box->y + box->height, tile.y + tile.height);
  }
  const auto small = PlaceHud(hud, PixelRect{0, 0, 480, 480}, HudPosition::kTopLeft);
  const auto large = PlaceHud(hud, PixelRect{0, 0, 960, 960}, HudPosition::kTopLeft);
  ASSERT_TRUE(small && large);
  // twice the text size: about twice the box (FreeType's hinting rounds each size on its own)
  EXPECT_NEAR(large->width, 2.0 * small->width, 0.1 * small->width);
  EXPECT_NEAR(large->height, 2.0 * small->height, 0.1 * small->height);
  EXPECT_FALSE(PlaceHud(hud, PixelRect{0, 0, 100, 100}, HudPosition::kTopLeft).has_value());
}

}  // namespace
}  // namespace fetchscope
