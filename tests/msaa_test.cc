// --msaa auto|0|1|2|4|8|16: the software-renderer rule, explicit counts honoured, the old
// default unchanged, bad values refused; on a real GL context and the bundled PickAndPlace.
#include <gtest/gtest.h>

#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "base/errors.h"
#include "encode/png_io.h"
#include "render/gl_context.h"
#include "render/renderer.h"
#include "render/view.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/fetch_env.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 160, kHeight = 120;

struct NameCase {
  const char* gl_renderer;
  const char* software;  // "" = hardware
};

class SoftwareRendererNameTest : public ::testing::TestWithParam<NameCase> {};

TEST_P(SoftwareRendererNameTest, NamesTheCpuRasterizer) {
  EXPECT_EQ(SoftwareRendererName(GetParam().gl_renderer), GetParam().software);
}

INSTANTIATE_TEST_SUITE_P(
    Renderers, SoftwareRendererNameTest,
    ::testing::Values(NameCase{"llvmpipe (LLVM 15.0.6, 256 bits)", "llvmpipe"},
                      NameCase{"softpipe", "softpipe"},
                      NameCase{"Gallium 0.4 on llvmpipe (LLVM 3.4, 128 bits)", "llvmpipe"},
                      NameCase{"Software Rasterizer", "swrast"},
                      NameCase{"Mesa OffScreen", "swrast"},
                      NameCase{"SWR (LLVM 11.0.1, 256 bits)", "SWR"},
                      NameCase{"NVIDIA GeForce RTX 3090/PCIe/SSE2", ""},
                      NameCase{"NVIDIA H100 80GB HBM3/PCIe/SSE2", ""},
                      NameCase{"AMD Radeon RX 6800 (navi21, LLVM 15.0.6, DRM 3.49, 6.1.0)", ""},
                      NameCase{"Mesa Intel(R) UHD Graphics 620 (KBL GT2)", ""}));

class MsaaTest : public ::testing::Test {
 protected:
  void SetUp() override {
    try {
      gl_ = CreateGlContext("auto");
    } catch (const RunError& e) {
      GTEST_SKIP() << "no GL context: " << e.what();
    }
    env_.emplace(FindEnvSpec("FetchPickAndPlace-v4"), ResolveAssets("bundled"));
    const Observation obs = env_->Reset(7);
    info_.goal = obs.desired_goal;
    info_.achieved = obs.achieved_goal;
    info_.title = "FetchPickAndPlace-v4";
  }

  // Renders the reset state with `msaa_samples` (no HUD: text is not anti-aliased anyway).
  std::vector<uint8_t> RenderWith(int msaa_samples, int* used = nullptr,
                                  std::string* reason = nullptr) {
    RenderOptions options;
    options.width = kWidth;
    options.height = kHeight;
    options.overlays = ParseOverlays("goal,achieved");
    options.msaa_samples = msaa_samples;
    Renderer renderer(*gl_, env_->model(), options);
    if (used) *used = renderer.msaa_samples();
    if (reason) *reason = renderer.msaa_reason();
    std::vector<uint8_t> rgb(static_cast<size_t>(kWidth) * kHeight * 3);
    renderer.Render(env_->data(), info_, rgb.data());
    return rgb;
  }

  std::unique_ptr<GlContext> gl_;
  std::optional<FetchEnv> env_;
  FrameInfo info_;
};

TEST_F(MsaaTest, AutoIsZeroOnSoftwareAndTheModelsOnHardware) {
  const std::string software = SoftwareRendererName(gl_->info().renderer);
  std::cout << "GL_RENDERER: " << gl_->info().renderer << "\n";
  int used = -5;
  std::string reason;
  RenderWith(kMsaaAuto, &used, &reason);
  if (software.empty()) {
    EXPECT_EQ(used, 4);  // the model's offsamples, as Gymnasium renders
    EXPECT_EQ(reason.rfind("auto: hardware renderer", 0), 0u) << reason;
  } else {
    EXPECT_EQ(used, 0);
    EXPECT_EQ(reason, "auto: software renderer " + software);
  }
}

TEST_F(MsaaTest, ExplicitCountsAreHonoured) {
  for (int n : {0, 4}) {
    int used = -5;
    std::string reason;
    RenderWith(n, &used, &reason);
    EXPECT_EQ(used, n);
    EXPECT_EQ(reason, "requested");
  }
  // a driver may round a count up (llvmpipe makes 4 for 2); the reason then says so
  int used = -5;
  std::string reason;
  RenderWith(2, &used, &reason);
  EXPECT_GE(used, 2);
  if (used != 2) {
    EXPECT_EQ(reason, "requested; 2 asked, the driver gave " + std::to_string(used));
  }
}

TEST_F(MsaaTest, FourEqualsTheOldDefaultAndLeavesTheModelAlone) {
  const int model_samples = env_->model()->vis.quality.offsamples;
  RenderWith(0);  // a renderer with another count must not change what the model says
  EXPECT_EQ(env_->model()->vis.quality.offsamples, model_samples);
  int used = -5;
  std::string reason;
  const std::vector<uint8_t> old_default = RenderWith(kMsaaModel, &used, &reason);
  EXPECT_EQ(used, 4);
  EXPECT_EQ(reason, "the model's offsamples");
  EXPECT_EQ(RenderWith(4), old_default);
}

// Multisampling changes edge pixels only: where MSAA 0 and 4 differ, the MSAA 0 frame has a
// neighbour of another colour (a geometry edge); flat interiors are identical.
TEST_F(MsaaTest, ZeroAndFourDifferAlongEdgesOnly) {
  const std::vector<uint8_t> aliased = RenderWith(0);
  const std::vector<uint8_t> smooth = RenderWith(4);
  auto at = [&](const std::vector<uint8_t>& img, int x, int y, int c) {
    return static_cast<int>(img[(static_cast<size_t>(y) * kWidth + x) * 3 + c]);
  };
  long differing = 0, at_edges = 0;
  for (int y = 1; y < kHeight - 1; ++y) {
    for (int x = 1; x < kWidth - 1; ++x) {
      bool differs = false;
      for (int c = 0; c < 3; ++c)
        differs |= std::abs(at(aliased, x, y, c) - at(smooth, x, y, c)) > 2;
      if (!differs) continue;
      ++differing;
      int contrast = 0;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          for (int c = 0; c < 3; ++c) {
            contrast =
                std::max(contrast, std::abs(at(aliased, x + dx, y + dy, c) - at(aliased, x, y, c)));
          }
        }
      }
      if (contrast > 8) ++at_edges;
    }
  }
  const long pixels = static_cast<long>(kWidth) * kHeight;
  std::cout << differing << " of " << pixels << " pixels differ, " << at_edges
            << " of them at edges\n";
  EXPECT_GT(differing, pixels / 200);  // the robot, table and object outlines
  EXPECT_LT(differing, pixels / 4);    // but not the flat areas
  EXPECT_GE(at_edges, differing * 9 / 10);
}

TEST_F(MsaaTest, RendererRefusesOtherCounts) {
  for (int bad : {3, 32, -3}) {
    try {
      RenderWith(bad);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const UsageError& e) {
      EXPECT_NE(std::string(e.what()).find("msaa " + std::to_string(bad)), std::string::npos)
          << e.what();
    }
  }
}

// The profile (FETCHSCOPE_PROFILE) finishes GL between phases; the pixels must not change.
TEST_F(MsaaTest, ProfilingKeepsPixelsAndPrintsPhases) {
  const std::vector<uint8_t> plain = RenderWith(4);
  setenv("FETCHSCOPE_PROFILE", "1", 1);
  ::testing::internal::CaptureStderr();
  const std::vector<uint8_t> profiled = RenderWith(4);
  const std::string printed = ::testing::internal::GetCapturedStderr();
  unsetenv("FETCHSCOPE_PROFILE");
  EXPECT_EQ(profiled, plain);
  EXPECT_NE(printed.find("fetchscope profile: 1 frames 160x120 msaa 4"), std::string::npos)
      << printed;
  EXPECT_NE(printed.find("raster"), std::string::npos) << printed;
}

TEST(MsaaCliTest, BadValueExitsTwoNamingItAndTheAccepted) {
  testing::TempDir dir;
  const auto r = testing::RunFetchscope("render --msaa 3 -o " + (dir.path() / "f.png").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--msaa: 3 not in {auto,0,1,2,4,8,16}"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir.path() / "f.png"));
}

TEST(MsaaCliTest, VerboseSaysTheSamplesAndWhy) {
  testing::TempDir dir;
  const std::string out = (dir.path() / "f.png").string();
  auto r = testing::RunFetchscope("render -v --width 64 --height 48 -o " + out);
  if (r.exit_code == 1 && r.output.find("GL") != std::string::npos && !fs::exists(out)) {
    GTEST_SKIP() << "no GL: " << r.output;
  }
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("MSAA: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("samples (auto: "), std::string::npos) << r.output;
  r = testing::RunFetchscope("render -v --msaa 0 --width 64 --height 48 -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("MSAA: 0 samples (requested)"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace fetchscope
