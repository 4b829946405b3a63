// GL context backends: real EGL and OSMesa contexts, no display server; a windowed MUJOCO_GL
// (one warning, then auto) and a mistyped one (an error with a suggestion).
#include "render/gl_context.h"

#include <GL/gl.h>
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <time.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "base/errors.h"
#include "encode/png_io.h"
#include "encode/video_options.h"
#include "encode/video_writer.h"
#include "render/renderer.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/fetch_env.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using testing::CommandResult;
using testing::Count;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::TempDir;
namespace fs = std::filesystem;

constexpr unsigned kGlMaxRenderbufferSize = 0x84E8;

class GlContextTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // Headless is the point: nothing may need an X server.
    unsetenv("DISPLAY");
    unsetenv("WAYLAND_DISPLAY");
    unsetenv("MUJOCO_GL");
    unsetenv("MUJOCO_EGL_DEVICE_ID");
  }
};

// Creates `backend` or skips the test with the reason when this machine lacks it.
#define CREATE_OR_SKIP(var, backend)                                   \
  std::unique_ptr<GlContext> var;                                      \
  try {                                                                \
    var = CreateGlContext(backend);                                    \
  } catch (const RunError& e) {                                        \
    GTEST_SKIP() << backend << " is not available here: " << e.what(); \
  }

std::string RendererString(const GlContext& gl) {
  using GetStringFn = const GLubyte* (*)(GLenum);
  auto get_string = reinterpret_cast<GetStringFn>(gl.GetProcAddress("glGetString"));
  if (!get_string) return "";
  const GLubyte* s = get_string(GL_RENDERER);
  return s ? reinterpret_cast<const char*>(s) : "";
}

class BackendTest : public GlContextTest, public ::testing::WithParamInterface<const char*> {};

TEST_P(BackendTest, CreatesAndReportsStrings) {
  CREATE_OR_SKIP(gl, GetParam());
  const GlInfo& info = gl->info();
  EXPECT_EQ(info.backend, GetParam());
  EXPECT_FALSE(info.vendor.empty());
  EXPECT_FALSE(info.renderer.empty());
  EXPECT_FALSE(info.device.empty());
  // MuJoCo 2.2 needs framebuffer objects: GL 3.0 or newer in practice.
  ASSERT_FALSE(info.version.empty());
  EXPECT_GE(std::atoi(info.version.c_str()), 3) << info.version;
  std::cout << GetParam() << ": " << info.vendor << " | " << info.renderer << " | " << info.version
            << " | " << info.device << "\n";

  // The context is current after creation and answers GL calls.
  EXPECT_EQ(RendererString(*gl), info.renderer);
  using GetIntegervFn = void (*)(GLenum, GLint*);
  auto get_integer = reinterpret_cast<GetIntegervFn>(gl->GetProcAddress("glGetIntegerv"));
  ASSERT_NE(get_integer, nullptr);
  GLint max_renderbuffer = 0;
  get_integer(kGlMaxRenderbufferSize, &max_renderbuffer);
  EXPECT_GE(max_renderbuffer, 1920);
}

TEST_P(BackendTest, ContextsOnSeparateThreads) {
  CREATE_OR_SKIP(probe, GetParam());
  probe.reset();
  // --jobs N gives each worker thread its own context.
  std::string renderers[2];
  std::string errors[2];
  auto work = [&](int i) {
    try {
      auto gl = CreateGlContext(GetParam());
      renderers[i] = RendererString(*gl);
    } catch (const std::exception& e) {
      errors[i] = e.what();
    }
  };
  std::thread a(work, 0), b(work, 1);
  a.join();
  b.join();
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(errors[i], "");
    EXPECT_FALSE(renderers[i].empty());
  }
}

TEST_P(BackendTest, TwoContextsOnOneThreadSwitch) {
  CREATE_OR_SKIP(first, GetParam());
  auto second = CreateGlContext(GetParam());
  first->MakeCurrent();
  EXPECT_EQ(RendererString(*first), first->info().renderer);
  second->MakeCurrent();
  EXPECT_EQ(RendererString(*second), second->info().renderer);
  second.reset();  // destroying the current context leaves the other one usable
  first->MakeCurrent();
  EXPECT_EQ(RendererString(*first), first->info().renderer);
}

INSTANTIATE_TEST_SUITE_P(Backends, BackendTest, ::testing::Values("egl", "osmesa"));

TEST_F(GlContextTest, AutoPicksAWorkingBackend) {
  CREATE_OR_SKIP(gl, "auto");
  EXPECT_TRUE(gl->info().backend == "egl" || gl->info().backend == "osmesa");
}

TEST_F(GlContextTest, EmptyNameFollowsMujocoGl) {
  CREATE_OR_SKIP(probe, "osmesa");
  setenv("MUJOCO_GL", "osmesa", 1);
  EXPECT_EQ(CreateGlContext("")->info().backend, "osmesa");
  unsetenv("MUJOCO_GL");
  EXPECT_FALSE(CreateGlContext("")->info().backend.empty());  // auto
}

TEST_F(GlContextTest, UnknownBackendNameIsAUsageError) {
  try {
    CreateGlContext("glfw");
    FAIL() << "expected UsageError";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("'glfw'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("auto|egl|osmesa"), std::string::npos) << e.what();
  }
  setenv("MUJOCO_GL", "vulkan", 1);
  try {
    CreateGlContext("");
    FAIL() << "expected UsageError";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("MUJOCO_GL 'vulkan'"), std::string::npos) << e.what();
  }
}

TEST_F(GlContextTest, EglDeviceIndexOutOfRange) {
  CREATE_OR_SKIP(probe, "egl");
  // Either a usage error naming the index and the valid range, or (an EGL without device
  // enumeration) a run-time error saying so; never a silent fallback to another device.
  try {
    CreateGlContext("egl", 97);
    FAIL() << "device 97 should not exist";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("--gpu 97 is out of range"), std::string::npos)
        << e.what();
  } catch (const RunError& e) {
    EXPECT_NE(std::string(e.what()).find("enumerates none"), std::string::npos) << e.what();
  }
  setenv("MUJOCO_EGL_DEVICE_ID", "first", 1);
  EXPECT_THROW(CreateGlContext("egl"), UsageError);
}

TEST_F(GlContextTest, EglDeviceZeroIsSelectable) {
  CREATE_OR_SKIP(probe, "egl");
  probe.reset();
  std::unique_ptr<GlContext> gl;
  try {
    gl = CreateGlContext("egl", 0);
  } catch (const RunError& e) {
    GTEST_SKIP() << "no enumerable EGL device: " << e.what();
  }
  EXPECT_NE(gl->info().device.find("EGL device 0"), std::string::npos) << gl->info().device;
  EXPECT_FALSE(RendererString(*gl).empty());
}

// A value that means "a windowed GL" (many laptops set MUJOCO_GL=glfw globally): one warning,
// then auto, in threads and in worker processes alike.
TEST(RoughEdges, WindowedMujocoGlWarnsOnceThenRendersWithAuto) {
  TempDir tmp;
  for (const char* value : {"glfw", "glx"}) {
    for (const char* mode : {"thread", "process"}) {
      SCOPED_TRACE(std::string(value) + " " + mode);
      const fs::path out = tmp.path() / (std::string(value) + mode);
      const CommandResult r =
          RunCommand(std::string("MUJOCO_GL=") + value + " " + FETCHSCOPE_BIN +
                     " record --no-report --env-id FetchReach-v4 --episodes 2 --steps 2 --width 32 "
                     "--height 32 --jobs 2 --worker-mode " +
                     mode + " --out " + out.string());
      ASSERT_EQ(r.exit_code, 0) << r.output;
      EXPECT_EQ(Count(r.output, std::string("warning: MUJOCO_GL=") + value), 1) << r.output;
      EXPECT_NE(r.output.find("off-screen"), std::string::npos) << r.output;
      EXPECT_TRUE(fs::exists(out / "episode_001.mp4"));
    }
  }
  // render makes one context: one warning too
  const CommandResult r =
      RunCommand(std::string("MUJOCO_GL=glfw ") + FETCHSCOPE_BIN +
                 " render --width 32 --height 32 -o " + (tmp.path() / "f.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(Count(r.output, "warning: MUJOCO_GL=glfw"), 1) << r.output;
}

// A plain mistake keeps its error, now with a suggestion; so does --backend.
TEST(RoughEdges, MistypedMujocoGlIsStillAnErrorWithASuggestion) {
  TempDir tmp;
  const std::string png = (tmp.path() / "f.png").string();
  CommandResult r = RunCommand(std::string("MUJOCO_GL=eglx ") + FETCHSCOPE_BIN +
                               " render --width 32 --height 32 -o " + png);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("MUJOCO_GL 'eglx' is not known (did you mean 'egl'?)"), std::string::npos)
      << r.output;
  r = RunFetchscope("render --backend osmesaa --width 32 --height 32 -o " + png);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("'osmesaa' is not known (did you mean 'osmesa'?)"), std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(png));
}

}  // namespace
}  // namespace fetchscope
