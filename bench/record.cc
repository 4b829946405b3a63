// bench --what record and soak: whole record runs of this binary as child processes beside
// mujoco-record + the ffmpeg program, and one long run with its memory sampled.
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
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
#include "src/policy_spec.h"
#include "src/versions.h"

namespace fetchscope::bench {

using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

namespace {

// The CPU account of a recorded frame at record's defaults (FetchPush-v4, random, 480x480, HUD,
// mp4 + sheet + JSON, --jobs 1) from the manifest's timings_s.cpu_ms_per_frame: thread CPU
// clocks, so steady on a busy machine. llvmpipe rasterises on the render thread here
// (LP_NUM_THREADS=0), so that its gl stage holds all of GL and "outside_gl" is what a node with
// a GPU pays on its cores.
nlohmann::json StageAccount(const std::string& self, const AssetSource& assets,
                            const std::string& backend, const fs::path& dir) {
  const int episodes = 8, frames = episodes * 51;
  const char* before = std::getenv("LP_NUM_THREADS");
  const std::string kept = before ? before : "";
  setenv("LP_NUM_THREADS", "0", 1);
  const RecordRun run =
      RunRecordChild(self,
                     Concat({"--env-id", "FetchPush-v4", "--policy", "random", "--episodes",
                             std::to_string(episodes), "--backend", backend, "--jobs", "1"},
                            AssetsArg(assets)),
                     dir);
  if (before) {
    setenv("LP_NUM_THREADS", kept.c_str(), 1);
  } else {
    unsetenv("LP_NUM_THREADS");
  }
  if (run.child.exit_code != 0 || !run.manifest || !run.manifest->timings_s.cpu_ms_per_frame) {
    const std::string why = run.child.exit_code != 0
                                ? "record failed (exit " + std::to_string(run.child.exit_code) + ")"
                                : "the manifest has no timings_s.cpu_ms_per_frame";
    std::printf("record CPU per frame: skipped: %s\n", why.c_str());
    return {{"skipped", why}};
  }
  const std::map<std::string, double>& ms = *run.manifest->timings_s.cpu_ms_per_frame;
  const auto at = [&ms](const char* stage) {
    const auto it = ms.find(stage);
    return it == ms.end() ? 0.0 : it->second;
  };
  std::printf("record CPU per frame (FetchPush-v4 random 480x480, --jobs 1, %s, thread CPU):\n",
              backend.c_str());
  for (const char* stage : {"sim", "scene", "gl", "hud", "copy", "render_other", "convert",
                            "encode", "sheet", "trajectory", "encode_other"}) {
    std::printf("  %-14s %6.3f ms\n", stage, at(stage));
  }
  std::printf(
      "  %-14s %6.3f ms   (every stage but gl: a GPU node's cores pay this and the GL "
      "driver's own CPU)\n",
      "outside GL", at("outside_gl"));
  std::printf("  %-14s %6.3f ms   (the whole process, start-up included)\n", "process",
              at("process"));
  return {{"episodes", episodes},       {"frames", frames},    {"backend", backend},
          {"wall_s", run.child.wall_s}, {"lp_num_threads", 0}, {"cpu_ms_per_frame", ms}};
}

// Whole-process record rows, per backend: the default (auto) msaa beside Gymnasium's 4, and 0
// where auto did not already pick it. `first_backend` gets the first backend that recorded.
nlohmann::json BackendRows(const std::string& self, const std::vector<std::string>& common,
                           const std::string& backends, int episodes, int frames,
                           const fs::path& dir, std::string* first_backend) {
  nlohmann::json rows = nlohmann::json::array();
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
      if (first_backend->empty()) *first_backend = backend;
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
  return rows;
}

// --jobs 1 against --jobs 2: the same episodes, whole process, the default msaa
nlohmann::json JobsRows(const std::string& self, const AssetSource& assets,
                        const std::string& first_backend, const fs::path& dir) {
  nlohmann::json jobs_rows = nlohmann::json::array();
  if (first_backend.empty()) return {{"skipped", "no backend recorded"}};
  if (!RecordHasJobs(self)) {
    std::printf("record --jobs: skipped (this build's record has no --jobs)\n");
    return {{"skipped", "this build's record has no --jobs"}};
  }
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
  return jobs_rows;
}

// The peer: MuJoCo's own recorder writing raw frames, then ffmpeg encoding them.
nlohmann::json PeerRecordRow(const AssetSource& assets, int frames, const fs::path& dir) {
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
  return peer;
}

// Samples the child's resident set every `interval_s` until it exits (sampled directly: it is
// not a shell); `usage` and `status` get how it ended.
nlohmann::json SampleRss(ChildProcess& child, Clock::time_point start, double interval_s,
                         rusage* usage, std::optional<ChildExit>* status) {
  nlohmann::json samples = nlohmann::json::array();
  double next = 0;
  while (!(*status = child.TryWait(usage))) {
    const double t = Since(start);
    if (t >= next) {
      const double rss = ReadRssMiB(child.pid());
      if (rss >= 0) samples.push_back({{"t_s", t}, {"rss_mib", rss}});
      next += interval_s;
    }
    usleep(20000);
  }
  return samples;
}

// The samples as a table of about 20 rows.
void PrintRssTable(const nlohmann::json& samples) {
  std::printf("%-10s %s\n", "t (s)", "RSS (MiB)");
  const size_t step = std::max<size_t>(1, samples.size() / 20);  // about 20 table rows
  for (size_t i = 0; i < samples.size(); i += step) {
    std::printf("%-10.1f %.1f\n", samples[i]["t_s"].get<double>(),
                samples[i]["rss_mib"].get<double>());
  }
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
  const std::vector<std::string> backend_list = Split(backends);
  result["stages"] =
      StageAccount(self, assets, backend_list.empty() ? "auto" : backend_list.front(), dir);
  std::string first_backend;
  std::printf("%-30s %-10s %s\n", "record (whole process)", "size", "ms/frame   peak RSS");
  result["fetchscope"] = BackendRows(self, common, backends, episodes, frames, dir, &first_backend);
  result["jobs"] = JobsRows(self, assets, first_backend, dir);
  if (peers) result["mujoco_record_plus_ffmpeg"] = PeerRecordRow(assets, frames, dir);
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
  rusage usage{};
  std::optional<ChildExit> status;
  const nlohmann::json samples = SampleRss(child, start, interval_s, &usage, &status);
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
  PrintRssTable(samples);
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

}  // namespace fetchscope::bench
