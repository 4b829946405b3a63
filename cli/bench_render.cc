// bench's rendering, encoding and recording parts, with the peers measured in the same run:
// MuJoCo's own record sample (Debian's mujoco-record under xvfb-run) and the ffmpeg program.
#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "cli/bench.h"
#include "cli/common.h"
#include "cli/render_common.h"
#include "render/renderer.h"
#include "render/video_writer.h"
#include "src/episode.h"
#include "src/fetch_env.h"

namespace fetchscope::cli {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

struct ChildRun {
  int exit_code = -1;
  double wall_s = 0;
  double peak_rss_mib = 0;
};

// Runs a shell command with output discarded; wall time and the child's peak RSS.
ChildRun RunChild(const std::string& command) {
  ChildRun run;
  const auto start = Clock::now();
  pid_t pid = fork();
  if (pid == 0) {
    int devnull = open("/dev/null", O_WRONLY);
    dup2(devnull, STDOUT_FILENO);
    dup2(devnull, STDERR_FILENO);
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  int status = 0;
  rusage usage{};
  wait4(pid, &status, 0, &usage);
  run.wall_s = Since(start);
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  run.peak_rss_mib = usage.ru_maxrss / 1024.0;
  return run;
}

bool HaveProgram(const std::string& name) {
  return RunChild("command -v " + name).exit_code == 0;
}

std::vector<std::string> Split(const std::string& list) {
  std::vector<std::string> out;
  std::stringstream ss(list);
  for (std::string s; std::getline(ss, s, ',');) {
    if (!s.empty()) out.push_back(s);
  }
  return out;
}

// The genuine model the peers run on: $FETCHSCOPE_ASSETS, ../shared, or --assets DIR.
std::string GenuineModel(const AssetSource& assets, const std::string& file) {
  if (assets.kind == "dir") return assets.fetch_dir + "/" + file;
  for (const char* candidate : std::vector<const char*>{std::getenv("FETCHSCOPE_ASSETS"), FETCHSCOPE_GENUINE_ASSETS}) {
    if (candidate && fs::exists(fs::path(candidate) / "fetch" / file)) {
      return (fs::path(candidate) / "fetch" / file).string();
    }
  }
  return "";
}

// mujoco-record renders `frames` frames at 25 fps of simulated time (640x480, its default).
nlohmann::json PeerMujocoRecord(const std::string& model, int frames, const std::string& rgb_out) {
  if (model.empty()) return {{"skipped", "no genuine assets (pass --assets DIR)"}};
  if (!HaveProgram("mujoco-record") || !HaveProgram("xvfb-run")) {
    return {{"skipped", "mujoco-record or xvfb-run missing: tools/install-deps.sh --bench"}};
  }
  const double duration = frames / 25.0 - 1e-6;
  const std::string cmd = "xvfb-run -a -s '-screen 0 1024x768x24' mujoco-record '" + model + "' " +
                          std::to_string(duration) + " 25 '" + rgb_out + "'";
  const ChildRun run = RunChild(cmd);
  std::error_code ec;
  const auto bytes = fs::file_size(rgb_out, ec);
  const long got = ec ? 0 : static_cast<long>(bytes / (640 * 480 * 3));
  // the sample returns 1 even when it succeeded: judge by the frames it wrote
  if (got == 0) return {{"skipped", "mujoco-record failed (exit " + std::to_string(run.exit_code) + ")"}};
  return {{"program", "xvfb-run mujoco-record"}, {"model", model}, {"frames", got},
          {"wall_s", run.wall_s}, {"frames_per_s", got / run.wall_s}, {"peak_rss_mib", run.peak_rss_mib}};
}

}  // namespace

nlohmann::json BenchRender(const AssetSource& assets, const std::string& backends, double budget_s, bool peers) {
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
    for (int msaa : {-1, 0})
    for (auto [w, h] : sizes) {
      FetchEnv env(spec, assets);
      ViewOptions view;
      view.width = w;
      view.height = h;
      view.msaa = msaa;
      const RenderOptions options = MakeRenderOptions(view, env.model());
      Renderer renderer(*gl, env.model(), options);
      PolicyContext context;
      auto policy = MakePolicy("scripted", spec, context);
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
      const int samples = env.model()->vis.quality.offsamples;
      std::printf("%-26s %4dx%-5d %.1f\n", (gl->info().backend + " msaa " + std::to_string(samples)).c_str(), w, h,
                  frames / busy);
      rows.push_back({{"backend", gl->info().backend}, {"gl_renderer", gl->info().renderer}, {"msaa", samples},
                      {"width", w}, {"height", h}, {"frames", frames}, {"frames_per_s", frames / busy}});
    }
  }
  result["fetchscope"] = rows;
  if (peers) {
    const std::string rgb = (fs::temp_directory_path() / ("fetchscope_bench_" + std::to_string(getpid()) + ".rgb")).string();
    result["mujoco_record"] = PeerMujocoRecord(GenuineModel(assets, "pick_and_place.xml"), 250, rgb);
    fs::remove(rgb);
    if (result["mujoco_record"].contains("frames_per_s")) {
      std::printf("%-26s %4dx%-5d %.1f  (physics included, process start included)\n", "mujoco-record (xvfb)", 640, 480,
                  result["mujoco_record"]["frames_per_s"].get<double>());
    } else {
      std::printf("mujoco-record: %s\n", result["mujoco_record"]["skipped"].get<std::string>().c_str());
    }
  }
  return result;
}

nlohmann::json BenchEncode(double budget_s) {
  nlohmann::json rows = nlohmann::json::array();
  const int w = 640, h = 480;
  // scene-like content: a gradient with a moving block, so the encoder has real work
  std::vector<std::vector<uint8_t>> frames(25, std::vector<uint8_t>(static_cast<size_t>(w) * h * 3));
  for (size_t f = 0; f < frames.size(); ++f) {
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        uint8_t* p = &frames[f][(static_cast<size_t>(y) * w + x) * 3];
        const bool block = std::abs(x - 100 - static_cast<int>(f) * 12) < 40 && std::abs(y - 240) < 40;
        p[0] = block ? 200 : static_cast<uint8_t>(110 + y / 8);
        p[1] = block ? 60 : static_cast<uint8_t>(200 - x / 16);
        p[2] = block ? 40 : static_cast<uint8_t>(140 + (x ^ y) % 7);
      }
    }
  }
  std::printf("%-26s %-10s %s\n", "encode", "size", "frames/s");
  for (const char* codec : {"libx264", "h264_nvenc"}) {
    const std::string path = (fs::temp_directory_path() / ("fetchscope_bench_" + std::to_string(getpid()) + ".mp4")).string();
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
      rows.push_back({{"codec", codec}, {"width", w}, {"height", h}, {"frames", n}, {"frames_per_s", n / s},
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

nlohmann::json BenchRecord(const AssetSource& assets, const std::string& backends, double budget_s, bool peers) {
  (void)budget_s;
  nlohmann::json result;
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  const fs::path dir = fs::temp_directory_path() / ("fetchscope_bench_record_" + std::to_string(getpid()));
  const int episodes = 4, frames = episodes * 51;
  nlohmann::json rows = nlohmann::json::array();
  std::printf("%-26s %-10s %s\n", "record (whole process)", "size", "ms/frame   peak RSS");
  for (const std::string& backend : Split(backends)) {
    for (const std::string msaa : {"", "0"}) {
      const std::string cmd = "'" + self + "' record --quiet --env-id FetchPush-v4 --policy scripted --episodes " +
                              std::to_string(episodes) + " --width 640 --height 480 --backend " + backend +
                              (msaa.empty() ? "" : " --msaa " + msaa) + " --assets '" +
                              (assets.kind == "bundled" ? std::string("bundled") : assets.root) + "' --out '" +
                              dir.string() + "'";
      const ChildRun run = RunChild(cmd);
      fs::remove_all(dir);
      const std::string label = "fetchscope " + backend + (msaa.empty() ? " msaa 4" : " msaa " + msaa);
      if (run.exit_code != 0) {
        rows.push_back({{"backend", backend}, {"skipped", "record failed (exit " + std::to_string(run.exit_code) + ")"}});
        continue;
      }
      std::printf("%-26s %4dx%-5d %7.2f   %.0f MiB\n", label.c_str(), 640, 480, 1000 * run.wall_s / frames,
                  run.peak_rss_mib);
      rows.push_back({{"backend", backend}, {"msaa", msaa.empty() ? 4 : std::stoi(msaa)}, {"episodes", episodes},
                      {"frames", frames}, {"wall_s", run.wall_s}, {"s_per_frame", run.wall_s / frames},
                      {"peak_rss_mib", run.peak_rss_mib}});
    }
  }
  result["fetchscope"] = rows;
  if (peers) {
    const std::string rgb = dir.string() + ".rgb", mp4 = dir.string() + ".mp4";
    nlohmann::json peer = PeerMujocoRecord(GenuineModel(assets, "push.xml"), frames, rgb);
    if (peer.contains("frames") && HaveProgram("ffmpeg")) {
      const ChildRun enc = RunChild("ffmpeg -y -f rawvideo -pix_fmt rgb24 -s 640x480 -r 25 -i '" + rgb +
                                    "' -vf vflip '" + mp4 + "'");
      const double total = peer["wall_s"].get<double>() + enc.wall_s;
      peer["ffmpeg_wall_s"] = enc.wall_s;
      peer["ffmpeg_peak_rss_mib"] = enc.peak_rss_mib;
      peer["s_per_frame"] = total / peer["frames"].get<double>();
      std::printf("%-26s %4dx%-5d %7.2f   %.0f MiB (record) + %.0f MiB (ffmpeg)\n", "mujoco-record + ffmpeg", 640, 480,
                  1000 * peer["s_per_frame"].get<double>(), peer["peak_rss_mib"].get<double>(), enc.peak_rss_mib);
    } else if (peer.contains("skipped")) {
      std::printf("mujoco-record + ffmpeg: %s\n", peer["skipped"].get<std::string>().c_str());
    }
    std::error_code ec;
    fs::remove(rgb, ec);
    fs::remove(mp4, ec);
    result["mujoco_record_plus_ffmpeg"] = peer;
  }
  return result;
}

}  // namespace fetchscope::cli
