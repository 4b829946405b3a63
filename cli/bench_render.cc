// bench's rendering, encoding and recording parts, with the peers measured in the same run:
// MuJoCo's own record sample (Debian's mujoco-record under xvfb-run) and the ffmpeg program.
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
#include "base/process.h"
#include "cli/bench.h"
#include "cli/common.h"
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

namespace fetchscope::cli {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

struct ChildRun {
  int exit_code = -1;
  double wall_s = 0;
  double peak_rss_mib = 0;
};

// Output discarded: the child's stdout and stderr go to /dev/null.
SpawnOptions Quiet() {
  SpawnOptions options;
  options.out = Stdio::kNull;
  options.err = Stdio::kNull;
  return options;
}

// Runs `argv` (no shell) with its output discarded; wall time and the child's peak RSS.
ChildRun RunChild(const std::vector<std::string>& argv) {
  ChildRun run;
  const auto start = Clock::now();
  ChildProcess child = ChildProcess::Spawn(argv, Quiet());
  rusage usage{};
  const ChildExit status = child.Wait(&usage);
  run.wall_s = Since(start);
  run.exit_code = status.ShellCode();
  run.peak_rss_mib = usage.ru_maxrss / 1024.0;
  return run;
}

// `a` followed by `b`.
std::vector<std::string> Concat(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

// The whole of a text file; "" when it cannot be read.
std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return in ? ss.str() : std::string();
}

// The manifest of the run in `dir`; nullopt when it wrote none (or not one this build reads).
std::optional<Manifest> ReadManifestIn(const fs::path& dir) {
  try {
    return ReadManifest(dir / kManifestFileName);
  } catch (const ManifestError&) {
    return std::nullopt;
  }
}

// "msaa auto (0)", "msaa 4": the table label for a requested and a resolved sample count.
std::string MsaaLabel(const std::string& requested, int samples) {
  return requested == "auto" ? "msaa auto (" + std::to_string(samples) + ")" : "msaa " + requested;
}

bool HaveProgram(const std::string& name) { return !FindProgram(name).empty(); }

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
  for (const char* candidate :
       std::vector<const char*>{std::getenv("FETCHSCOPE_ASSETS"), FETCHSCOPE_GENUINE_ASSETS}) {
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
  const ChildRun run = RunChild({"xvfb-run", "-a", "-s", "-screen 0 1024x768x24", "mujoco-record",
                                 model, std::to_string(duration), "25", rgb_out});
  std::error_code ec;
  const auto bytes = fs::file_size(rgb_out, ec);
  const long got = ec ? 0 : static_cast<long>(bytes / (640 * 480 * 3));
  // the sample returns 1 even when it succeeded: judge by the frames it wrote
  if (got == 0)
    return {{"skipped", "mujoco-record failed (exit " + std::to_string(run.exit_code) + ")"}};
  return {{"program", "xvfb-run mujoco-record"},
          {"model", model},
          {"frames", got},
          {"wall_s", run.wall_s},
          {"frames_per_s", got / run.wall_s},
          {"peak_rss_mib", run.peak_rss_mib}};
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
        FetchEnv env(spec, assets);
        ViewOptions view;
        view.width = w;
        view.height = h;
        view.msaa = msaa;
        const RenderOptions options = MakeRenderOptions(view, env.model());
        Renderer renderer(*gl, env.model(), options);
        if (msaa == "auto" && renderer.msaa_samples() != 0 && msaa_values.size() == 2)
          msaa_values.push_back("0");
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
          RunEpisode(env, *policy, episode, episode, 50,
                     [&](const StepRecord& r, const StepResult*) {
                       const auto t0 = Clock::now();
                       renderer.Render(env.data(), MakeFrameInfo(env, r), rgb.data());
                       busy += Since(t0);
                       ++frames;
                       return busy < budget_s / 3;
                     });
          ++episode;
        }
        const int samples = renderer.msaa_samples();
        std::printf("%-26s %4dx%-5d %.1f\n",
                    (gl->info().backend + " " + MsaaLabel(msaa, samples)).c_str(), w, h,
                    frames / busy);
        rows.push_back({{"backend", gl->info().backend},
                        {"gl_renderer", gl->info().renderer},
                        {"msaa_requested", msaa},
                        {"msaa", samples},
                        {"msaa_reason", renderer.msaa_reason()},
                        {"width", w},
                        {"height", h},
                        {"frames", frames},
                        {"frames_per_s", frames / busy}});
      }
  }
  result["fetchscope"] = rows;
  if (peers) {
    const std::string rgb =
        (fs::temp_directory_path() / ("fetchscope_bench_" + std::to_string(getpid()) + ".rgb"))
            .string();
    result["mujoco_record"] =
        PeerMujocoRecord(GenuineModel(assets, "pick_and_place.xml"), 250, rgb);
    fs::remove(rgb);
    if (result["mujoco_record"].contains("frames_per_s")) {
      std::printf("%-26s %4dx%-5d %.1f  (physics included, process start included)\n",
                  "mujoco-record (xvfb)", 640, 480,
                  result["mujoco_record"]["frames_per_s"].get<double>());
    } else {
      std::printf("mujoco-record: %s\n",
                  result["mujoco_record"]["skipped"].get<std::string>().c_str());
    }
  }
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

namespace {

// One `fetchscope record` child: its process figures and the manifest it wrote.
struct RecordRun {
  ChildRun child;
  std::optional<Manifest> manifest;  // nullopt when the run wrote none
};

// Runs this binary's `record` with `args` into `dir` (removed afterwards).
RecordRun RunRecordChild(const std::string& self, const std::vector<std::string>& args,
                         const fs::path& dir) {
  RecordRun run;
  run.child = RunChild(Concat(Concat({self, "record", "--quiet"}, args), {"--out", dir.string()}));
  run.manifest = ReadManifestIn(dir);
  std::error_code ec;
  fs::remove_all(dir, ec);
  return run;
}

// The samples a record run used: its manifest's "msaa"; without a manifest the samples asked
// for, or -1 (unknown) for auto.
int ManifestMsaa(const std::optional<Manifest>& manifest, const std::string& requested) {
  if (manifest) return manifest->msaa;
  if (requested != "auto") return std::stoi(requested);
  return -1;
}

std::vector<std::string> AssetsArg(const AssetSource& assets) {
  return {"--assets", assets.kind == "bundled" ? std::string("bundled") : assets.root};
}

// True when this binary's record takes --jobs (its help names it).
bool RecordHasJobs(const std::string& self) {
  SpawnOptions options = Quiet();
  options.out = Stdio::kPipe;
  ChildProcess child = ChildProcess::Spawn({self, "record", "--help"}, options);
  child.channel().CloseOutput();
  std::string help;
  while (child.channel().ReadSome()) {
    while (std::optional<std::string> line = child.channel().TakeLine()) help += *line + "\n";
  }
  child.Wait();
  return help.find("--jobs") != std::string::npos;
}

// Resident set size (VmRSS) of process `pid` in MiB, or -1 once it has gone.
double ReadRssMiB(pid_t pid) {
  const std::string status = ReadText("/proc/" + std::to_string(pid) + "/status");
  const size_t at = status.find("VmRSS:");
  if (at == std::string::npos) return -1;  // a zombie has no memory lines
  return std::strtod(status.c_str() + at + 6, nullptr) / 1024.0;
}

}  // namespace

nlohmann::json BenchRecord(const AssetSource& assets, const std::string& backends, double budget_s,
                           bool peers) {
  (void)budget_s;
  nlohmann::json result;
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  const fs::path dir =
      fs::temp_directory_path() / ("fetchscope_bench_record_" + std::to_string(getpid()));
  const int episodes = 4, frames = episodes * 51;
  const std::vector<std::string> common =
      Concat({"--env-id", "FetchPush-v4", "--policy", "scripted", "--episodes",
              std::to_string(episodes), "--width", "640", "--height", "480"},
             AssetsArg(assets));
  nlohmann::json rows = nlohmann::json::array();
  std::string first_backend;
  std::printf("%-30s %-10s %s\n", "record (whole process)", "size", "ms/frame   peak RSS");
  for (const std::string& backend : Split(backends)) {
    // the default (auto) beside Gymnasium's 4; 0 too where auto did not already pick it
    std::vector<std::string> msaa_values = {"auto", "4"};
    for (size_t m = 0; m < msaa_values.size(); ++m) {
      const std::string msaa = msaa_values[m];  // a copy: the list may grow below
      const RecordRun run =
          RunRecordChild(self, Concat(common, {"--backend", backend, "--msaa", msaa}), dir);
      if (run.child.exit_code != 0) {
        rows.push_back(
            {{"backend", backend},
             {"msaa_requested", msaa},
             {"skipped", "record failed (exit " + std::to_string(run.child.exit_code) + ")"}});
        std::printf("%-30s skipped: record failed (exit %d)\n", ("fetchscope " + backend).c_str(),
                    run.child.exit_code);
        break;
      }
      if (first_backend.empty()) first_backend = backend;
      const int samples = ManifestMsaa(run.manifest, msaa);
      if (msaa == "auto" && samples != 0 && msaa_values.size() == 2) msaa_values.push_back("0");
      const std::string label = "fetchscope " + backend + " " + MsaaLabel(msaa, samples);
      std::printf("%-30s %4dx%-5d %7.2f   %.0f MiB\n", label.c_str(), 640, 480,
                  1000 * run.child.wall_s / frames, run.child.peak_rss_mib);
      nlohmann::json row = {{"backend", backend},
                            {"msaa_requested", msaa},
                            {"msaa", samples},
                            {"episodes", episodes},
                            {"frames", frames},
                            {"wall_s", run.child.wall_s},
                            {"s_per_frame", run.child.wall_s / frames},
                            {"peak_rss_mib", run.child.peak_rss_mib}};
      if (run.manifest) row["msaa_reason"] = run.manifest->msaa_reason;
      rows.push_back(row);
    }
  }
  result["fetchscope"] = rows;

  // --jobs 1 against --jobs 2: the same episodes, whole process, the default msaa
  nlohmann::json jobs_rows = nlohmann::json::array();
  if (first_backend.empty()) {
    result["jobs"] = {{"skipped", "no backend recorded"}};
  } else if (!RecordHasJobs(self)) {
    result["jobs"] = {{"skipped", "this build's record has no --jobs"}};
    std::printf("record --jobs: skipped (this build's record has no --jobs)\n");
  } else {
    const int job_episodes = 8;
    double base = 0;
    for (int jobs : {1, 2}) {
      const RecordRun run = RunRecordChild(
          self,
          Concat(Concat({"--env-id", "FetchPush-v4", "--policy", "scripted", "--episodes",
                         std::to_string(job_episodes), "--width", "640", "--height", "480"},
                        AssetsArg(assets)),
                 {"--backend", first_backend, "--jobs", std::to_string(jobs)}),
          dir);
      if (run.child.exit_code != 0) {
        jobs_rows.push_back(
            {{"jobs", jobs},
             {"skipped", "record failed (exit " + std::to_string(run.child.exit_code) + ")"}});
        continue;
      }
      const double eps = job_episodes / run.child.wall_s;
      if (jobs == 1) base = eps;
      const std::string label = "fetchscope " + first_backend + " --jobs " + std::to_string(jobs);
      std::printf("%-30s %4dx%-5d %7.2f episodes/s (x%.2f)   %.0f MiB\n", label.c_str(), 640, 480,
                  eps, base > 0 ? eps / base : 0.0, run.child.peak_rss_mib);
      jobs_rows.push_back(
          {{"backend", first_backend},
           {"jobs", jobs},
           {"episodes", job_episodes},
           {"frames", job_episodes * 51},
           {"wall_s", run.child.wall_s},
           {"episodes_per_s", eps},
           {"speedup_vs_jobs_1", base > 0 ? nlohmann::json(eps / base) : nlohmann::json(nullptr)},
           {"msaa", ManifestMsaa(run.manifest, "auto")},
           {"peak_rss_mib", run.child.peak_rss_mib}});
    }
    result["jobs"] = jobs_rows;
  }

  if (peers) {
    const std::string rgb = dir.string() + ".rgb", mp4 = dir.string() + ".mp4";
    nlohmann::json peer = PeerMujocoRecord(GenuineModel(assets, "push.xml"), frames, rgb);
    if (peer.contains("frames") && HaveProgram("ffmpeg")) {
      const ChildRun enc = RunChild({"ffmpeg", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s",
                                     "640x480", "-r", "25", "-i", rgb, "-vf", "vflip", mp4});
      const double total = peer["wall_s"].get<double>() + enc.wall_s;
      peer["ffmpeg_wall_s"] = enc.wall_s;
      peer["ffmpeg_peak_rss_mib"] = enc.peak_rss_mib;
      peer["s_per_frame"] = total / peer["frames"].get<double>();
      std::printf("%-26s %4dx%-5d %7.2f   %.0f MiB (record) + %.0f MiB (ffmpeg)\n",
                  "mujoco-record + ffmpeg", 640, 480, 1000 * peer["s_per_frame"].get<double>(),
                  peer["peak_rss_mib"].get<double>(), enc.peak_rss_mib);
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

nlohmann::json BenchSoak(const AssetSource& assets, const std::string& backends, int target_frames,
                         double interval_s) {
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  const fs::path dir =
      fs::temp_directory_path() / ("fetchscope_bench_soak_" + std::to_string(getpid()));
  const std::vector<std::string> backend_list = Split(backends);
  const std::string backend = backend_list.empty() ? "auto" : backend_list.front();
  const int episodes = std::max(1, (target_frames + 50) / 51);  // 51 frames each, reset included
  const std::string assets_dir = assets.kind == "bundled" ? std::string("bundled") : assets.root;
  const std::vector<std::string> args = {self,        "record",       "--quiet",
                                         "--env-id",  "FetchPush-v4", "--policy",
                                         "scripted",  "--episodes",   std::to_string(episodes),
                                         "--width",   "640",          "--height",
                                         "480",       "--backend",    backend,
                                         "--assets",  assets_dir,     "--out",
                                         dir.string()};
  std::printf("soak: record of %d episodes (%d frames) at 640x480 on %s, RSS every %.1f s\n",
              episodes, episodes * 51, backend.c_str(), interval_s);
  const auto start = Clock::now();
  ChildProcess child;
  try {
    child = ChildProcess::Spawn(args, Quiet());
  } catch (const RunError& e) {
    throw RunError(std::string("bench soak: cannot start record: ") + e.what());
  }
  // sample the child's resident set until it exits (sampled directly: it is not a shell)
  nlohmann::json samples = nlohmann::json::array();
  rusage usage{};
  double next = 0;
  std::optional<ChildExit> status;
  while (!(status = child.TryWait(&usage))) {
    const double t = Since(start);
    if (t >= next) {
      const double rss = ReadRssMiB(child.pid());
      if (rss >= 0) samples.push_back({{"t_s", t}, {"rss_mib", rss}});
      next += interval_s;
    }
    usleep(20000);
  }
  const double wall = Since(start);
  const int exit_code = status->ShellCode();
  const std::optional<Manifest> manifest = ReadManifestIn(dir);
  std::error_code ec;
  fs::remove_all(dir, ec);
  if (exit_code != 0) {
    std::printf("soak: record failed (exit %d)\n", exit_code);
    return {{"skipped", "record failed (exit " + std::to_string(exit_code) + ")"},
            {"backend", backend}};
  }
  const long frames = manifest ? manifest->frames : 0L;
  // flatness: the resident set once the first episodes have warmed up (after a tenth of the
  // run) against its largest later value and the last sample
  double settled = -1, later_max = 0, last = 0;
  for (const auto& s : samples) {
    const double t = s["t_s"].get<double>(), rss = s["rss_mib"].get<double>();
    if (t >= wall / 10 && settled < 0) settled = rss;
    if (settled >= 0) later_max = std::max(later_max, rss);
    last = rss;
  }
  const double peak = usage.ru_maxrss / 1024.0;
  std::printf("%-10s %s\n", "t (s)", "RSS (MiB)");
  const size_t step = std::max<size_t>(1, samples.size() / 20);  // about 20 table rows
  for (size_t i = 0; i < samples.size(); i += step) {
    std::printf("%-10.1f %.1f\n", samples[i]["t_s"].get<double>(),
                samples[i]["rss_mib"].get<double>());
  }
  std::printf(
      "soak: %ld frames in %.1f s; RSS %.1f MiB after a tenth of the run, at most %.1f later, %.1f "
      "at the "
      "end (growth %+.1f MiB); peak RSS %.1f MiB\n",
      frames, wall, settled, later_max, last, later_max - settled, peak);
  return {{"backend", backend},
          {"width", 640},
          {"height", 480},
          {"episodes", episodes},
          {"frames", frames},
          {"msaa", ManifestMsaa(manifest, "auto")},
          {"wall_s", wall},
          {"interval_s", interval_s},
          {"rss_settled_mib", settled},
          {"rss_max_after_settled_mib", later_max},
          {"rss_last_mib", last},
          {"rss_growth_mib", later_max - settled},
          {"peak_rss_mib", peak},
          {"samples", samples}};
}

namespace {

// One context's render rate at w x h: frames/s over the time spent rendering (Submit and
// Collect, the simulation excluded) and over the whole loop (simulation included).
nlohmann::json NodeRenderRow(GlContext& gl, const AssetSource& assets, int w, int h,
                             const std::string& msaa, const std::string& readback,
                             double budget_s) {
  const EnvSpec& spec = FindEnvSpec("FetchPush-v4");
  FetchEnv env(spec, assets);
  ViewOptions view;
  view.width = w;
  view.height = h;
  view.msaa = msaa;
  view.readback = readback;
  Renderer renderer(gl, env.model(), MakeRenderOptions(view, env.model()));
  PolicyContext context;
  auto policy = MakePolicy("random", spec, context);
  std::vector<std::vector<uint8_t>> frames(kReadbackDepth,
                                           std::vector<uint8_t>(static_cast<size_t>(w) * h * 3));
  long submitted = 0, frames_done = 0;
  double busy = 0;
  auto on_step = [&](const StepRecord& r, const StepResult*) {
    const auto t0 = Clock::now();
    renderer.Submit(env.data(), MakeFrameInfo(env, r), frames[submitted++ % frames.size()].data());
    while (renderer.pending() >= renderer.pipeline_depth()) {
      renderer.Collect();
      ++frames_done;
    }
    busy += Since(t0);
    return true;
  };
  RunEpisode(env, *policy, 0, 0, 10, on_step);  // warm-up: shaders, first-touch allocations
  busy = 0;
  frames_done = 0;
  const auto start = Clock::now();
  for (int episode = 1; Since(start) < budget_s; ++episode)
    RunEpisode(env, *policy, episode, episode, 50, on_step);
  const auto drain = Clock::now();
  while (renderer.Collect()) ++frames_done;
  busy += Since(drain);
  const double wall = Since(start);
  return {{"width", w},
          {"height", h},
          {"msaa_requested", msaa},
          {"msaa", renderer.msaa_samples()},
          {"readback", renderer.readback_reason()},
          {"frames", frames_done},
          {"render_frames_per_s", frames_done / busy},
          {"loop_frames_per_s", frames_done / wall}};
}

}  // namespace

nlohmann::json BenchNode(const AssetSource& assets, const std::string& backends, double budget_s,
                         int width, int height) {
  nlohmann::json result;
  const Cores machine_cores = UsableCores();
  const int cores = machine_cores.usable;
  const std::string backend = Split(backends).empty() ? "egl" : Split(backends).front();
  const int w = width, h = height;

  // the node: GPUs and the encoder a run would choose
  nlohmann::json gpus = nlohmann::json::array();
  try {
    for (const EglDevice& d : ListEglDevices().devices) gpus.push_back(d.Describe());
  } catch (const std::exception& e) {
    gpus.push_back(std::string("EGL unavailable: ") + e.what());
  }
  std::string encoder = "?", encoder_reason;
  try {
    const VideoCodecDecision d = DecideVideoCodec(VideoOptions{});
    encoder = d.codec;
    encoder_reason = d.reason;
  } catch (const std::exception& e) {
    encoder_reason = e.what();
  }
  result["width"] = w;
  result["height"] = h;
  result["cores"] = cores;
  result["cores_online"] = machine_cores.online;
  result["cores_source"] = machine_cores.source;
  result["gpus"] = gpus;
  result["encoder"] = {{"codec", encoder}, {"reason", encoder_reason}};
  std::string gpu_list;
  for (const auto& g : gpus) gpu_list += (gpu_list.empty() ? "" : "; ") + g.get<std::string>();
  std::printf("node: %d usable cores (%s; %d online); EGL devices: %s; encoder: %s (%s)\n", cores,
              machine_cores.source.c_str(), machine_cores.online,
              gpu_list.empty() ? "none" : gpu_list.c_str(), encoder.c_str(),
              encoder_reason.c_str());

  // one context, rendering only, synchronous against asynchronous readback
  nlohmann::json render_rows = nlohmann::json::array();
  std::printf("%-44s %-9s %12s %12s\n", "render, one context (FetchPush, random)", "size",
              "render fps", "+sim fps");
  try {
    std::unique_ptr<GlContext> gl = CreateGlContext(backend, -1);
    bool auto_is_zero = false;
    for (const char* msaa : {"auto", "0"}) {
      if (auto_is_zero) break;  // msaa 0 is what auto already measured
      for (const char* readback : {"sync", "async"}) {
        nlohmann::json row = NodeRenderRow(*gl, assets, w, h, msaa, readback, budget_s / 4);
        auto_is_zero = std::string(msaa) == "auto" && row["msaa"].get<int>() == 0;
        const std::string label =
            gl->info().backend + " " + MsaaLabel(msaa, row["msaa"].get<int>()) + " " + readback;
        std::printf("%-44s %4dx%-4d %12.0f %12.0f\n", label.c_str(), w, h,
                    row["render_frames_per_s"].get<double>(),
                    row["loop_frames_per_s"].get<double>());
        row["backend"] = gl->info().backend;
        row["gl_renderer"] = gl->info().renderer;
        render_rows.push_back(row);
      }
    }
  } catch (const std::exception& e) {
    render_rows.push_back({{"skipped", e.what()}});
    std::printf("render: skipped: %s\n", e.what());
  }
  result["render"] = render_rows;

  // whole record runs (sheets, trajectory JSON, manifest) at --jobs 1, cores/2 and cores,
  // worker processes against threads
  std::vector<int> job_counts = {1};
  for (int j : {cores / 2, cores}) {
    if (j > job_counts.back()) job_counts.push_back(j);
  }
  struct Case {
    int jobs;
    std::string mode;
    std::string msaa;
  };
  std::vector<Case> cases;
  for (int j : job_counts) {
    cases.push_back({j, "process", "auto"});
    if (j > 1) cases.push_back({j, "thread", "auto"});
  }
  cases.push_back({cores, "process", "0"});
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  const fs::path dir =
      fs::temp_directory_path() / ("fetchscope_bench_node_" + std::to_string(getpid()));
  nlohmann::json record_rows = nlohmann::json::array();
  int auto_msaa = -1;  // the samples msaa auto gave (from the first run's manifest)
  std::printf("%-44s %-9s %12s %9s %s\n", "record FetchPush random, 50 steps", "size", "frames/s",
              "wall s", "encoder");
  for (const Case& c : cases) {
    if (c.msaa == "0" && auto_msaa == 0) continue;  // auto already rendered without multisampling
    const int episodes = std::max(8, 4 * c.jobs);
    const RecordRun run =
        RunRecordChild(self,
                       Concat(Concat({"--env-id", "FetchPush-v4", "--policy", "random",
                                      "--episodes", std::to_string(episodes), "--width",
                                      std::to_string(w), "--height", std::to_string(h)},
                                     AssetsArg(assets)),
                              {"--backend", backend, "--msaa", c.msaa, "--jobs",
                               std::to_string(c.jobs), "--worker-mode", c.mode}),
                       dir);
    const std::string label = "--jobs " + std::to_string(c.jobs) + " " +
                              (c.mode == "process" ? "processes" : "threads") + ", msaa " + c.msaa;
    if (run.child.exit_code != 0) {
      record_rows.push_back(
          {{"jobs", c.jobs},
           {"worker_mode", c.mode},
           {"msaa_requested", c.msaa},
           {"skipped", "record failed (exit " + std::to_string(run.child.exit_code) + ")"}});
      std::printf("%-44s skipped: record failed (exit %d)\n", label.c_str(), run.child.exit_code);
      continue;
    }
    if (c.msaa == "auto" && auto_msaa < 0) auto_msaa = ManifestMsaa(run.manifest, "auto");
    const int frames = episodes * 51;
    const nlohmann::json video = run.manifest ? run.manifest->video : nlohmann::json::object();
    const std::string codec = video.value("codec", "?");
    std::printf("%-44s %4dx%-4d %12.0f %9.2f %s\n", label.c_str(), w, h, frames / run.child.wall_s,
                run.child.wall_s, codec.c_str());
    record_rows.push_back({{"jobs", c.jobs},
                           {"worker_mode", c.mode},
                           {"msaa_requested", c.msaa},
                           {"msaa", ManifestMsaa(run.manifest, c.msaa)},
                           {"episodes", episodes},
                           {"frames", frames},
                           {"wall_s", run.child.wall_s},
                           {"frames_per_s", frames / run.child.wall_s},
                           {"peak_rss_mib_largest_process", run.child.peak_rss_mib},
                           {"video", video}});
  }
  result["record"] = record_rows;
  return result;
}

}  // namespace fetchscope::cli
