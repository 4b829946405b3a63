// Randomized looks (render/look.h, issue 49): parsing and bad input, the draw's ranges, seed
// rule, contrast rule and JSON form; the renderer's frames, physics, camera geometry and texture
// uploads under a look; render --randomize as a black box.
#include "render/look.h"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "base/errors.h"
#include "base/json_util.h"
#include "encode/png_io.h"
#include "render/camera.h"
#include "render/gl_context.h"
#include "render/obs_view.h"
#include "render/renderer.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/fetch_env.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using testing::RunFetchscope;
using testing::TempDir;

constexpr int kSeeds = 200;

// The message of the UsageError `f` throws ("" when it throws none).
template <typename F>
std::string UsageMessage(F&& f) {
  try {
    f();
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}

FetchEnv PushEnv() { return FetchEnv(FindEnvSpec("FetchPush-v4"), ResolveAssets("bundled")); }

LookConfig AllKinds() { return ParseRandomize("colors,textures,lighting,camera"); }

TEST(LookParse, KindsAndNone) {
  const LookConfig all = ParseRandomize("colors, textures,lighting,camera");
  EXPECT_TRUE(all.colors && all.textures && all.lighting && all.camera);
  EXPECT_FALSE(ParseRandomize("none").any());
  EXPECT_FALSE(ParseRandomize("").any());
  const LookConfig one = ParseRandomize("lighting");
  EXPECT_TRUE(one.lighting && !one.colors && !one.textures && !one.camera);
}

TEST(LookParse, BadKindIsOneLineNamingIt) {
  const std::string bad = UsageMessage([] { ParseRandomize("colors,sparkles"); });
  EXPECT_NE(bad.find("'sparkles'"), std::string::npos) << bad;
  EXPECT_NE(bad.find("accepted: colors, textures, lighting, camera"), std::string::npos) << bad;
  EXPECT_EQ(bad.find('\n'), std::string::npos) << bad;
  EXPECT_NE(UsageMessage([] { ParseRandomize("colors,colors"); }).find("twice"), std::string::npos);
  EXPECT_NE(UsageMessage([] { ParseRandomize("colors,,camera"); }).find("empty"),
            std::string::npos);
}

TEST(LookConfigFile, BadInputIsOneLineNamingTheKeyOrRange) {
  TempDir dir;
  const auto message = [&](const std::string& text) {
    const fs::path file = dir.path() / "look.json";
    std::ofstream(file) << text;
    LookConfig config = AllKinds();
    return UsageMessage([&] { ReadLookConfig(file.string(), &config); });
  };
  const std::string unknown = message(R"({"camera_fovy": [1, 2], "colour_rgb": [0, 1]})");
  EXPECT_NE(unknown.find("unknown key 'colour_rgb'"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("accepted: robot_colors, color_rgb"), std::string::npos) << unknown;
  const std::string reversed = message(R"({"light_pos": [0.2, 0.1]})");
  EXPECT_NE(reversed.find("range light_pos has min 0.2 > max 0.1"), std::string::npos) << reversed;
  const std::string not_number = message(R"({"camera_pos": ["a", 1]})");
  EXPECT_NE(not_number.find("camera_pos must be a pair of numbers"), std::string::npos)
      << not_number;
  EXPECT_NE(message("{").find("JSON"), std::string::npos);
  for (const std::string& m : {unknown, reversed, not_number}) {
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    EXPECT_NE(m.find("look.json"), std::string::npos) << m;
  }
  EXPECT_EQ(message(R"({"camera_fovy": [-1, 1], "robot_colors": true})"), "");
}

TEST(LookDraw, ConfigRangesAreRespected) {
  FetchEnv env = PushEnv();
  const mjModel* m = env.model();
  LookConfig config = AllKinds();
  nlohmann::json ranges = {{"color_rgb", {0.3, 0.4}},       {"texture_rgb", {0.6, 0.7}},
                           {"texture_scale", {2.0, 2.5}},   {"light_pos", {0.01, 0.02}},
                           {"light_ambient", {-0.05, 0.0}}, {"camera_pos", {-0.002, 0.003}},
                           {"camera_angle", {0.01, 0.02}},  {"camera_fovy", {1.0, 2.0}},
                           {"light_dir_angle", {0.1, 0.2}}, {"robot_colors", true}};
  ApplyLookConfig(ranges, "test", &config);
  const std::vector<std::string> keys = {"default", "external_camera_0"};
  const auto within = [](double v, double lo, double hi) { return v >= lo && v <= hi; };
  for (int s = 0; s < kSeeds; ++s) {
    const LookDraw d = DrawLook(config, LookSeed(s, 0), keys, m);
    ASSERT_GT(d.colors_by_part.size(), 3u);  // robot links too
    for (const auto& [part, rgba] : d.colors_by_part) {
      for (int k = 0; k < 3; ++k) {
        // the contrast fallback may turn the object black or white
        if (part != "object") {
          EXPECT_TRUE(within(rgba[k], 0.3, 0.4)) << part << " " << rgba[k];
        }
      }
    }
    for (const auto& [surface, t] : d.textures_by_surface) {
      EXPECT_TRUE(within(t.scale, 2.0, 2.5)) << t.scale;
      for (int k = 0; k < 3; ++k) EXPECT_TRUE(within(t.rgb1[k], 0.6, 0.7)) << t.rgb1[k];
    }
    ASSERT_EQ(d.lights.size(), static_cast<size_t>(m->nlight));
    for (const auto& [id, l] : d.lights) {
      for (int k = 0; k < 3; ++k) {
        EXPECT_TRUE(within((*l.pos)[k] - m->light_pos[3 * id + k], 0.01 - 1e-12, 0.02 + 1e-12));
        EXPECT_TRUE(within((*l.ambient)[k] - m->light_ambient[3 * id + k], -0.05 - 1e-6, 1e-6));
      }
      double dir0[3] = {m->light_dir[3 * id], m->light_dir[3 * id + 1], m->light_dir[3 * id + 2]};
      mju_normalize3(dir0);
      const double cosine = mju_dot3(dir0, l.dir->data());
      EXPECT_TRUE(within(std::acos(std::min(1.0, cosine)), 0.1 - 1e-9, 0.2 + 1e-9));
    }
    ASSERT_EQ(d.cameras.size(), 2u);
    const double base[2] = {m->vis.global.fovy,
                            m->cam_fovy[mj_name2id(m, mjOBJ_CAMERA, "external_camera_0")]};
    for (size_t i = 0; i < keys.size(); ++i) {
      const CameraJitter& j = d.cameras.at(keys[i]);
      for (int k = 0; k < 3; ++k) EXPECT_TRUE(within(j.dpos[k], -0.002, 0.003)) << j.dpos[k];
      EXPECT_TRUE(within(std::sqrt(mju_dot3(j.drot.data(), j.drot.data())), 0.01, 0.02));
      EXPECT_TRUE(within(*j.fovy - base[i], 1.0 - 1e-9, 2.0 + 1e-9)) << *j.fovy;
    }
  }
}

TEST(LookDraw, SameSeedSameDrawOtherSeedOtherDraw) {
  FetchEnv env = PushEnv();
  const std::vector<std::string> keys = {"default"};
  const LookDraw a = DrawLook(AllKinds(), LookSeed(5, 0), keys, env.model());
  const LookDraw b = DrawLook(AllKinds(), LookSeed(5, 0), keys, env.model());
  const LookDraw c = DrawLook(AllKinds(), LookSeed(5, 1), keys, env.model());
  const LookDraw d = DrawLook(AllKinds(), LookSeed(6, 0), keys, env.model());
  EXPECT_EQ(DumpJson(LookJson(a)), DumpJson(LookJson(b)));
  EXPECT_NE(DumpJson(LookJson(a)), DumpJson(LookJson(c)));
  EXPECT_NE(DumpJson(LookJson(a)), DumpJson(LookJson(d)));
  EXPECT_NE(a.colors_by_part.at("object"), d.colors_by_part.at("object"));
  // the look's generator is its own: not the seed itself, and distinct per episode
  std::set<uint64_t> seeds;
  for (int s = 0; s < 50; ++s) {
    for (int e = 0; e < 20; ++e) seeds.insert(LookSeed(s, e));
  }
  EXPECT_EQ(seeds.size(), 1000u);
  EXPECT_NE(LookSeed(0, 0), 0u);
  // a kind's stream is its own: turning lighting on leaves the colours as they were
  const LookDraw colours = DrawLook(ParseRandomize("colors"), 99, keys, env.model());
  const LookDraw lit = DrawLook(ParseRandomize("colors,lighting"), 99, keys, env.model());
  EXPECT_EQ(colours.colors_by_part, lit.colors_by_part);
}

TEST(LookDraw, JsonRoundTripsExactlyAndIsStrict) {
  FetchEnv env = PushEnv();
  LookConfig config = AllKinds();
  config.robot_colors = true;
  for (int s = 0; s < 20; ++s) {
    const LookDraw d = DrawLook(config, LookSeed(s, 3), {"default", "track"}, env.model());
    const std::string text = DumpJson(LookJson(d));
    const LookDraw back = ParseLookJson(nlohmann::json::parse(text), "look.json");
    EXPECT_EQ(DumpJson(LookJson(back)), text);
    EXPECT_EQ(back.seed, d.seed);
    EXPECT_EQ(back.colors_by_part, d.colors_by_part);  // bitwise: doubles round-trip
    EXPECT_EQ(back.cameras.at("track").drot, d.cameras.at("track").drot);
    EXPECT_EQ(*back.lights.at(0).dir, *d.lights.at(0).dir);
    EXPECT_TRUE(back.textures_by_surface.at("floor") == d.textures_by_surface.at("floor"));
  }
  nlohmann::json j = LookJson(DrawLook(config, 1, {"default"}, env.model()));
  j["cameras"]["default"]["dpox"] = {0, 0, 0};
  const std::string bad = UsageMessage([&] { ParseLookJson(j, "look.json"); });
  EXPECT_NE(bad.find("look.cameras.default.dpox is not a known key"), std::string::npos) << bad;
  EXPECT_EQ(bad.find('\n'), std::string::npos);
  // a missing field means unchanged
  const LookDraw sparse = ParseLookJson(
      nlohmann::json::parse(R"({"seed": 1, "kinds": ["camera"], "cameras": {"default": {}}})"),
      "x");
  EXPECT_FALSE(sparse.cameras.at("default").fovy.has_value());
  EXPECT_TRUE(sparse.colors_by_part.empty());
}

TEST(LookDraw, ObjectKeepsItsContrastWithTheTable) {
  FetchEnv env = PushEnv();
  for (const char* kinds : {"colors", "textures", "colors,textures"}) {
    for (int s = 0; s < 1000; ++s) {
      const LookDraw d = DrawLook(ParseRandomize(kinds), LookSeed(s, 0), {}, env.model());
      ASSERT_GE(ObjectContrast(d, env.model()), kMinObjectContrast) << kinds << " seed " << s;
    }
  }
  // ranges that can never contrast: the fallback keeps the object visible
  LookConfig grey = ParseRandomize("colors,textures");
  ApplyLookConfig({{"color_rgb", {0.5, 0.5}}, {"texture_rgb", {0.5, 0.5}}}, "test", &grey);
  const LookDraw d = DrawLook(grey, 3, {}, env.model());
  EXPECT_GE(ObjectContrast(d, env.model()), 0.5);
  LookConfig wide = ParseRandomize("colors,textures");
  ApplyLookConfig({{"texture_rgb", {0.0, 1.0}}, {"color_rgb", {0.45, 0.55}}}, "test", &wide);
  for (int s = 0; s < 200; ++s) {
    EXPECT_GE(ObjectContrast(DrawLook(wide, s, {}, env.model()), env.model()), 0.2);
  }
}

// ---- with a GL context ----

std::unique_ptr<GlContext> AnyContext() {
  unsetenv("DISPLAY");
  try {
    return CreateGlContext("auto");
  } catch (const RunError& e) {
    std::cout << "[  SKIPPED ] no GL: " << e.what() << "\n";
    return nullptr;
  }
}

RenderOptions SmallOptions(const mjModel* model, const std::string& cameras) {
  RenderOptions o;
  o.width = 160;
  o.height = 160;
  o.cameras = ParseCameraList(cameras, model);
  o.overlays = ParseOverlays("none");
  o.msaa_samples = 0;
  o.readback = Readback::kSync;
  return o;
}

double DifferentFraction(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  long differ = 0;
  for (size_t i = 0; i + 2 < a.size(); i += 3) {
    int most = 0;
    for (int k = 0; k < 3; ++k) most = std::max(most, std::abs(a[i + k] - b[i + k]));
    if (most > 8) ++differ;
  }
  return static_cast<double>(differ) / static_cast<double>(a.size() / 3);
}

TEST(LookRender, FramesChangeAndDifferBetweenDraws) {
  auto gl = AnyContext();
  if (!gl) GTEST_SKIP();
  FetchEnv env = PushEnv();
  env.Reset(11);
  Renderer r(*gl, env.model(), SmallOptions(env.model(), "default"));
  std::vector<uint8_t> plain(160 * 160 * 3), one(plain.size()), two(plain.size()),
      again(plain.size());
  const FrameInfo info;
  r.Render(env.data(), info, plain.data());
  const LookConfig config = ParseRandomize("colors,textures,lighting");
  const LookDraw a = DrawLook(config, LookSeed(11, 0), r.camera_keys(), env.model());
  const LookDraw b = DrawLook(config, LookSeed(11, 1), r.camera_keys(), env.model());
  r.SetLook(&a);
  r.Render(env.data(), info, one.data());
  r.SetLook(&b);
  r.Render(env.data(), info, two.data());
  r.SetLook(nullptr);
  r.Render(env.data(), info, again.data());
  EXPECT_GT(DifferentFraction(plain, one), 0.10);
  EXPECT_GT(DifferentFraction(plain, two), 0.10);
  EXPECT_GT(DifferentFraction(one, two), 0.10);
  EXPECT_EQ(plain, again);  // the plain look comes back exactly
}

TEST(LookRender, PhysicsIsUnchanged) {
  auto gl = AnyContext();
  if (!gl) GTEST_SKIP();
  FetchEnv plain = PushEnv(), looked = PushEnv();
  plain.Reset(4);
  looked.Reset(4);
  Renderer r(*gl, looked.model(), SmallOptions(looked.model(), "default,external_camera_0"));
  const LookDraw look = DrawLook(AllKinds(), LookSeed(4, 0), r.camera_keys(), looked.model());
  r.SetLook(&look);
  std::vector<uint8_t> rgb(static_cast<size_t>(r.width()) * r.height() * 3), layer;
  const mjModel* m = looked.model();
  const auto same_state = [&] {
    const mjData* a = plain.data();
    const mjData* b = looked.data();
    return std::memcmp(a->qpos, b->qpos, sizeof(mjtNum) * m->nq) == 0 &&
           std::memcmp(a->qvel, b->qvel, sizeof(mjtNum) * m->nv) == 0 &&
           std::memcmp(a->xpos, b->xpos, sizeof(mjtNum) * 3 * m->nbody) == 0;
  };
  for (int t = 0; t < 15; ++t) {
    r.Render(looked.data(), FrameInfo{}, rgb.data());
    r.RenderLayer(looked.data(), FrameInfo{}, Layer::kSegmentation, &layer);
    r.RenderLayer(looked.data(), FrameInfo{}, Layer::kDepth, &layer);
    ASSERT_TRUE(same_state()) << "step " << t;
    Action action;
    action.value = {0.3, -0.2, 0.1, (t % 2) ? 1.0 : -1.0};
    plain.Step(action);
    looked.Step(action);
    ASSERT_TRUE(same_state()) << "step " << t;
  }
}

TEST(LookRender, CameraDrawProjectsTheObjectOntoItsSegmentation) {
  auto gl = AnyContext();
  if (!gl) GTEST_SKIP();
  FetchEnv env = PushEnv();
  env.Reset(2);
  const mjModel* m = env.model();
  ObsSetup setup;
  for (const char* text : {"external_camera_0", "default"}) {
    ObsCamera c;
    c.name = c.text = text;
    c.spec = ParseCameraList(text, m).front();
    setup.cameras.push_back(c);
  }
  setup.width = 200;
  setup.height = 160;
  setup.layers = {Layer::kSegmentation};
  setup.msaa_samples = 0;
  ObsRenderer obs(*gl, env.model(), setup);
  obs.Render(env.data(), FrameInfo{});
  const ObsCameraGeometry plain = obs.images(0).geometry;
  LookConfig config = ParseRandomize("camera");  // a large jitter, so that a wrong pose shows
  ApplyLookConfig(
      {{"camera_pos", {-0.05, 0.05}}, {"camera_angle", {0.06, 0.1}}, {"camera_fovy", {-12, -8}}},
      "test", &config);
  const int object = mj_name2id(m, mjOBJ_BODY, "object0");
  const double* p = env.data()->xpos + 3 * object;
  for (int s = 0; s < 5; ++s) {
    const LookDraw look = DrawLook(config, LookSeed(s, 0), obs.camera_keys(), m);
    obs.SetLook(&look);
    obs.Render(env.data(), FrameInfo{});
    for (size_t i = 0; i < obs.cameras(); ++i) {
      const ObsCameraGeometry& g = obs.images(i).geometry;
      EXPECT_NEAR(g.fovy, *look.cameras.at(setup.cameras[i].text).fovy, 1e-3);
      // world -> camera frame: R^T (p - t), R from the pose's quaternion
      double rel[3] = {p[0] - g.pose[0], p[1] - g.pose[1], p[2] - g.pose[2]}, cam[3];
      const double q[4] = {g.pose[3], -g.pose[4], -g.pose[5], -g.pose[6]};
      mju_rotVecQuat(cam, rel, q);
      ASSERT_LT(cam[2], 0);  // in front: the camera looks along -z
      const int u = static_cast<int>(std::lround(g.cx + g.fx * cam[0] / -cam[2]));
      const int v = static_cast<int>(std::lround(g.cy - g.fy * cam[1] / -cam[2]));
      ASSERT_TRUE(u >= 0 && u < setup.width && v >= 0 && v < setup.height) << u << "," << v;
      EXPECT_EQ(obs.images(i).segmentation[static_cast<size_t>(v) * setup.width + u], object)
          << "seed " << s << " camera " << setup.cameras[i].text << " pixel " << u << "," << v;
    }
  }
  EXPECT_NE(obs.images(0).geometry.pose, plain.pose);
  EXPECT_NE(obs.images(0).geometry.fy, plain.fy);
}

TEST(LookRender, TexturesUploadOncePerLook) {
  auto gl = AnyContext();
  if (!gl) GTEST_SKIP();
  FetchEnv env = PushEnv();
  env.Reset(0);
  Renderer r(*gl, env.model(), SmallOptions(env.model(), "default"));
  const LookDraw a = DrawLook(ParseRandomize("textures"), 1, r.camera_keys(), env.model());
  const LookDraw b = DrawLook(ParseRandomize("textures"), 2, r.camera_keys(), env.model());
  std::vector<uint8_t> rgb(160 * 160 * 3), layer;
  r.SetLook(&a);
  EXPECT_EQ(r.texture_uploads(), 2);  // table and floor
  for (int t = 0; t < 30; ++t) {
    r.Render(env.data(), FrameInfo{}, rgb.data());
    r.RenderLayer(env.data(), FrameInfo{}, Layer::kDepth, &layer);
  }
  r.SetLook(&a);  // the same look again: nothing to upload
  EXPECT_EQ(r.texture_uploads(), 2);
  r.SetLook(&b);
  EXPECT_EQ(r.texture_uploads(), 4);
}

// ---- the render command ----

TEST(LookCli, BadInputIsOneLine) {
  TempDir dir;
  const std::string out = " -o " + (dir.path() / "x.png").string();
  const auto check = [&](const std::string& args, const std::string& expected) {
    const auto r = RunFetchscope("render --env-id FetchPush-v4" + out + " " + args);
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_EQ(testing::LineCount(r.output), 1) << r.output;
    EXPECT_NE(r.output.find(expected), std::string::npos) << r.output;
  };
  check("--randomize colors,glitter", "'glitter' is not a kind");
  const fs::path reversed = dir.path() / "reversed.json";
  std::ofstream(reversed) << R"({"camera_fovy": [4, -4]})";
  check("--randomize camera --randomize-config " + reversed.string(),
        "range camera_fovy has min 4.0 > max -4.0");
  const fs::path unknown = dir.path() / "unknown.json";
  std::ofstream(unknown) << R"({"fovy": [0, 1]})";
  check("--randomize camera --randomize-config " + unknown.string(), "unknown key 'fovy'");
}

TEST(LookCli, RandomizedPngDiffersFromThePlainOne) {
  TempDir dir;
  const std::string base = "render --env-id FetchPush-v4 --seed 8 --width 120 --height 120 ";
  const fs::path plain = dir.path() / "plain.png", looked = dir.path() / "look.png",
                 none = dir.path() / "none.png";
  ASSERT_EQ(RunFetchscope(base + "-o " + plain.string()).exit_code, 0);
  const auto r = RunFetchscope(base + "--randomize colors,textures,lighting -o " + looked.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(testing::LineCount(r.output), 1) << r.output;  // "wrote ...": nothing extra
  ASSERT_EQ(RunFetchscope(base + "--randomize none -o " + none.string()).exit_code, 0);
  const Image a = ReadPng(plain.string()), b = ReadPng(looked.string());
  EXPECT_GT(DifferentFraction(a.pixels, b.pixels), 0.10);
  EXPECT_EQ(testing::ReadFile(plain), testing::ReadFile(none));
}

}  // namespace
}  // namespace fetchscope
