// The command line's view options and --format, parsed once into typed values
// (cli/view_options.h): cameras resolved against the model, overlays, msaa, readback, HUD,
// backend and GPU request, and --format as rows of the one format table.
#include "cli/view_options.h"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <stdlib.h>

#include <fstream>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "base/errors.h"
#include "src/mj_handles.h"
#include "tests/test_util.h"

namespace fetchscope::cli {
namespace {

// A tiny model with one named camera and the body the track camera follows.
constexpr char kModelXml[] = R"(
<mujoco>
  <worldbody>
    <camera name="overhead" pos="0 0 3"/>
    <body name="robot0:gripper_link" pos="1 0.5 0.4">
      <geom type="sphere" size="0.05"/>
    </body>
  </worldbody>
</mujoco>
)";

const mjModel* Model() {
  static MjModelPtr model = [] {
    testing::TempDir dir;
    const std::string path = (dir.path() / "model.xml").string();
    std::ofstream(path) << kModelXml;
    char error[1000] = "";
    MjModelPtr loaded(mj_loadXML(path.c_str(), nullptr, error, sizeof(error)));
    EXPECT_TRUE(loaded) << error;
    return loaded;
  }();
  return model.get();
}

// The UsageError message `body` throws ("" when it throws none).
template <typename Body>
std::string UsageMessage(Body body) {
  try {
    body();
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}

// Sets an environment variable for one scope, restoring what was there.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value != nullptr) {
      setenv(name, value, 1);
    } else {
      unsetenv(name);
    }
  }
  ~ScopedEnv() {
    if (old_) {
      setenv(name_, old_->c_str(), 1);
    } else {
      unsetenv(name_);
    }
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

TEST(ViewOptionsTest, DefaultsBecomeTheRenderersDefaults) {
  const RenderOptions r = ResolveRenderOptions(ViewOptions{}, Model());
  EXPECT_EQ(r.width, 480);
  EXPECT_EQ(r.height, 480);
  ASSERT_EQ(r.cameras.size(), 1u);
  EXPECT_EQ(r.cameras[0].kind, CameraSpec::kDefault);
  EXPECT_EQ(r.cameras[0].name, "default");
  EXPECT_TRUE(r.overlays.goal && r.overlays.achieved && r.overlays.hud && r.overlays.labels);
  EXPECT_FALSE(r.overlays.action || r.overlays.trail || r.overlays.hindsight);
  EXPECT_EQ(r.msaa_samples, kMsaaAuto);
  EXPECT_EQ(r.readback, Readback::kAuto);
  EXPECT_EQ(r.hud_position, HudPosition::kTopLeft);
  EXPECT_DOUBLE_EQ(r.hud_opacity, 0.6);
}

TEST(ViewOptionsTest, CamerasAreResolvedAgainstTheModel) {
  ViewOptions view;
  view.camera = "overhead, track, free:lookat=1,0.7,0.5,distance=2";
  view.width = 64;
  view.height = 48;
  const RenderOptions r = ResolveRenderOptions(view, Model());
  ASSERT_EQ(r.cameras.size(), 3u);
  EXPECT_EQ(r.cameras[0].kind, CameraSpec::kNamed);
  EXPECT_EQ(r.cameras[0].name, "overhead");
  EXPECT_EQ(r.cameras[1].kind, CameraSpec::kTrack);
  EXPECT_EQ(r.cameras[2].kind, CameraSpec::kFree);
  EXPECT_EQ(r.cameras[2].name, "free:lookat=1,0.7,0.5,distance=2");  // one camera, not four
  EXPECT_DOUBLE_EQ(r.cameras[2].free.distance, 2);
  EXPECT_EQ(r.width, 64);
  EXPECT_EQ(r.height, 48);
  const FrameDims frame = FrameSize(r);
  EXPECT_EQ(frame.width, 3 * 64);
  EXPECT_EQ(frame.height, 48);

  // a camera the model lacks is refused, naming the model's own
  view.camera = "overheda";
  const std::string message = UsageMessage([&] { ResolveRenderOptions(view, Model()); });
  EXPECT_NE(message.find("'overheda'"), std::string::npos) << message;
  EXPECT_NE(message.find("did you mean 'overhead'?"), std::string::npos) << message;
  view.camera = "wrist_cam";  // a Fetch camera, but not in this model
  EXPECT_NE(UsageMessage([&] { ResolveRenderOptions(view, Model()); }).find("overhead"),
            std::string::npos);
}

TEST(ViewOptionsTest, OverlaysHudAndReadbackBecomeTypes) {
  ViewOptions view;
  view.overlay = "action, trail";
  view.hud_position = "bottom-right";
  view.hud_opacity = 0.25;
  view.readback = "sync";
  view.msaa = "8";
  const RenderOptions r = ResolveRenderOptions(view, Model());
  EXPECT_TRUE(r.overlays.action);
  EXPECT_TRUE(r.overlays.trail);
  EXPECT_FALSE(r.overlays.goal || r.overlays.hud || r.overlays.achieved);
  EXPECT_EQ(r.hud_position, HudPosition::kBottomRight);
  EXPECT_DOUBLE_EQ(r.hud_opacity, 0.25);
  EXPECT_EQ(r.readback, Readback::kSync);
  EXPECT_EQ(r.msaa_samples, 8);
  EXPECT_EQ(ParseReadback("async"), Readback::kAsync);
  EXPECT_EQ(ParseReadback("auto"), Readback::kAuto);
}

TEST(ViewOptionsTest, BadValuesAreRefusedWithOneLineNamingThem) {
  const std::vector<std::pair<ViewOptions, std::string>> cases = [] {
    std::vector<std::pair<ViewOptions, std::string>> out;
    ViewOptions v;
    v.overlay = "goal, hdu";
    out.push_back({v, "'hdu' in 'goal, hdu' is not known (did you mean 'hud'?)"});
    v = ViewOptions{};
    v.hud_position = "middle";
    out.push_back({v, "middle"});
    v = ViewOptions{};
    v.hud_opacity = 1.5;
    out.push_back({v, "1.5"});
    v = ViewOptions{};
    v.msaa = "3";
    out.push_back({v, "--msaa '3' is not accepted; use auto, 0, 1, 2, 4, 8, 16"});
    v = ViewOptions{};
    v.readback = "later";
    out.push_back({v, "--readback 'later' is not accepted; use auto, sync or async"});
    v = ViewOptions{};
    v.camera = "";
    out.push_back({v, "camera"});
    v = ViewOptions{};  // 5 tiles of 4096 x 4096: over the frame limit, refused before any work
    v.camera = "default,default,default,default,default";
    v.width = v.height = 4096;
    out.push_back({v, "4096"});
    return out;
  }();
  for (const auto& [view, expected] : cases) {
    // (a structured binding is captured by name only from C++20: clang 14 refuses it)
    const std::string message = UsageMessage([&, &view = view] { ResolveView(view, Model()); });
    EXPECT_NE(message.find(expected), std::string::npos) << "'" << message << "'";
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

TEST(ViewOptionsTest, ParseMsaaAcceptsAutoAndTheCounts) {
  EXPECT_EQ(ParseMsaa("auto"), kMsaaAuto);
  for (int n : {0, 1, 2, 4, 8, 16}) EXPECT_EQ(ParseMsaa(std::to_string(n)), n);
  for (const char* bad : {"3", "-1", "32", "four", ""}) {
    const std::string message = UsageMessage([&] { ParseMsaa(bad); });
    EXPECT_NE(message.find(std::string("'") + bad + "'"), std::string::npos) << message;
    EXPECT_NE(message.find("auto, 0, 1, 2, 4, 8, 16"), std::string::npos) << message;
  }
}

TEST(ViewOptionsTest, BackendAndGpuAreResolvedOnceFromTheOptionsAndTheEnvironment) {
  const ScopedEnv no_egl_device("MUJOCO_EGL_DEVICE_ID", nullptr);
  const ScopedEnv no_cuda("CUDA_VISIBLE_DEVICES", nullptr);
  ViewOptions view;
  view.backend = "osmesa";
  view.gpu = "0,2";
  ViewSetup setup = ResolveGlView(view);
  EXPECT_EQ(setup.backend, GlBackend::kOsmesa);
  EXPECT_EQ(setup.gpu.kind, GpuSpec::Kind::kEgl);
  EXPECT_EQ(setup.gpu.ids, (std::vector<int>{0, 2}));
  // osmesa renders on no device: the request resolves to auto without enumerating any
  EXPECT_TRUE(ResolveGpuChoice(setup).devices.empty());
  view.backend = "egl";
  view.gpu = "cuda:1";
  setup = ResolveGlView(view);
  EXPECT_EQ(setup.backend, GlBackend::kEgl);
  EXPECT_EQ(setup.gpu.kind, GpuSpec::Kind::kCuda);
  view.gpu = "";
  EXPECT_EQ(ResolveGlView(view).gpu.kind, GpuSpec::Kind::kAuto);
  {
    const ScopedEnv device("MUJOCO_EGL_DEVICE_ID", "3");  // the environment's request
    const GpuSpec spec = ResolveGlView(view).gpu;
    EXPECT_EQ(spec.kind, GpuSpec::Kind::kEgl);
    EXPECT_EQ(spec.ids, std::vector<int>{3});
  }
  // no --backend: $MUJOCO_GL, else auto
  view.backend = "";
  {
    const ScopedEnv gl("MUJOCO_GL", "osmesa");
    EXPECT_EQ(ResolveGlView(view).backend, GlBackend::kOsmesa);
  }
  {
    const ScopedEnv gl("MUJOCO_GL", nullptr);
    EXPECT_EQ(ResolveGlView(view).backend, GlBackend::kAuto);
  }
  {
    const ScopedEnv gl("MUJOCO_GL", "vulkan");
    EXPECT_NE(UsageMessage([&] { ResolveGlView(view); }).find("MUJOCO_GL 'vulkan' is not known"),
              std::string::npos);
  }
  view.backend = "vulkan";
  EXPECT_NE(UsageMessage([&] { ResolveGlView(view); }).find("backend 'vulkan' is not known"),
            std::string::npos);
  view.backend = "auto";
  view.gpu = "-7";
  EXPECT_NE(UsageMessage([&] { ResolveGlView(view); }).find("-7"), std::string::npos);
}

TEST(ViewOptionsTest, ResolveViewCarriesTheRenderOptionsAndTheContextChoice) {
  ViewOptions view;
  view.camera = "track";
  view.backend = "osmesa";
  view.width = 32;
  const ViewSetup setup = ResolveView(view, Model());
  EXPECT_EQ(setup.backend, GlBackend::kOsmesa);
  ASSERT_EQ(setup.render.cameras.size(), 1u);
  EXPECT_EQ(setup.render.cameras[0].kind, CameraSpec::kTrack);
  EXPECT_EQ(setup.render.width, 32);
  // a bad camera is reported before a bad backend, as the commands always reported them
  view.camera = "nosuchcam";
  view.backend = "vulkan";
  EXPECT_NE(UsageMessage([&] { ResolveView(view, Model()); }).find("nosuchcam"), std::string::npos);
}

TEST(VideoFormatsOptionTest, ParsesCommaListsIntoTheTablesRows) {
  const std::vector<const VideoFormat*> one = ParseVideoFormats("mp4");
  ASSERT_EQ(one.size(), 1u);
  EXPECT_EQ(one[0], &VideoFormats()[0]);  // the table's own row, not a copy
  const std::vector<const VideoFormat*> three = ParseVideoFormats("webm,gif,mp4");
  EXPECT_EQ(three, (std::vector<const VideoFormat*>{FindVideoFormat("webm"), FindVideoFormat("gif"),
                                                    FindVideoFormat("mp4")}));
  EXPECT_EQ(three[1]->pixels, VideoPixels::kPal8);
  EXPECT_EQ(VideoFormatNames(three), (std::vector<std::string>{"webm", "gif", "mp4"}));
  // spaces after the commas, as every other list option takes them
  EXPECT_EQ(VideoFormatNames(ParseVideoFormats("mp4, gif")),
            (std::vector<std::string>{"mp4", "gif"}));
  for (const auto& [list, expected] : std::vector<std::pair<std::string, std::string>>{
           {"avi",
            "unknown --format 'avi' in 'avi': accepted a comma list of mp4, webm, gif, apng"},
           {"mp4,", "unknown --format '' in 'mp4,'"},
           {"", "unknown --format ''"},
           {"MP4", "unknown --format 'MP4'"},
           {"gif,webm,gif", "--format 'gif,webm,gif' names gif twice: give each format once"},
           {"mp4, gfi", "unknown --format 'gfi' in 'mp4, gfi' (did you mean 'gif'?)"},
           {"mp4, mp4", "names mp4 twice"}}) {
    const std::string message = UsageMessage([&, &list = list] { ParseVideoFormats(list); });
    EXPECT_NE(message.find(expected), std::string::npos) << "'" << list << "': " << message;
  }
}

}  // namespace
}  // namespace fetchscope::cli
