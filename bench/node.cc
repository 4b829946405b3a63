// bench --what node: what sizes a job on this machine (usable cores, render frames/s of one
// context with sync and async readback, record runs at several --jobs as processes and threads).
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

#include "base/cores.h"
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
using Clock = std::chrono::steady_clock;
namespace {

// One context's render rate at w x h: frames/s over the time spent rendering (Submit and
// Collect, the simulation excluded) and over the whole loop (simulation included).
nlohmann::json NodeRenderRow(GlContext& gl, const AssetSource& assets, int w, int h,
                             const std::string& msaa, const std::string& readback,
                             double budget_s) {
  const EnvSpec& spec = FindEnvSpec("FetchPush-v4");
  FetchEnv env(spec, assets);
  RenderOptions options;  // record's defaults: the default camera and overlays
  options.width = w;
  options.height = h;
  options.msaa_samples = msaa == "auto" ? kMsaaAuto : std::stoi(msaa);  // "auto" or "0"
  options.readback = readback == "async" ? Readback::kAsync : Readback::kSync;
  Renderer renderer(gl, env.model(), options);
  PolicyContext context;
  auto policy = MakePolicy(PolicySpec::Random(), spec, context);
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

// The node: its cores, GPUs and the encoder a run would choose, into `result`; printed.
void ProbeNodeInto(nlohmann::json* result) {
  const Cores machine_cores = UsableCores();
  const int cores = machine_cores.usable;
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
  (*result)["cores"] = cores;
  (*result)["cores_online"] = machine_cores.online;
  (*result)["cores_source"] = machine_cores.source;
  (*result)["gpus"] = gpus;
  (*result)["encoder"] = {{"codec", encoder}, {"reason", encoder_reason}};
  std::string gpu_list;
  for (const auto& g : gpus) gpu_list += (gpu_list.empty() ? "" : "; ") + g.get<std::string>();
  std::printf("node: %d usable cores (%s; %d online); EGL devices: %s; encoder: %s (%s)\n", cores,
              machine_cores.source.c_str(), machine_cores.online,
              gpu_list.empty() ? "none" : gpu_list.c_str(), encoder.c_str(),
              encoder_reason.c_str());
}

// One context, rendering only, synchronous against asynchronous readback.
nlohmann::json NodeRenderRows(const AssetSource& assets, const std::string& backend, int w, int h,
                              double budget_s) {
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
  return render_rows;
}

struct RecordCase {
  int jobs;  // 0: the fastest --jobs of the msaa auto runs before it
  std::string mode;
  std::string msaa;
};

// Whole record runs at --jobs 1, cores/4, cores/2 and cores, worker processes against threads;
// then msaa 0 at the --jobs that was fastest with msaa auto (not always the core count: workers
// each with an encoder thread beside the render thread can oversubscribe the cores).
std::vector<RecordCase> RecordCases(int cores) {
  std::vector<int> job_counts = {1};
  for (int j : {cores / 4, cores / 2, cores}) {
    if (j > job_counts.back()) job_counts.push_back(j);
  }
  std::vector<RecordCase> cases;
  for (int j : job_counts) {
    cases.push_back({j, "process", "auto"});
    if (j > 1) cases.push_back({j, "thread", "auto"});
  }
  cases.push_back({0, "process", "0"});
  return cases;
}

// One record run of case `c` (its jobs decided), as a row; printed.
nlohmann::json NodeRecordRow(const AssetSource& assets, const std::string& backend, int w, int h,
                             const RecordCase& c, const fs::path& dir, int* auto_msaa,
                             double* fastest_fps, int* fastest_jobs) {
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  const int episodes = std::max(8, 4 * c.jobs);
  const RecordRun run =
      RunRecordChild(self,
                     Concat(Concat({"--env-id", "FetchPush-v4", "--policy", "random", "--episodes",
                                    std::to_string(episodes), "--width", std::to_string(w),
                                    "--height", std::to_string(h)},
                                   AssetsArg(assets)),
                            {"--backend", backend, "--msaa", c.msaa, "--jobs",
                             std::to_string(c.jobs), "--worker-mode", c.mode}),
                     dir);
  const std::string label = "--jobs " + std::to_string(c.jobs) + " " +
                            (c.mode == "process" ? "processes" : "threads") + ", msaa " + c.msaa;
  if (run.child.exit_code != 0) {
    std::printf("%-44s skipped: record failed (exit %d)\n", label.c_str(), run.child.exit_code);
    return {{"jobs", c.jobs},
            {"worker_mode", c.mode},
            {"msaa_requested", c.msaa},
            {"skipped", "record failed (exit " + std::to_string(run.child.exit_code) + ")"}};
  }
  if (c.msaa == "auto" && *auto_msaa < 0) *auto_msaa = ManifestMsaa(run.manifest, "auto");
  const int frames = episodes * 51;
  if (c.msaa == "auto" && c.mode == "process" && frames / run.child.wall_s > *fastest_fps) {
    *fastest_fps = frames / run.child.wall_s;
    *fastest_jobs = c.jobs;
  }
  const ManifestVideo video = run.manifest ? run.manifest->video : ManifestVideo{};
  const std::string codec = video.codec.value_or("?");
  std::printf("%-44s %4dx%-4d %12.0f %9.2f %s\n", label.c_str(), w, h, frames / run.child.wall_s,
              run.child.wall_s, codec.c_str());
  return {{"jobs", c.jobs},
          {"worker_mode", c.mode},
          {"msaa_requested", c.msaa},
          {"msaa", ManifestMsaa(run.manifest, c.msaa)},
          {"episodes", episodes},
          {"frames", frames},
          {"wall_s", run.child.wall_s},
          {"frames_per_s", frames / run.child.wall_s},
          {"peak_rss_mib_largest_process", run.child.peak_rss_mib},
          {"video", ManifestVideoToJson(video)}};
}

}  // namespace

nlohmann::json BenchNode(const AssetSource& assets, const std::string& backends, double budget_s,
                         int width, int height) {
  nlohmann::json result;
  const int cores = UsableCores().usable;
  const std::string backend = Split(backends).empty() ? "egl" : Split(backends).front();
  result["width"] = width;
  result["height"] = height;
  ProbeNodeInto(&result);
  result["render"] = NodeRenderRows(assets, backend, width, height, budget_s);
  // whole record runs (sheets, trajectory JSON, manifest)
  const fs::path dir =
      fs::temp_directory_path() / ("fetchscope_bench_node_" + std::to_string(getpid()));
  nlohmann::json record_rows = nlohmann::json::array();
  int auto_msaa = -1;  // the samples msaa auto gave (from the first run's manifest)
  std::printf("%-44s %-9s %12s %9s %s\n", "record FetchPush random, 50 steps", "size", "frames/s",
              "wall s", "encoder");
  int fastest_jobs = cores;  // of the msaa auto process runs so far
  double fastest_fps = 0;
  for (RecordCase c : RecordCases(cores)) {
    if (c.msaa == "0" && auto_msaa == 0) continue;  // auto already rendered without multisampling
    if (c.jobs == 0) c.jobs = fastest_jobs;
    record_rows.push_back(NodeRecordRow(assets, backend, width, height, c, dir, &auto_msaa,
                                        &fastest_fps, &fastest_jobs));
  }
  result["record"] = record_rows;
  return result;
}

nlohmann::json NodeRecommendation(const nlohmann::json& record_rows) {
  const nlohmann::json* best = nullptr;
  for (const nlohmann::json& row : record_rows) {
    if (!row.contains("frames_per_s")) continue;  // a skipped run
    if (!best || row["frames_per_s"].get<double>() > (*best)["frames_per_s"].get<double>()) {
      best = &row;
    }
  }
  if (!best) return {{"none", "no record run finished, so there is nothing to recommend"}};
  const nlohmann::json& b = *best;
  std::string flags = "--jobs " + std::to_string(b["jobs"].get<int>()) + " --worker-mode " +
                      b["worker_mode"].get<std::string>();
  // msaa auto is the default; a row that asked for 0 was faster without multisampling
  if (b.value("msaa_requested", "auto") != "auto") {
    flags += " --msaa " + b["msaa_requested"].get<std::string>();
  }
  return {{"jobs", b["jobs"]},
          {"worker_mode", b["worker_mode"]},
          {"msaa_requested", b.value("msaa_requested", "auto")},
          {"frames_per_s", b["frames_per_s"]},
          {"flags", flags},
          {"why", "the record run with the most frames/s of those measured above"}};
}

}  // namespace fetchscope::bench
