// bench --what render and encode: render+readback frames/s per backend and size beside
// MuJoCo's own record sample (mujoco-record under xvfb-run), and encode frames/s per codec.
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>

#include "base/errors.h"
#include "base/json_util.h"
#include "base/process.h"
#include "bench/bench.h"
#include "bench/children.h"
#include "encode/video_writer.h"
#include "fetchscope/paths.h"
#include "render/gpu_select.h"
#include "render/renderer.h"
#include "render/view.h"
#include "run/manifest.h"
#include "run/run_files.h"
#include "src/episode.h"
#include "src/fetch_env.h"
#include "src/policy.h"
#include "src/versions.h"

namespace fetchscope::bench {

namespace fs = std::filesystem;

namespace {

// Render+readback frames/s of one size and msaa on `gl`, for a third of `budget_s`, with the
// scripted policy's episodes: its row. Where auto picked samples, 0 joins `msaa_values`.
nlohmann::json RenderRow(GlContext& gl, const EnvSpec& spec, const AssetSource& assets, int w,
                         int h, const std::string& msaa, double budget_s,
                         std::vector<std::string>* msaa_values) {
  FetchEnv env(spec, assets);
  RenderOptions options;  // render's defaults: the default camera and overlays
  options.width = w;
  options.height = h;
  options.msaa_samples = msaa == "auto" ? kMsaaAuto : std::stoi(msaa);  // auto, 4 or 0
  Renderer renderer(gl, env.model(), options);
  if (msaa == "auto" && renderer.msaa_samples() != 0 && msaa_values->size() == 2)
    msaa_values->push_back("0");
  PolicyContext context;
  auto policy = MakePolicy(PolicySpec::Scripted(), spec, context);
  std::vector<uint8_t> rgb(static_cast<size_t>(w) * h * 3);
  long frames = 0;
  double busy = 0;
  int episode = 0;
  // warm up once (shader compilation, first-touch allocations)
  RunEpisode(env, *policy, 0, 0, 1, [&](const StepRecord& r, const StepResult*) {
    renderer.Render(env.data(), MakeFrameInfo(env, r), rgb.data());
    return true;
  });
  while (busy < budget_s / 3) {
    RunEpisode(env, *policy, episode, episode, 50, [&](const StepRecord& r, const StepResult*) {
      const auto t0 = Clock::now();
      renderer.Render(env.data(), MakeFrameInfo(env, r), rgb.data());
      busy += Since(t0);
      ++frames;
      return busy < budget_s / 3;
    });
    ++episode;
  }
  const int samples = renderer.msaa_samples();
  std::printf("%-26s %4dx%-5d %.1f\n", (gl.info().backend + " " + MsaaLabel(msaa, samples)).c_str(),
              w, h, frames / busy);
  return {{"backend", gl.info().backend},
          {"gl_renderer", gl.info().renderer},
          {"msaa_requested", msaa},
          {"msaa", samples},
          {"msaa_reason", renderer.msaa_reason()},
          {"width", w},
          {"height", h},
          {"frames", frames},
          {"frames_per_s", frames / busy}};
}

// The peer: MuJoCo's own record sample (mujoco-record under xvfb-run).
nlohmann::json PeerRenderRow(const AssetSource& assets) {
  const std::string rgb =
      (fs::temp_directory_path() / ("fetchscope_bench_" + std::to_string(getpid()) + ".rgb"))
          .string();
  nlohmann::json peer = PeerMujocoRecord(GenuineModel(assets, "pick_and_place.xml"), 250, rgb);
  fs::remove(rgb);
  if (peer.contains("frames_per_s")) {
    std::printf("%-26s %4dx%-5d %.1f  (physics included, process start included)\n",
                "mujoco-record (xvfb)", 640, 480, peer["frames_per_s"].get<double>());
  } else {
    std::printf("mujoco-record: %s\n", peer["skipped"].get<std::string>().c_str());
  }
  return peer;
}

}  // namespace

nlohmann::json BenchRender(const AssetSource& assets, const std::string& backends, double budget_s,
                           bool peers) {
  nlohmann::json result;
  nlohmann::json rows = nlohmann::json::array();
  const EnvSpec& spec = FindEnvSpec("FetchPickAndPlace-v4");
  const std::pair<int, int> sizes[] = {{480, 480}, {640, 480}, {1280, 720}};
  std::printf("%-26s %-10s %-60s\n", "render+readback", "size", "frames/s");
  for (const std::string& backend : Split(backends)) {
    std::unique_ptr<GlContext> gl;
    try {
      gl = CreateGlContext(backend, -1);
    } catch (const std::exception& e) {
      rows.push_back({{"backend", backend}, {"skipped", e.what()}});
      std::printf("%-26s skipped: %s\n", backend.c_str(), e.what());
      continue;
    }
    // the default (auto) beside Gymnasium's 4; 0 too where auto did not already pick it
    std::vector<std::string> msaa_values = {"auto", "4"};
    for (size_t m = 0; m < msaa_values.size(); ++m)
      for (auto [w, h] : sizes) {
        const std::string msaa = msaa_values[m];  // a copy: the list may grow below
        rows.push_back(RenderRow(*gl, spec, assets, w, h, msaa, budget_s, &msaa_values));
      }
  }
  result["fetchscope"] = rows;
  if (peers) result["mujoco_record"] = PeerRenderRow(assets);
  return result;
}

nlohmann::json BenchEncode(double budget_s) {
  nlohmann::json rows = nlohmann::json::array();
  const int w = 640, h = 480;
  // scene-like content: a gradient with a moving block, so the encoder has real work
  std::vector<std::vector<uint8_t>> frames(25,
                                           std::vector<uint8_t>(static_cast<size_t>(w) * h * 3));
  for (size_t f = 0; f < frames.size(); ++f) {
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        uint8_t* p = &frames[f][(static_cast<size_t>(y) * w + x) * 3];
        const bool block =
            std::abs(x - 100 - static_cast<int>(f) * 12) < 40 && std::abs(y - 240) < 40;
        p[0] = block ? 200 : static_cast<uint8_t>(110 + y / 8);
        p[1] = block ? 60 : static_cast<uint8_t>(200 - x / 16);
        p[2] = block ? 40 : static_cast<uint8_t>(140 + (x ^ y) % 7);
      }
    }
  }
  std::printf("%-26s %-10s %s\n", "encode", "size", "frames/s");
  for (const char* codec : {"libx264", "h264_nvenc"}) {
    const std::string path =
        (fs::temp_directory_path() / ("fetchscope_bench_" + std::to_string(getpid()) + ".mp4"))
            .string();
    try {
      VideoOptions options;
      options.width = w;
      options.height = h;
      options.codec = codec;
      VideoWriter writer(path, options);
      long n = 0;
      const auto start = Clock::now();
      while (Since(start) < budget_s / 2) writer.AddFrame(frames[n++ % frames.size()].data());
      writer.Finish();
      const double s = Since(start);
      std::printf("%-26s %4dx%-5d %.1f\n", codec, w, h, n / s);
      rows.push_back({{"codec", codec},
                      {"width", w},
                      {"height", h},
                      {"frames", n},
                      {"frames_per_s", n / s},
                      {"preset", kDefaultVideoPreset}});
    } catch (const std::exception& e) {
      std::printf("%-26s skipped: %s\n", codec, e.what());
      rows.push_back({{"codec", codec}, {"skipped", e.what()}});
    }
    std::error_code ec;
    fs::remove(path, ec);
  }
  return rows;
}

}  // namespace fetchscope::bench
