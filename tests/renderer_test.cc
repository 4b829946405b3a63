// The renderer on real GL contexts and the real Fetch PickAndPlace model (the genuine
// Gymnasium-Robotics assets and the bundled model, each skipped when absent); the segmentation
// layer without the mocap crosshair.
#include "render/renderer.h"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <time.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "base/errors.h"
#include "cli/view_options.h"
#include "encode/png_io.h"
#include "encode/video_options.h"
#include "encode/video_writer.h"
#include "render/gl_context.h"
#include "render/view.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/episode.h"
#include "src/fetch_env.h"
#include "src/hindsight.h"
#include "src/mj_handles.h"
#include "src/policy.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using testing::CommandResult;
using testing::ReadFile;
using testing::RunFetchscope;
using testing::TempDir;

constexpr int kSize = 480;

void OnMujocoError(const char* message) {
  // MuJoCo's default handler waits for Enter; a test must fail instead.
  std::fprintf(stderr, "MuJoCo error: %s\n", message);
  std::_Exit(1);
}

fs::path ModelPath(const std::string& source) {
  if (source == "genuine") {
    fs::path dir = testing::GenuineAssetsDir();
    return dir.empty() ? fs::path() : dir / "fetch" / "pick_and_place.xml";
  }
  return testing::SourceDir() / "models" / "pick_and_place.xml";
}

struct Rgb {
  int r, g, b;
};

// A projected point: column from the left, row from the top.
struct Pixel {
  int col, row;
};

// Projects world point `p` with MuJoCo's free camera `cam` (vertical field of view fovy):
// forward = (cos el cos az, cos el sin az, sin el), eye = lookat - distance * forward,
// up = (-sin el cos az, -sin el sin az, cos el), right = forward x up.
Pixel Project(const FreeCamera& cam, const std::array<double, 3>& p, int width, int height,
              double fovy_degrees) {
  const double az = cam.azimuth * M_PI / 180, el = cam.elevation * M_PI / 180;
  const double f[3] = {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
  const double u[3] = {-std::sin(el) * std::cos(az), -std::sin(el) * std::sin(az), std::cos(el)};
  const double r[3] = {f[1] * u[2] - f[2] * u[1], f[2] * u[0] - f[0] * u[2],
                       f[0] * u[1] - f[1] * u[0]};
  double v[3];
  for (int k = 0; k < 3; ++k) v[k] = p[k] - (cam.lookat[k] - cam.distance * f[k]);
  const double x = v[0] * r[0] + v[1] * r[1] + v[2] * r[2];
  const double y = v[0] * u[0] + v[1] * u[1] + v[2] * u[2];
  const double z = v[0] * f[0] + v[1] * f[1] + v[2] * f[2];
  const double t = std::tan(fovy_degrees * M_PI / 360);
  const double aspect = static_cast<double>(width) / height;
  const double ndc_x = x / (z * t * aspect), ndc_y = y / (z * t);
  return Pixel{static_cast<int>(std::floor((ndc_x + 1) / 2 * width)),
               static_cast<int>(std::floor((1 - ndc_y) / 2 * height))};
}

// Distance from the default camera's eye to `p` along the view axis.
double ViewDepth(const FreeCamera& cam, const std::array<double, 3>& p) {
  const double az = cam.azimuth * M_PI / 180, el = cam.elevation * M_PI / 180;
  const double f[3] = {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
  double z = 0;
  for (int k = 0; k < 3; ++k) z += (p[k] - (cam.lookat[k] - cam.distance * f[k])) * f[k];
  return z;
}

Rgb At(const std::vector<uint8_t>& image, int width, Pixel p) {
  const uint8_t* q = image.data() + (static_cast<size_t>(p.row) * width + p.col) * 3;
  return Rgb{q[0], q[1], q[2]};
}

bool IsRed(Rgb c) { return c.r > 150 && c.g < 90 && c.b < 90; }
bool IsSky(Rgb c) { return c.g > c.r + 40 && c.g > c.b + 40; }  // the green gradient skybox
bool IsGray(Rgb c) { return std::abs(c.r - c.g) < 16 && std::abs(c.g - c.b) < 16; }
bool IsDarkGray(Rgb c) { return IsGray(c) && c.r < 110; }   // floor_mat 0.2, lit
bool IsLightGray(Rgb c) { return IsGray(c) && c.r > 170; }  // table_mat 0.93, lit

double MeanAbsDiff(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  double sum = 0;
  for (size_t i = 0; i < a.size(); ++i) sum += std::abs(a[i] - b[i]);
  return sum / a.size();
}

// The fraction of pixels that differ in any channel, and their bounding box.
struct Difference {
  double fraction = 0;
  int min_col = 1 << 30, min_row = 1 << 30, max_col = -1, max_row = -1;
};

Difference Compare(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b, int width) {
  Difference d;
  const size_t pixels = a.size() / 3;
  size_t differing = 0;
  for (size_t i = 0; i < pixels; ++i) {
    if (std::memcmp(&a[3 * i], &b[3 * i], 3) == 0) continue;
    ++differing;
    int col = static_cast<int>(i % width), row = static_cast<int>(i / width);
    d.min_col = std::min(d.min_col, col);
    d.max_col = std::max(d.max_col, col);
    d.min_row = std::min(d.min_row, row);
    d.max_row = std::max(d.max_row, row);
  }
  d.fraction = static_cast<double>(differing) / pixels;
  return d;
}

// CIEDE2000 colour difference of two sRGB colours (D65): about 1 is barely noticeable; the
// segmentation palette keeps its colours at least kApartInOneImage apart.
double Ciede2000(const std::array<uint8_t, 3>& rgb1, const std::array<uint8_t, 3>& rgb2) {
  auto lab = [](const std::array<uint8_t, 3>& rgb) {
    double lin[3];
    for (int k = 0; k < 3; ++k) {
      const double c = rgb[k] / 255.0;
      lin[k] = c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
    }
    const double x = (0.4124564 * lin[0] + 0.3575761 * lin[1] + 0.1804375 * lin[2]) / 0.95047;
    const double y = 0.2126729 * lin[0] + 0.7151522 * lin[1] + 0.0721750 * lin[2];
    const double z = (0.0193339 * lin[0] + 0.1191920 * lin[1] + 0.9503041 * lin[2]) / 1.08883;
    auto f = [](double t) {
      return t > 216.0 / 24389 ? std::cbrt(t) : (24389.0 / 27 * t + 16) / 116;
    };
    return std::array<double, 3>{116 * f(y) - 16, 500 * (f(x) - f(y)), 200 * (f(y) - f(z))};
  };
  const auto [l1, a1, b1] = lab(rgb1);
  const auto [l2, a2, b2] = lab(rgb2);
  const double deg = M_PI / 180;
  const double cbar = (std::hypot(a1, b1) + std::hypot(a2, b2)) / 2;
  const double g =
      0.5 * (1 - std::sqrt(std::pow(cbar, 7) / (std::pow(cbar, 7) + std::pow(25.0, 7))));
  const double a1p = (1 + g) * a1, a2p = (1 + g) * a2;
  const double c1p = std::hypot(a1p, b1), c2p = std::hypot(a2p, b2);
  auto hue = [&](double b, double ap) {
    if (b == 0 && ap == 0) return 0.0;
    const double h = std::atan2(b, ap) / deg;
    return h < 0 ? h + 360 : h;
  };
  const double h1p = hue(b1, a1p), h2p = hue(b2, a2p);
  double dhp = 0;
  if (c1p * c2p != 0) {
    dhp = h2p - h1p;
    if (dhp > 180) dhp -= 360;
    if (dhp < -180) dhp += 360;
  }
  const double dl = l2 - l1, dc = c2p - c1p;
  const double dh = 2 * std::sqrt(c1p * c2p) * std::sin(dhp / 2 * deg);
  const double lbar = (l1 + l2) / 2, cbarp = (c1p + c2p) / 2;
  double hbar = h1p + h2p;
  if (c1p * c2p != 0) {
    if (std::abs(h1p - h2p) <= 180) {
      hbar = (h1p + h2p) / 2;
    } else {
      hbar = h1p + h2p < 360 ? (h1p + h2p + 360) / 2 : (h1p + h2p - 360) / 2;
    }
  }
  const double t = 1 - 0.17 * std::cos((hbar - 30) * deg) + 0.24 * std::cos(2 * hbar * deg) +
                   0.32 * std::cos((3 * hbar + 6) * deg) - 0.20 * std::cos((4 * hbar - 63) * deg);
  const double dtheta = 30 * std::exp(-std::pow((hbar - 275) / 25, 2));
  const double rc = 2 * std::sqrt(std::pow(cbarp, 7) / (std::pow(cbarp, 7) + std::pow(25.0, 7)));
  const double sl = 1 + 0.015 * std::pow(lbar - 50, 2) / std::sqrt(20 + std::pow(lbar - 50, 2));
  const double sc = 1 + 0.045 * cbarp, sh = 1 + 0.015 * cbarp * t;
  const double rt = -std::sin(2 * dtheta * deg) * rc;
  return std::sqrt(std::pow(dl / sl, 2) + std::pow(dc / sc, 2) + std::pow(dh / sh, 2) +
                   rt * (dc / sc) * (dh / sh));
}

// Palette indices a Fetch model uses: its bodies (world, robot, table, object) and sites.
constexpr int kFetchObjects = 36;
// The least CIEDE2000 difference between two colours in one segmentation image (Kelly's two
// oranges, the old palette's closest pair in a Fetch image, are 11.8 apart), and among all of
// the palette's colours.
constexpr double kApartInOneImage = 15.0;
constexpr double kApartAll = 14.0;

class RendererTest : public ::testing::TestWithParam<const char*> {
 protected:
  void SetUp() override {
    unsetenv("DISPLAY");
    mju_user_error = OnMujocoError;
    fs::path path = ModelPath(GetParam());
    if (path.empty() || !fs::exists(path)) GTEST_SKIP() << GetParam() << " model is absent";
    char error[1000] = "";
    model_.reset(mj_loadXML(path.string().c_str(), nullptr, error, sizeof(error)));
    if (!model_) GTEST_SKIP() << path << " does not compile (yet?): " << error;
    data_.reset(mj_makeData(model_.get()));

    // The robot where the Fetch env's initial_qpos puts it, the block on the table.
    SetJoint("robot0:slide0", {0.405});
    SetJoint("robot0:slide1", {0.48});
    SetJoint("robot0:slide2", {0.0});
    SetJoint("object0:joint", {1.3, 0.75, 0.425, 1, 0, 0, 0});
    mj_forward(model_.get(), data_.get());

    info_.title = "FetchPickAndPlace-v4";
    info_.goal = {1.4, 0.8, 0.6};  // in the air above the table, in view of the default camera
    const int object = mj_name2id(model_.get(), mjOBJ_SITE, "object0");
    ASSERT_GE(object, 0);
    for (int k = 0; k < 3; ++k) info_.achieved[k] = data_->site_xpos[3 * object + k];
    info_.distance = std::sqrt(std::pow(info_.achieved[0] - info_.goal[0], 2) +
                               std::pow(info_.achieved[1] - info_.goal[1], 2) +
                               std::pow(info_.achieved[2] - info_.goal[2], 2));
    info_.step = 1;
    info_.reward = -info_.distance;
    info_.has_action = true;
    info_.action = {0.5, -0.5, 1.0, -1.0};
  }

  void SetJoint(const char* name, std::vector<double> values) {
    int id = mj_name2id(model_.get(), mjOBJ_JOINT, name);
    ASSERT_GE(id, 0) << name;
    for (size_t k = 0; k < values.size(); ++k) {
      data_->qpos[model_->jnt_qposadr[id] + k] = values[k];
    }
  }

  // A context of `backend`, or nullptr (and the test skipped) when this machine lacks it.
  std::unique_ptr<GlContext> Context(const std::string& backend = "auto") {
    try {
      return CreateGlContext(backend);
    } catch (const RunError& e) {
      std::cout << "[  SKIPPED ] " << backend << " unavailable: " << e.what() << "\n";
      return nullptr;
    }
  }

  std::vector<uint8_t> RenderWith(GlContext& gl, const RenderOptions& options) {
    Renderer renderer(gl, model_.get(), options);
    std::vector<uint8_t> rgb(static_cast<size_t>(renderer.width()) * renderer.height() * 3);
    renderer.Render(data_.get(), info_, rgb.data());
    Dump(options, rgb);
    return rgb;
  }

  // With FETCHSCOPE_TEST_DUMP=DIR, frames are also written there to look at.
  void Dump(const RenderOptions& options, const std::vector<uint8_t>& rgb) {
    const char* dir = std::getenv("FETCHSCOPE_TEST_DUMP");
    if (!dir) return;
    const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(test->name()) + "_" + std::to_string(dumped_++) + ".png";
    for (char& c : name) {
      if (c == '/') c = '_';
    }
    const FrameDims frame = FrameSize(options);
    WritePng((fs::path(dir) / name).string(), frame.width, frame.height, 3, 8, rgb.data());
  }

  static RenderOptions Options(const std::string& overlays, int width = kSize, int height = kSize) {
    RenderOptions options;
    options.width = width;
    options.height = height;
    options.overlays = ParseOverlays(overlays);
    return options;
  }

  double Fovy() const { return model_->vis.global.fovy; }

  MjModelPtr model_;
  MjDataPtr data_;
  FrameInfo info_;
  int dumped_ = 0;
};

TEST_P(RendererTest, BothBackendsAgree) {
  auto osmesa = Context("osmesa");
  auto egl = Context("egl");
  if (!osmesa || !egl) GTEST_SKIP() << "needs both backends";
  std::vector<uint8_t> a = RenderWith(*osmesa, Options("default"));
  std::vector<uint8_t> b = RenderWith(*egl, Options("default"));
  EXPECT_LT(MeanAbsDiff(a, b), 3.0);
  // and again in the other order, on the same contexts
  std::vector<uint8_t> c = RenderWith(*osmesa, Options("default"));
  EXPECT_LT(MeanAbsDiff(a, c), 3.0);
}

TEST_P(RendererTest, BothBackendsAgreeEglFirst) {
  // MuJoCo binds its GL functions at the first mjr_makeContext of the process; either order
  // must work (when the whole binary runs in one process, the first test decides).
  auto egl = Context("egl");
  auto osmesa = Context("osmesa");
  if (!osmesa || !egl) GTEST_SKIP() << "needs both backends";
  std::vector<uint8_t> a = RenderWith(*egl, Options("default"));
  std::vector<uint8_t> b = RenderWith(*osmesa, Options("default"));
  EXPECT_LT(MeanAbsDiff(a, b), 3.0);
}

TEST_P(RendererTest, FrameIsTheRightWayUp) {
  auto gl = Context();
  if (!gl) GTEST_SKIP();
  std::vector<uint8_t> rgb = RenderWith(*gl, Options("none"));
  const FreeCamera cam = DefaultFreeCamera();

  // the goal sphere (target0, moved to the goal) is where the camera projects the goal
  Pixel goal = Project(cam, info_.goal, kSize, kSize, Fovy());
  Rgb at_goal = At(rgb, kSize, goal);
  EXPECT_TRUE(IsRed(at_goal)) << "goal pixel (" << goal.col << "," << goal.row
                              << ") = " << at_goal.r << "," << at_goal.g << "," << at_goal.b;
  // the table top is light, the floor dark, the sky at the top
  Pixel table = Project(cam, {1.2, 0.6, 0.4}, kSize, kSize, Fovy());
  Rgb at_table = At(rgb, kSize, table);
  EXPECT_TRUE(IsLightGray(at_table)) << at_table.r << "," << at_table.g << "," << at_table.b;
  Pixel floor = Project(cam, {1.5, 0.2, 0.0}, kSize, kSize, Fovy());
  Rgb at_floor = At(rgb, kSize, floor);
  EXPECT_TRUE(IsDarkGray(at_floor)) << at_floor.r << "," << at_floor.g << "," << at_floor.b;
  EXPECT_GT(table.row, goal.row);  // the table is below the goal
  EXPECT_GT(floor.row, table.row);
  for (int col = 0; col < kSize; col += 8) {
    Rgb top = At(rgb, kSize, Pixel{col, 0});
    ASSERT_TRUE(IsSky(top)) << "top row, column " << col;
  }
}

TEST_P(RendererTest, GoalMarkerFollowsTheGoal) {
  auto gl = Context();
  if (!gl) GTEST_SKIP();
  Renderer renderer(*gl, model_.get(), Options("none"));
  std::vector<uint8_t> rgb(kSize * kSize * 3);
  for (const std::array<double, 3>& goal :
       {std::array<double, 3>{1.25, 0.65, 0.7}, std::array<double, 3>{1.5, 0.95, 0.5}}) {
    info_.goal = goal;
    renderer.Render(data_.get(), info_, rgb.data());
    Dump(Options("none"), rgb);
    Pixel p = Project(DefaultFreeCamera(), goal, kSize, kSize, Fovy());
    EXPECT_TRUE(IsRed(At(rgb, kSize, p))) << goal[0] << "," << goal[1] << "," << goal[2];
  }
}

TEST_P(RendererTest, OverlaysStayLocal) {
  auto gl = Context();
  if (!gl) GTEST_SKIP();
  std::vector<uint8_t> none = RenderWith(*gl, Options("none"));
  const Pixel goal = Project(DefaultFreeCamera(), info_.goal, kSize, kSize, Fovy());

  // scene overlays: a small part of the frame, including the goal (the translucent shell)
  std::vector<uint8_t> markers = RenderWith(*gl, Options("goal,achieved"));
  Difference d = Compare(none, markers, kSize);
  EXPECT_GT(d.fraction, 0.0005);
  EXPECT_LT(d.fraction, 0.10);
  Rgb a = At(none, kSize, goal), b = At(markers, kSize, goal);
  EXPECT_TRUE(a.r != b.r || a.g != b.g || a.b != b.b) << "the shell should tint the goal";

  // the HUD: only the top-left corner
  std::vector<uint8_t> hud = RenderWith(*gl, Options("hud"));
  d = Compare(none, hud, kSize);
  EXPECT_GT(d.fraction, 0.01);
  EXPECT_LT(d.min_col, 20);
  EXPECT_LT(d.min_row, 20);
  EXPECT_LT(d.max_col, kSize * 3 / 4);
  EXPECT_LT(d.max_row, kSize * 2 / 5);

  // the action arrow draws something, and only near the gripper
  std::vector<uint8_t> arrow = RenderWith(*gl, Options("action"));
  d = Compare(none, arrow, kSize);
  EXPECT_GT(d.fraction, 0.0001);
  EXPECT_LT(d.fraction, 0.05);
  info_.has_action = false;  // at reset there is no arrow
  EXPECT_EQ(Compare(none, RenderWith(*gl, Options("action")), kSize).fraction, 0.0);
}

TEST_P(RendererTest, TrailGrowsWithStepsAndResets) {
  auto gl = Context();
  if (!gl) GTEST_SKIP();
  Renderer renderer(*gl, model_.get(), Options("trail"));
  std::vector<uint8_t> first(kSize * kSize * 3), later(kSize * kSize * 3);
  const std::array<double, 3> start = info_.achieved;
  for (int step = 0; step <= 5; ++step) {
    info_.step = step;
    info_.achieved = {start[0] - 0.04 * step, start[1] + 0.03 * step, start[2] + 0.03 * step};
    renderer.Render(data_.get(), info_, step == 0 ? first.data() : later.data());
  }
  Dump(Options("trail"), later);
  EXPECT_GT(Compare(first, later, kSize).fraction, 0.0002);  // a polyline appeared
  // a new episode's first frame shows no trail again
  renderer.ResetTrail();
  info_.step = 0;
  info_.achieved = start;
  std::vector<uint8_t> reset(kSize * kSize * 3);
  renderer.Render(data_.get(), info_, reset.data());
  EXPECT_EQ(reset, first);
}

TEST_P(RendererTest, RendersFullHd) {
  auto gl = Context();
  if (!gl) GTEST_SKIP();
  std::vector<uint8_t> rgb = RenderWith(*gl, Options("default", 1920, 1080));
  ASSERT_EQ(rgb.size(), 1920u * 1080 * 3);
  Pixel goal = Project(DefaultFreeCamera(), info_.goal, 1920, 1080, Fovy());
  // the shell tints the sphere but it stays red
  Rgb c = At(rgb, 1920, goal);
  EXPECT_TRUE(c.r > 150 && c.g < 110 && c.b < 110) << c.r << "," << c.g << "," << c.b;
  EXPECT_TRUE(IsSky(At(rgb, 1920, Pixel{1900, 5})));
}

TEST_P(RendererTest, RejectsBadSizes) {
  auto gl = Context();
  if (!gl) GTEST_SKIP();
  for (auto [w, h] : {std::pair{0, 480}, std::pair{480, 0}, std::pair{-1, 480},
                      std::pair{100000, 480}, std::pair{480, 100000}}) {
    try {
      Renderer renderer(*gl, model_.get(), Options("none", w, h));
      ADD_FAILURE() << w << "x" << h << " should be rejected";
    } catch (const UsageError& e) {
      std::string message = e.what();
      EXPECT_NE(message.find(std::to_string(w) + "x" + std::to_string(h)), std::string::npos)
          << message;
      EXPECT_NE(message.find("accepted: 1.."), std::string::npos) << message;
    }
  }
  // a rejected size leaves the model's offscreen size alone
  EXPECT_LT(model_->vis.global.offwidth, 100000);
}

TEST_P(RendererTest, RenderingTwiceGivesTheSamePixels) {
  auto gl = Context();
  if (!gl) GTEST_SKIP();
  RenderOptions options = Options("goal,achieved,hud,action,trail");
  options.cameras = ParseCameraList("default,track", model_.get());
  Renderer renderer(*gl, model_.get(), options);
  std::vector<uint8_t> a(2 * kSize * kSize * 3), b(2 * kSize * kSize * 3);
  renderer.Render(data_.get(), info_, a.data());
  renderer.Render(data_.get(), info_, b.data());
  EXPECT_EQ(a, b);
}

// Asynchronous readback (pixel buffer objects, frames in flight) gives the synchronous
// pixels, frame for frame, on both backends, with and without multisampling, at a width whose
// rows are not a multiple of 4 bytes, and with the gripper moving between frames so that a
// frame read from the wrong buffer would show.
TEST_P(RendererTest, AsyncReadbackGivesTheSamePixelsFrameForFrame) {
  for (const char* backend : {"egl", "osmesa"}) {
    auto gl = Context(backend);
    if (!gl) continue;
    for (int msaa : {0, 4}) {
      RenderOptions options = Options("goal,achieved,hud,action,trail", 161, 97);
      options.msaa_samples = msaa;
      options.readback = Readback::kSync;
      RenderOptions async_options = options;
      async_options.readback = Readback::kAsync;
      Renderer sync(*gl, model_.get(), options);
      Renderer async(*gl, model_.get(), async_options);
      EXPECT_FALSE(sync.async_readback());
      ASSERT_TRUE(async.async_readback()) << async.readback_reason();
      EXPECT_EQ(async.pipeline_depth(), kReadbackDepth);
      const size_t bytes = 161 * 97 * 3;
      const int frames = 7;
      std::vector<std::vector<uint8_t>> expected(frames, std::vector<uint8_t>(bytes));
      std::vector<std::vector<uint8_t>> got(frames, std::vector<uint8_t>(bytes, 0x5A));
      std::vector<uint8_t*> order;
      const double x0 =
          data_->qpos[model_->jnt_qposadr[mj_name2id(model_.get(), mjOBJ_JOINT, "robot0:slide0")]];
      for (int k = 0; k < frames; ++k) {
        SetJoint("robot0:slide0", {x0 + 0.05 * k});
        mj_forward(model_.get(), data_.get());
        info_.step = k;
        sync.Render(data_.get(), info_, expected[k].data());
        async.Submit(data_.get(), info_, got[k].data());
        EXPECT_LE(async.pending(), kReadbackDepth);
        while (async.pending() >= async.pipeline_depth()) order.push_back(async.Collect());
      }
      while (uint8_t* done = async.Collect()) order.push_back(done);
      EXPECT_EQ(async.Collect(), nullptr);
      ASSERT_EQ(order.size(), static_cast<size_t>(frames));
      for (int k = 0; k < frames; ++k) {
        EXPECT_EQ(order[k], got[k].data()) << "frames come back in submission order";
        EXPECT_TRUE(got[k] == expected[k]) << backend << " msaa " << msaa << " frame " << k;
      }
      EXPECT_NE(expected[0], expected[frames - 1])
          << "the frames differ: the test can see a mix-up";
      SetJoint("robot0:slide0", {x0});
      mj_forward(model_.get(), data_.get());
    }
  }
}

TEST_P(RendererTest, AutoReadbackIsSyncOnSoftwareRasterizers) {
  auto gl = Context();
  if (!gl) GTEST_SKIP();
  Renderer renderer(*gl, model_.get(), Options("none", 64, 64));
  if (SoftwareRendererName(gl->info().renderer).empty()) {
    EXPECT_TRUE(renderer.async_readback()) << renderer.readback_reason();
  } else {
    EXPECT_FALSE(renderer.async_readback());
    EXPECT_NE(renderer.readback_reason().find("software"), std::string::npos)
        << renderer.readback_reason();
    EXPECT_EQ(renderer.pipeline_depth(), 1);
  }
}

TEST_P(RendererTest, RenderingDoesNotTouchTheSimulation) {
  auto gl = Context();
  if (!gl) GTEST_SKIP();
  const mjModel* m = model_.get();
  const mjData* d = data_.get();
  // a moving state: warmstart and velocities are not zero
  for (int i = 0; i < 5; ++i) mj_step(model_.get(), data_.get());
  auto snapshot = [&] {
    std::vector<double> s;
    auto add = [&](const mjtNum* p, int n) { s.insert(s.end(), p, p + n); };
    add(d->qpos, m->nq);
    add(d->qvel, m->nv);
    add(d->qacc_warmstart, m->nv);
    add(d->xpos, 3 * m->nbody);
    add(d->xquat, 4 * m->nbody);
    add(d->site_xpos, 3 * m->nsite);
    add(d->mocap_pos, 3 * m->nmocap);
    add(d->ctrl, m->nu);
    add(d->subtree_com, 3 * m->nbody);
    add(m->site_pos, 3 * m->nsite);  // Gymnasium moves target0 here; we must not
    s.push_back(d->time);
    return s;
  };
  const std::vector<double> before = snapshot();
  RenderOptions options = Options("goal,achieved,hud,action,trail");
  options.cameras = ParseCameraList("default,track,external_camera_0", model_.get());
  Renderer renderer(*gl, model_.get(), options);
  std::vector<uint8_t> rgb(3 * kSize * kSize * 3), layer;
  renderer.Render(data_.get(), info_, rgb.data());
  renderer.RenderLayer(data_.get(), info_, Layer::kDepth, &layer);
  renderer.RenderLayer(data_.get(), info_, Layer::kSegmentation, &layer);
  EXPECT_EQ(snapshot(), before);
}

TEST_P(RendererTest, DepthIsMillimetresAlongTheViewAxis) {
  auto gl = Context();
  if (!gl) GTEST_SKIP();
  Renderer renderer(*gl, model_.get(), Options("default"));
  std::vector<uint8_t> layer;
  renderer.RenderLayer(data_.get(), info_, Layer::kDepth, &layer);
  ASSERT_EQ(layer.size(), kSize * kSize * 2u);
  std::vector<uint16_t> mm(kSize * kSize);
  std::memcpy(mm.data(), layer.data(), layer.size());

  const FreeCamera cam = DefaultFreeCamera();
  Pixel goal = Project(cam, info_.goal, kSize, kSize, Fovy());
  // the sphere's near surface: its centre's depth less about its radius (0.02 m)
  const double expected = 1000 * ViewDepth(cam, info_.goal) - 20;
  EXPECT_NEAR(mm[goal.row * kSize + goal.col], expected, 8);
  Pixel table = Project(cam, {1.2, 0.6, 0.4}, kSize, kSize, Fovy());
  EXPECT_NEAR(mm[table.row * kSize + table.col], 1000 * ViewDepth(cam, {1.2, 0.6, 0.4}), 15);
  EXPECT_EQ(mm[0], 0) << "the sky has no depth";
}

TEST_P(RendererTest, SegmentationNamesObjects) {
  auto gl = Context();
  if (!gl) GTEST_SKIP();
  Renderer renderer(*gl, model_.get(), Options("default"));
  std::vector<uint8_t> layer;
  renderer.RenderLayer(data_.get(), info_, Layer::kSegmentation, &layer);
  ASSERT_EQ(layer.size(), kSize * kSize * 3u);
  const std::vector<SegmentObject>& legend = renderer.segmentation_legend();
  auto object_at = [&](Pixel p) -> const SegmentObject* {
    const Rgb c = At(layer, kSize, p);
    for (const SegmentObject& o : legend) {
      if (o.color[0] == c.r && o.color[1] == c.g && o.color[2] == c.b) return &o;
    }
    return nullptr;
  };
  const FreeCamera cam = DefaultFreeCamera();
  const SegmentObject* goal = object_at(Project(cam, info_.goal, kSize, kSize, Fovy()));
  ASSERT_NE(goal, nullptr);
  EXPECT_EQ(goal->site, "target0");
  const SegmentObject* table = object_at(Project(cam, {1.2, 0.6, 0.4}, kSize, kSize, Fovy()));
  ASSERT_NE(table, nullptr);
  EXPECT_EQ(table->body, "table0");
  EXPECT_TRUE(table->site.empty());
  EXPECT_FALSE(table->geoms.empty());
  const Rgb sky = At(layer, kSize, Pixel{0, 0});
  EXPECT_EQ(sky.r + sky.g + sky.b, 0) << "the sky is background (black)";
  EXPECT_EQ(object_at(Pixel{0, 0}), nullptr);
  // distinct colours; every pixel is black or one object's colour, and the counts add up
  std::map<std::array<uint8_t, 3>, long> count;
  for (size_t i = 0; i < layer.size(); i += 3) ++count[{layer[i], layer[i + 1], layer[i + 2]}];
  long background = count[{0, 0, 0}];
  EXPECT_GT(background, 0);
  std::set<std::array<uint8_t, 3>> colours;
  for (const SegmentObject& o : legend) {
    EXPECT_TRUE(colours.insert(o.color).second) << "colour shared: " << o.body << " " << o.site;
    EXPECT_EQ(count[o.color], o.pixels) << o.body;
    EXPECT_EQ(o.color, SegmentationColor(o.index));
    background += o.pixels;
  }
  EXPECT_EQ(background, static_cast<long>(kSize) * kSize) << "a pixel of no object's colour";
  // the colours used in this image are clearly apart, pair by pair
  EXPECT_GE(legend.size(), 19u);  // 20 with the mocap crosshair, now left out
  for (size_t i = 0; i < legend.size(); ++i) {
    EXPECT_LT(legend[i].index, kFetchObjects) << legend[i].body;
    for (size_t j = 0; j < i; ++j) {
      EXPECT_GE(Ciede2000(legend[i].color, legend[j].color), kApartInOneImage)
          << legend[i].body << " " << legend[i].site << " and " << legend[j].body << " "
          << legend[j].site;
    }
  }
  // the same object keeps its colour in another view
  RenderOptions other = Options("default");
  other.cameras = ParseCameraList("external_camera_0", model_.get());
  Renderer second(*gl, model_.get(), other);
  std::vector<uint8_t> layer2;
  second.RenderLayer(data_.get(), info_, Layer::kSegmentation, &layer2);
  bool found_table = false;
  for (const SegmentObject& o : second.segmentation_legend()) {
    if (o.body == "table0") {
      EXPECT_EQ(o.color, table->color);
      found_table = true;
    }
  }
  EXPECT_TRUE(found_table);
}

// Pick names the geom or site under a pixel, as the segmentation layer colours it
TEST_P(RendererTest, PickNamesWhatTheSegmentationLayerShows) {
  auto gl = Context();
  if (!gl) GTEST_SKIP();
  Renderer renderer(*gl, model_.get(), Options("default"));
  std::vector<uint8_t> layer;
  renderer.RenderLayer(data_.get(), info_, Layer::kSegmentation, &layer);
  const FreeCamera cam = DefaultFreeCamera();
  const Pixel goal = Project(cam, info_.goal, kSize, kSize, Fovy());
  const Pixel table = Project(cam, {1.2, 0.6, 0.4}, kSize, kSize, Fovy());
  const std::optional<PickedObject> at_goal = renderer.Pick(data_.get(), info_, goal.col, goal.row);
  ASSERT_TRUE(at_goal);
  EXPECT_EQ(at_goal->site, "target0");
  EXPECT_TRUE(at_goal->geom.empty());
  const std::optional<PickedObject> at_table =
      renderer.Pick(data_.get(), info_, table.col, table.row);
  ASSERT_TRUE(at_table);
  EXPECT_EQ(at_table->body, "table0");
  EXPECT_FALSE(at_table->geom.empty());
  EXPECT_TRUE(at_table->site.empty());
  for (const Pixel p : {goal, table}) {  // the colour it reports is the layer's there
    const Rgb c = At(layer, kSize, p);
    const auto picked = renderer.Pick(data_.get(), info_, p.col, p.row);
    EXPECT_EQ(picked->color[0], c.r);
    EXPECT_EQ(picked->color[1], c.g);
    EXPECT_EQ(picked->color[2], c.b);
  }
  EXPECT_FALSE(renderer.Pick(data_.get(), info_, 0, 0));  // the sky
  EXPECT_FALSE(renderer.Pick(data_.get(), info_, -1, 5));
  EXPECT_FALSE(renderer.Pick(data_.get(), info_, kSize, 5));
}

TEST(SegmentationPalette, FixedDistinctAndNeverBlack) {
  std::set<std::array<uint8_t, 3>> seen;
  for (int i = 0; i < 200; ++i) {
    const auto c = SegmentationColor(i);
    EXPECT_EQ(c, SegmentationColor(i));
    EXPECT_NE(c[0] + c[1] + c[2], 0) << i;
    seen.insert(c);
  }
  EXPECT_EQ(seen.size(), 200u);
}

TEST(SegmentationPalette, ColoursAreClearlyApart) {
  // the metric, on the pair that made the old palette (Kelly's) ambiguous: two oranges
  EXPECT_NEAR(Ciede2000({0xF3, 0x84, 0x00}, {0xF6, 0xA6, 0x00}), 11.8, 0.1);
  EXPECT_NEAR(Ciede2000({0, 0, 0}, {255, 255, 255}), 100.0, 0.01);
  double closest = 1e9, darkest = 1e9;
  for (int i = 0; i < kSegmentationColors; ++i) {
    darkest = std::min(darkest, Ciede2000(SegmentationColor(i), {0, 0, 0}));
    for (int j = 0; j < i; ++j) {
      const double d = Ciede2000(SegmentationColor(i), SegmentationColor(j));
      if (i < kFetchObjects) closest = std::min(closest, d);
      EXPECT_GE(d, kApartAll) << i << " " << j;
    }
  }
  EXPECT_GE(closest, kApartInOneImage);
  EXPECT_GE(darkest, 25.0) << "every colour stands out from the black background";
}

TEST_P(RendererTest, CamerasTileOneFrame) {
  auto gl = Context();
  if (!gl) GTEST_SKIP();
  std::vector<uint8_t> single = RenderWith(*gl, Options("none"));
  RenderOptions options = Options("none");  // --width/--height size each tile
  options.cameras = ParseCameraList("default,default", model_.get());
  Renderer renderer(*gl, model_.get(), options);
  EXPECT_EQ(renderer.width(), 2 * kSize);
  EXPECT_EQ(renderer.height(), kSize);
  ASSERT_EQ(renderer.tiles().size(), 2u);
  EXPECT_EQ(renderer.tiles()[1].left, kSize);
  EXPECT_EQ(renderer.tiles()[1].width, kSize);
  std::vector<uint8_t> pair(2 * kSize * kSize * 3);
  renderer.Render(data_.get(), info_, pair.data());
  Dump(options, pair);
  std::vector<uint8_t> left(kSize * kSize * 3), right(kSize * kSize * 3);
  for (int row = 0; row < kSize; ++row) {
    std::memcpy(&left[row * kSize * 3], &pair[row * 2 * kSize * 3], kSize * 3);
    std::memcpy(&right[row * kSize * 3], &pair[(row * 2 + 1) * kSize * 3], kSize * 3);
  }
  EXPECT_LT(MeanAbsDiff(left, single), 1.0);
  EXPECT_LT(MeanAbsDiff(right, single), 1.0);

  // named and tracking cameras see something else than the default view
  for (const char* spec : {"external_camera_0", "track"}) {
    RenderOptions other = Options("none");
    other.cameras = ParseCameraList(spec, model_.get());
    EXPECT_GT(Compare(single, RenderWith(*gl, other), kSize).fraction, 0.2) << spec;
  }
}

TEST_P(RendererTest, TiledCamerasGetFullSizeTilesEachLabelled) {
  auto gl = Context();
  if (!gl) GTEST_SKIP();
  constexpr int kTileW = 240, kTileH = 200;
  RenderOptions plain = Options("none", kTileW, kTileH);
  plain.cameras = ParseCameraList("default,track,external_camera_0", model_.get());
  const FrameDims dims = FrameSize(plain);
  EXPECT_EQ(dims.width, 3 * kTileW);
  EXPECT_EQ(dims.height, kTileH);
  Renderer renderer(*gl, model_.get(), plain);
  EXPECT_EQ(renderer.width(), 3 * kTileW);
  ASSERT_EQ(renderer.tiles().size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(renderer.tiles()[i].left, i * kTileW);
    EXPECT_EQ(renderer.tiles()[i].width, kTileW);
    EXPECT_EQ(renderer.tiles()[i].height, kTileH);
  }
  const std::vector<uint8_t> none = RenderWith(*gl, plain);
  RenderOptions labelled = plain;
  labelled.overlays = ParseOverlays("labels");
  const std::vector<uint8_t> with_labels = RenderWith(*gl, labelled);
  // each tile has its label: a small change near the top centre of every tile, nothing else
  for (int tile = 0; tile < 3; ++tile) {
    std::vector<uint8_t> a, b;
    for (int row = 0; row < kTileH; ++row) {
      const size_t at = (static_cast<size_t>(row) * dims.width + tile * kTileW) * 3;
      a.insert(a.end(), none.begin() + at, none.begin() + at + kTileW * 3);
      b.insert(b.end(), with_labels.begin() + at, with_labels.begin() + at + kTileW * 3);
    }
    const Difference d = Compare(a, b, kTileW);
    EXPECT_GT(d.fraction, 0.003) << "tile " << tile;
    EXPECT_LT(d.fraction, 0.08) << "tile " << tile;
    EXPECT_LT(d.max_row, kTileH / 4) << "tile " << tile;
    EXPECT_LT(std::abs((d.min_col + d.max_col) / 2 - kTileW / 2), 4) << "tile " << tile;
  }
  // a grid from four cameras: 2 x 2 tiles of the size asked
  RenderOptions grid = Options("none", 100, 80);
  grid.cameras = ParseCameraList("default,default,default,default", model_.get());
  EXPECT_EQ(FrameSize(grid).width, 200);
  EXPECT_EQ(FrameSize(grid).height, 160);
}

TEST_P(RendererTest, HudIsDrawnOnceInsideTheTileAtItsCorner) {
  auto gl = Context();
  if (!gl) GTEST_SKIP();
  constexpr int kTile = 320;
  for (const char* corner : {"top-left", "top-right", "bottom-left", "bottom-right"}) {
    RenderOptions plain = Options("none", kTile, kTile);
    plain.cameras = ParseCameraList("default,default", model_.get());
    RenderOptions hud = plain;
    hud.overlays = ParseOverlays("hud");
    hud.hud_position = cli::ParseHudPosition(corner);
    const Difference d = Compare(RenderWith(*gl, plain), RenderWith(*gl, hud), 2 * kTile);
    EXPECT_GT(d.fraction, 0.01) << corner;
    const bool right = std::string(corner).find("right") != std::string::npos;
    const bool bottom = std::string(corner).find("bottom") != std::string::npos;
    // all of it in one tile: the left one, or the right one for the right corners
    EXPECT_GE(d.min_col, right ? kTile : 0) << corner;
    EXPECT_LT(d.max_col, right ? 2 * kTile : kTile) << corner;
    // and in that corner's half of the tile
    if (right) {
      EXPECT_GT(d.min_col, kTile + kTile / 4) << corner;
    } else {
      EXPECT_LT(d.max_col, kTile - kTile / 4) << corner;
    }
    if (bottom) {
      EXPECT_GT(d.min_row, kTile / 2) << corner;
    } else {
      EXPECT_LT(d.max_row, kTile / 2) << corner;
    }
  }
}

TEST_P(RendererTest, HudScalesWithTheFrameAndIsDroppedWhenTooSmall) {
  auto gl = Context();
  if (!gl) GTEST_SKIP();
  auto hud_box = [&](int side) {
    return Compare(RenderWith(*gl, Options("none", side, side)),
                   RenderWith(*gl, Options("hud", side, side)), side);
  };
  const Difference small = hud_box(480), large = hud_box(960);
  const double h_small = small.max_row - small.min_row + 1,
               h_large = large.max_row - large.min_row + 1;
  const double w_small = small.max_col - small.min_col + 1,
               w_large = large.max_col - large.min_col + 1;
  EXPECT_NEAR(h_large / h_small, 2.0, 0.15);
  EXPECT_NEAR(w_large / w_small, 2.0, 0.15);
  // the same share of the frame
  EXPECT_NEAR(small.fraction, large.fraction, 0.25 * small.fraction);
  // too small to read: no HUD at all, the frame is as without it
  for (int side : {64, 120}) {
    EXPECT_EQ(RenderWith(*gl, Options("none", side, side)),
              RenderWith(*gl, Options("hud", side, side)))
        << side;
  }
}

TEST_P(RendererTest, HudOpacitySetsTheBox) {
  auto gl = Context();
  if (!gl) GTEST_SKIP();
  const std::vector<uint8_t> none = RenderWith(*gl, Options("none"));
  RenderOptions opaque = Options("hud"), clear = Options("hud");
  opaque.hud_opacity = 1.0;
  clear.hud_opacity = 0.0;
  const std::vector<uint8_t> a = RenderWith(*gl, opaque), b = RenderWith(*gl, clear);
  const Difference da = Compare(none, a, kSize), db = Compare(none, b, kSize);
  // opaque: the box's corner pixel is black; no box: only the text's pixels change
  const size_t corner = (static_cast<size_t>(da.min_row) * kSize + da.min_col) * 3;
  EXPECT_EQ(a[corner] + a[corner + 1] + a[corner + 2], 0);
  EXPECT_GT(da.fraction, 3 * db.fraction);
  EXPECT_GT(db.fraction, 0.001);
}

INSTANTIATE_TEST_SUITE_P(Models, RendererTest, ::testing::Values("genuine", "bundled"));

// A GL context for the episode tests below, or nullptr where this machine has none.
std::unique_ptr<GlContext> AnyContext() {
  unsetenv("DISPLAY");
  mju_user_error = OnMujocoError;
  try {
    return CreateGlContext("auto");
  } catch (const RunError& e) {
    std::cout << "[  SKIPPED ] no GL: " << e.what() << "\n";
    return nullptr;
  }
}

// Runs episode 0 of `policy` on FetchPush-v4 (bundled) as `record --seed seed` does, calling
// `on_step` after the reset and after every step.
EpisodeRecord RunPush(FetchEnv& env, const std::string& policy, uint64_t seed, int steps,
                      const StepCallback& on_step) {
  PolicyContext context;
  context.seed = seed;
  context.steps_per_episode = steps;
  auto p = MakePolicy(ParsePolicySpec(policy), env.spec(), context);
  return RunEpisode(env, *p, 0, seed, steps, on_step);
}

// Every frame of a short scripted Push episode, at sizes around the HUD's threshold and where
// it used to come and go with the width of the action line (144-160 px): the HUD is on every
// frame or on none, in the same box on every frame, within its share of the frame.
TEST(HudEpisode, OnEveryFrameOrOnNoneInOneBoxWithinItsShare) {
  auto gl = AnyContext();
  if (!gl) GTEST_SKIP();
  FetchEnv env(FindEnvSpec("FetchPush-v4"), ResolveAssets("bundled"));
  struct View {
    int w = 0, h = 0;
    std::unique_ptr<Renderer> plain, hud;
    int frames = 0, with_hud = 0;
    std::optional<Difference> first_box;
  };
  std::vector<View> views;
  for (auto [w, h] : std::vector<std::pair<int, int>>{{144, 144},
                                                      {150, 150},
                                                      {160, 160},
                                                      {219, 219},
                                                      {240, 240},
                                                      {319, 319},
                                                      {320, 239},
                                                      {320, 240},
                                                      {336, 336},
                                                      {480, 270}}) {
    View v;
    v.w = w;
    v.h = h;
    RenderOptions options;
    options.width = w;
    options.height = h;
    options.msaa_samples = 0;
    options.overlays = ParseOverlays("action");
    v.plain = std::make_unique<Renderer>(*gl, env.model(), options);
    options.overlays = ParseOverlays("action,hud");  // the arrow adds a row
    v.hud = std::make_unique<Renderer>(*gl, env.model(), options);
    views.push_back(std::move(v));
  }
  RunPush(env, "scripted", 0, 8, [&](const StepRecord& record, const StepResult*) {
    const FrameInfo info = MakeFrameInfo(env, record);
    for (View& v : views) {
      std::vector<uint8_t> a(static_cast<size_t>(v.w) * v.h * 3), b(a.size());
      v.plain->Render(env.data(), info, a.data());
      v.hud->Render(env.data(), info, b.data());
      const Difference d = Compare(a, b, v.w);
      ++v.frames;
      if (d.fraction == 0) continue;
      ++v.with_hud;
      // the box: darkened, every pixel of it differs
      EXPECT_LE(d.max_col - d.min_col + 1, kHudMaxWidthShare * v.w) << v.w << "x" << v.h;
      EXPECT_LE(d.max_row - d.min_row + 1, kHudMaxHeightShare * v.h) << v.w << "x" << v.h;
      if (!v.first_box) {
        v.first_box = d;
      } else {
        EXPECT_EQ(d.min_col, v.first_box->min_col) << v.w << "x" << v.h << " step " << record.t;
        EXPECT_EQ(d.max_col, v.first_box->max_col) << v.w << "x" << v.h << " step " << record.t;
        EXPECT_EQ(d.min_row, v.first_box->min_row) << v.w << "x" << v.h << " step " << record.t;
        EXPECT_EQ(d.max_row, v.first_box->max_row) << v.w << "x" << v.h << " step " << record.t;
      }
    }
    return true;
  });
  for (const View& v : views) {
    ASSERT_EQ(v.frames, 9);
    const bool expected = v.w >= kHudMinTileWidth && v.h >= kHudMinTileHeight;
    EXPECT_EQ(v.with_hud, expected ? v.frames : 0) << v.w << "x" << v.h;
  }
}

bool IsBeadGreen(Rgb c) { return c.g > 120 && c.r < 80 && c.g > c.b + 60; }
bool IsBeadRed(Rgb c) { return c.r > 120 && c.g < 80 && c.b < 80; }

// A failed random Push episode with the hindsight overlay: every relabelled goal's bead shows
// in its reward colour where it projects (unless the robot or the table hides it), and is not
// there without the overlay. Before the pins, the markers sat inside the block and none showed.
TEST(HindsightOverlay, PinsShowInTheRewardColoursWhereTheyProject) {
  auto gl = AnyContext();
  if (!gl) GTEST_SKIP();
  FetchEnv env(FindEnvSpec("FetchPush-v4"), ResolveAssets("bundled"));
  constexpr int kSteps = 20, kSize = 320;
  constexpr uint64_t kSeed = 1;
  const EpisodeRecord episode = RunPush(env, "random", kSeed, kSteps, nullptr);
  std::vector<std::array<double, 3>> achieved;
  for (const StepRecord& r : episode.steps) {
    ASSERT_FALSE(r.is_success) << "step " << r.t << ": the episode must fail";
    achieved.push_back(r.obs.achieved_goal);
  }
  const HindsightEpisode her = SampleHindsight(
      achieved, episode.steps[0].obs.desired_goal, HindsightSeed(kSeed, 0), kHindsightK,
      [&](const auto& a, const auto& g) { return env.ComputeReward(a, g); },
      [&](const auto& a, const auto& g) { return env.IsSuccess(a, g); });
  ASSERT_GT(her.relabelled_successes, 0);

  RenderOptions options;
  options.width = options.height = kSize;
  options.msaa_samples = 0;
  options.overlays = ParseOverlays("goal,achieved,hindsight");
  Renderer pins(*gl, env.model(), options);
  options.overlays = ParseOverlays("goal,achieved");
  Renderer plain(*gl, env.model(), options);
  const FreeCamera cam = DefaultFreeCamera();
  const double fovy = env.model()->vis.global.fovy;
  const double bead_px = kHindsightBeadRadius * kSize / (2 * 2.5 * std::tan(fovy * M_PI / 360));
  int green = 0, red = 0, hidden = 0;
  RunPush(env, "random", kSeed, kSteps, [&](const StepRecord& record, const StepResult*) {
    if (record.t == 0) return true;
    FrameInfo info = MakeFrameInfo(env, record);
    for (const HindsightGoal& g : her.transitions[record.t - 1])
      info.relabelled.push_back({g.goal, g.success});
    std::vector<uint8_t> a(kSize * kSize * 3), b(a.size()), depth;
    pins.Render(env.data(), info, a.data());
    plain.Render(env.data(), info, b.data());
    plain.RenderLayer(env.data(), info, Layer::kDepth, &depth);  // the scene without overlays
    const auto* mm = reinterpret_cast<const uint16_t*>(depth.data());
    const std::vector<HindsightPin> all = HindsightPins(info);
    for (const HindsightPin& pin : all) {
      const Pixel p = Project(cam, pin.head, kSize, kSize, fovy);
      if (p.col < 1 || p.col >= kSize - 1 || p.row < 1 || p.row >= kSize - 1) {
        ADD_FAILURE() << "step " << record.t << ": a bead out of the frame";
        continue;
      }
      // hidden by the robot or the table (nearer than the bead's front)?
      const double bead_mm = 1000 * (ViewDepth(cam, pin.head) - kHindsightBeadRadius);
      const uint16_t scene_mm = mm[p.row * kSize + p.col];
      bool covered = scene_mm != 0 && scene_mm < bead_mm;
      // or by a bead of the other colour in front of it
      for (const HindsightPin& other : all) {
        const Pixel q = Project(cam, other.head, kSize, kSize, fovy);
        if (other.success != pin.success &&
            std::hypot(q.col - p.col, q.row - p.row) < 2 * bead_px &&
            ViewDepth(cam, other.head) < ViewDepth(cam, pin.head)) {
          covered = true;
        }
      }
      if (covered) {
        ++hidden;
        continue;
      }
      const auto is_bead = pin.success ? IsBeadGreen : IsBeadRed;
      bool found = false;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const Pixel q{p.col + dx, p.row + dy};
          if (is_bead(At(a, kSize, q)) && !is_bead(At(b, kSize, q))) found = true;
        }
      }
      EXPECT_TRUE(found) << "step " << record.t << ": no " << (pin.success ? "green" : "red")
                         << " bead at column " << p.col << ", row " << p.row;
      ++(pin.success ? green : red);
    }
    return true;
  });
  std::cout << green << " green and " << red << " red beads seen, " << hidden << " hidden\n";
  EXPECT_GE(green, 20);
  EXPECT_GE(red, 3);
  EXPECT_LE(hidden, (green + red) / 4);
}

TEST(HindsightOverlay, IdenticalGoalsStringTheirBeadsOnOneStem) {
  FrameInfo info;
  const std::array<double, 3> block = {1.3, 0.75, 0.425};
  info.relabelled = {{block, true}, {block, true}, {{1.5, 0.75, 0.425}, false}, {block, true}};
  const std::vector<HindsightPin> pins = HindsightPins(info);
  ASSERT_EQ(pins.size(), 4u);
  auto length = [&](const HindsightPin& pin) {
    double along = 0, off = 0;
    for (int k = 0; k < 3; ++k) along += (pin.head[k] - pin.base[k]) * kHindsightPinDirection[k];
    for (int k = 0; k < 3; ++k) {
      off += std::pow(pin.head[k] - pin.base[k] - along * kHindsightPinDirection[k], 2);
    }
    EXPECT_LT(off, 1e-20) << "the bead is on the stem's line";
    return along;
  };
  std::set<double> lengths;
  for (int i : {0, 1, 3}) {
    EXPECT_EQ(pins[i].base, block);
    EXPECT_TRUE(pins[i].success);
    lengths.insert(length(pins[i]));
  }
  // three beads on one stem, apart, the nearest clear of the 5 cm block (corners 4.4 cm out)
  ASSERT_EQ(lengths.size(), 3u);
  EXPECT_NEAR(*lengths.begin(), kHindsightPinLength, 1e-12);
  EXPECT_GT(*lengths.begin() - kHindsightBeadRadius, 0.044);
  EXPECT_NEAR(*lengths.rbegin() - *lengths.begin(), 2 * kHindsightBeadSpacing, 1e-12);
  EXPECT_GT(kHindsightBeadSpacing, 2 * kHindsightBeadRadius);
  // leaning up: the bead is above g'
  EXPECT_GT(pins[0].head[2], block[2] + 0.05);
  // a goal elsewhere gets its own pin at the first length
  EXPECT_NEAR(length(pins[2]), kHindsightPinLength, 1e-12);
  EXPECT_FALSE(pins[2].success);
  // sixteen identical goals: sixteen beads, the loop ends
  info.relabelled.assign(16, {block, false});
  EXPECT_EQ(HindsightPins(info).size(), 16u);
}

// render's segmentation legend is named as its --help says: NAME_segmentation_legend.json for
// -o NAME.png, whether the segmentation layer goes to NAME_segmentation.png or to NAME.png.
TEST(RenderCommand, WritesTheLegendWhereTheHelpSays) {
  const auto help = testing::RunFetchscope("render --help");
  ASSERT_EQ(help.exit_code, 0);
  std::string flat;  // the help wraps lines
  for (char c : help.output) {
    if (c == '\n') c = ' ';
    if (c != ' ' || flat.empty() || flat.back() != ' ') flat += c;
  }
  EXPECT_NE(flat.find("NAME_segmentation_legend.json"), std::string::npos) << help.output;
  EXPECT_EQ(flat.find("NAME_legend.json"), std::string::npos);
  testing::TempDir tmp;
  const std::string common = "render --env-id FetchPush-v4 --width 96 --height 96 ";
  auto r = testing::RunFetchscope(common + "--layers rgb,segmentation -o " +
                                  (tmp.path() / "both.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = testing::RunFetchscope(common + "--layers segmentation -o " +
                             (tmp.path() / "alone.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::set<std::string> files;
  for (const auto& entry : fs::directory_iterator(tmp.path()))
    files.insert(entry.path().filename());
  EXPECT_EQ(files, (std::set<std::string>{"both.png", "both_segmentation.png",
                                          "both_segmentation_legend.json", "alone.png",
                                          "alone_segmentation_legend.json"}));
}

// Overlay helpers that need no GL.
TEST(Trail, KeepsOnePointPerStepAndRestartsAtZero) {
  Trail trail;
  trail.Add(0, {0, 0, 0});
  trail.Add(1, {1, 0, 0});
  trail.Add(1, {2, 0, 0});  // the same step rendered again replaces its point
  trail.Add(2, {3, 0, 0});
  ASSERT_EQ(trail.points().size(), 3u);
  EXPECT_EQ(trail.points()[1][0], 2);
  trail.Add(0, {9, 9, 9});  // a new episode
  ASSERT_EQ(trail.points().size(), 1u);
  for (int step = 1; step < 1000; ++step) trail.Add(step, {0, 0, 0});
  EXPECT_EQ(trail.points().size(), Trail::kMaxPoints);
  trail.Clear();
  EXPECT_TRUE(trail.points().empty());
}

TEST(Hud, ShowsTheFrameInfo) {
  FrameInfo info;
  info.title = "FetchReach-v4";
  HudText reset = FormatHud(info, OverlaySet{});
  EXPECT_NE(reset.labels.find("reward"), std::string::npos);
  EXPECT_EQ(reset.title, "FetchReach-v4");
  EXPECT_NE(reset.values.find("\n-\n"), std::string::npos) << "no reward at reset";
  info.step = 12;
  info.reward = -1;
  info.success = true;
  info.distance = 0.0123;
  info.has_action = true;
  info.action = {1, -0.5, 0, 0.25};
  OverlaySet with_arrow;
  with_arrow.action = true;
  HudText step = FormatHud(info, with_arrow);
  EXPECT_NE(step.values.find("12"), std::string::npos);
  EXPECT_NE(step.values.find("-1.0000"), std::string::npos);
  EXPECT_NE(step.values.find("0.0123 m"), std::string::npos);
  EXPECT_NE(step.values.find("yes"), std::string::npos);
  EXPECT_NE(step.values.find("+1.00 -0.50 +0.00 +0.25"), std::string::npos);
  EXPECT_NE(step.labels.find("arrow"), std::string::npos);
  // one value per label
  EXPECT_EQ(std::count(step.labels.begin(), step.labels.end(), '\n'),
            std::count(step.values.begin(), step.values.end(), '\n'));
  // the hindsight row is on every frame, the reset's included, so the box keeps its height
  OverlaySet her;
  her.hindsight = true;
  EXPECT_EQ(FormatHud(FrameInfo{}, her).labels, FormatHud(info, her).labels);
  info.relabelled = {{{0, 0, 0}, true}, {{0, 0, 0}, true}, {{1, 0, 0}, false}, {{0, 0, 0}, true}};
  info.relabelled_successes = 3;
  EXPECT_NE(FormatHud(info, her).values.find("3/4"), std::string::npos);
}

// The largest HUD there is: every row, the longest env id, the widest values.
FrameInfo LargestHudFrame() {
  FrameInfo info;
  for (const EnvSpec& spec : AllEnvSpecs()) {
    if (spec.id.size() > info.title.size()) info.title = spec.id;
  }
  info.step = 1000;
  info.reward = -1;
  info.distance = 1.2345;
  info.has_action = true;
  info.action = {1, 1, 1, 1};
  info.relabelled = {{{0, 0, 0}, true}, {{0, 0, 0}, true}, {{0, 0, 0}, true}, {{0, 0, 0}, true}};
  info.relabelled_successes = 4;
  return info;
}

TEST(HudPlacement, TheTileAloneDecidesAndTheBoxKeepsItsShareOnEveryFrame) {
  const OverlaySet all = ParseOverlays("all");
  const HudText largest = FormatHud(LargestHudFrame(), all);
  FrameInfo reset;  // the same run's reset frame: narrow values, no action, no transition
  reset.title = LargestHudFrame().title;
  const HudText first = FormatHud(reset, all);
  const std::vector<int> sides = {1,   64,  120, 150, 160, 200, 219, 220, 239, 240,  241,  300, 319,
                                  320, 321, 360, 400, 480, 512, 640, 720, 960, 1080, 1920, 4096};
  int drawn = 0;
  for (int w : sides) {
    for (int h : sides) {
      const PixelRect tile{7, 3, w, h};
      const bool big_enough = w >= kHudMinTileWidth && h >= kHudMinTileHeight;
      EXPECT_EQ(HudTextPixels(w, h) > 0, big_enough) << w << "x" << h;
      const auto box = PlaceHud(largest, tile, HudPosition::kBottomRight);
      ASSERT_EQ(box.has_value(), big_enough) << w << "x" << h;
      // the frame's values never change the box: the same on the reset frame
      const auto box0 = PlaceHud(first, tile, HudPosition::kBottomRight);
      ASSERT_EQ(box0.has_value(), big_enough) << w << "x" << h;
      if (!box) continue;
      ++drawn;
      EXPECT_EQ(box->width, box0->width) << w << "x" << h;
      EXPECT_EQ(box->height, box0->height) << w << "x" << h;
      EXPECT_LE(box->width, kHudMaxWidthShare * w) << w << "x" << h;
      EXPECT_LE(box->height, kHudMaxHeightShare * h) << w << "x" << h;
      EXPECT_GE(box->x, tile.x);
      EXPECT_GE(box->y, tile.y);
    }
  }
  EXPECT_GT(drawn, 100);
  EXPECT_EQ(kHudMinTileWidth, 320);  // docs/guide/recording.md: "views at least 320 x 240 pixels"
  EXPECT_EQ(kHudMinTileHeight, 240);
}

TEST(HudPlacement, TextNeverLeavesTheBox) {
  // values far wider than any real one are cut to the box, not drawn past it
  FrameInfo info = LargestHudFrame();
  info.title = "FetchPickAndPlaceDense-v4 with a title far too long for the box";
  info.step = 123456789;
  info.distance = 123456.789;
  const HudText hud = FormatHud(info, ParseOverlays("all"));
  constexpr int kW = 400, kH = 300;
  std::vector<uint8_t> image(kW * kH * 3, 128);
  const PixelRect tile{0, 0, kW, kH};
  const auto box = PlaceHud(hud, tile, HudPosition::kTopLeft);
  ASSERT_TRUE(box.has_value());
  ASSERT_TRUE(DrawHud(image.data(), kW, kH, tile, hud, HudPosition::kTopLeft, 0.0));
  int changed = 0;
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      if (image[(y * kW + x) * 3] == 128) continue;
      ++changed;
      EXPECT_TRUE(x >= box->x && x < box->x + box->width && y >= box->y && y < box->y + box->height)
          << "text at " << x << "," << y;
    }
  }
  EXPECT_GT(changed, 500);
}

// The colour the segmentation layer gives robot0:mocap (its body id's palette entry).
std::array<uint8_t, 3> MocapColour() {
  char error[1000] = "";
  mjModel* m = mj_loadXML((testing::SourceDir() / "models" / "reach.xml").c_str(), nullptr, error,
                          sizeof(error));
  EXPECT_NE(m, nullptr) << error;
  if (!m) return {};
  const int body = mj_name2id(m, mjOBJ_BODY, "robot0:mocap");
  EXPECT_GE(body, 0);
  EXPECT_GE(m->body_mocapid[body], 0);
  mj_deleteModel(m);
  return SegmentationColor(body);
}

TEST(RoughEdges, SegmentationLeavesOutTheMocapCrosshair) {
  TempDir tmp;
  const std::array<uint8_t, 3> mocap = MocapColour();
  for (int steps : {0, 3}) {  // at reset the cross sits at the world origin, then on the gripper
    SCOPED_TRACE(steps);
    const fs::path png = tmp.path() / ("s" + std::to_string(steps) + ".png");
    const CommandResult r =
        RunFetchscope("render --layers segmentation --width 240 --height 240 --steps " +
                      std::to_string(steps) + " -o " + png.string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json legend = nlohmann::json::parse(
        ReadFile(tmp.path() / ("s" + std::to_string(steps) + "_segmentation_legend.json")));
    bool gripper = false;
    for (const auto& o : legend["objects"]) {
      EXPECT_EQ(o["body"].get<std::string>().find("mocap"), std::string::npos) << o.dump();
      gripper |= o["body"] == "robot0:r_gripper_finger_link";
    }
    EXPECT_TRUE(gripper) << legend.dump();
    const Image image = ReadPng(png.string());
    long mocap_pixels = 0;
    for (size_t i = 0; i + 2 < image.pixels.size(); i += 3) {
      mocap_pixels += image.pixels[i] == mocap[0] && image.pixels[i + 1] == mocap[1] &&
                      image.pixels[i + 2] == mocap[2];
    }
    EXPECT_EQ(mocap_pixels, 0);
  }
}

// Through the renderer: with the crosshair asked for (RenderOptions::segment_mocap) and
// without (the default). Without it, every pixel that was not the crosshair keeps its colour,
// no object loses a pixel, and the crosshair's pixels go to what lies behind it.
TEST(RoughEdges, SegmentationWithoutTheMocapKeepsEveryOtherPixel) {
  std::unique_ptr<GlContext> gl;
  try {
    gl = CreateGlContext("auto");
  } catch (const std::exception& e) {
    GTEST_SKIP() << e.what();
  }
  FetchEnv env(FindEnvSpec("FetchReachDense-v4"), ResolveAssets("bundled"));
  env.Reset(0);
  for (int k = 0; k < 3; ++k) env.Step(Action{});
  FrameInfo info;
  info.goal = env.goal();
  const std::array<uint8_t, 3> mocap = MocapColour();
  RenderOptions options;
  options.width = options.height = 240;
  auto segment = [&](bool with_mocap, std::map<std::array<uint8_t, 3>, long>* counts) {
    RenderOptions o = options;
    o.segment_mocap = with_mocap;
    Renderer renderer(*gl, env.model(), o);
    std::vector<uint8_t> layer;
    renderer.RenderLayer(env.data(), info, Layer::kSegmentation, &layer);
    for (const SegmentObject& object : renderer.segmentation_legend()) {
      (*counts)[object.color] = object.pixels;
    }
    return layer;
  };
  std::map<std::array<uint8_t, 3>, long> with_counts, without_counts;
  const std::vector<uint8_t> with = segment(true, &with_counts);
  const std::vector<uint8_t> without = segment(false, &without_counts);
  ASSERT_GT(with_counts[mocap], 100) << "the crosshair, when asked for";
  EXPECT_EQ(without_counts.count(mocap), 0u) << "the legend lists no mocap";
  ASSERT_EQ(with.size(), without.size());
  long kept = 0, moved = 0;
  for (size_t i = 0; i < with.size(); i += 3) {
    const std::array<uint8_t, 3> a{with[i], with[i + 1], with[i + 2]};
    const std::array<uint8_t, 3> b{without[i], without[i + 1], without[i + 2]};
    EXPECT_NE(b, mocap);
    if (a == mocap) {
      ++moved;
    } else {
      kept += a == b;
      EXPECT_EQ(a, b) << "pixel " << i / 3;
    }
  }
  EXPECT_EQ(moved, with_counts[mocap]);
  EXPECT_EQ(kept + moved, static_cast<long>(with.size() / 3));
  for (const auto& [colour, pixels] : with_counts) {
    if (colour != mocap) {
      EXPECT_GE(without_counts[colour], pixels);
    }
  }
}

}  // namespace
}  // namespace fetchscope
