// bench --what dataset: images into a dataset against record of the same camera and size.
#include <unistd.h>

#include <cstdio>
#include <filesystem>

#include "bench/bench.h"
#include "bench/children.h"

namespace fetchscope::bench {
namespace {

namespace fs = std::filesystem;

// One child's row: wall, CPU, steps (frames) per second and per CPU second, peak RSS.
nlohmann::json Row(const std::string& what, const ChildRun& run, long steps) {
  const double rate = run.wall_s > 0 ? steps / run.wall_s : 0;
  std::printf("  %-44s %7.2f s wall %7.2f s CPU %7.1f steps/s %6.2f ms CPU/step %6.0f MiB%s\n",
              what.c_str(), run.wall_s, run.cpu_s, rate, steps ? 1000 * run.cpu_s / steps : 0.0,
              run.peak_rss_mib, run.exit_code == 0 ? "" : "  (failed)");
  return {{"what", what},
          {"exit_code", run.exit_code},
          {"wall_s", run.wall_s},
          {"cpu_s", run.cpu_s},
          {"steps", steps},
          {"steps_per_s", rate},
          {"cpu_ms_per_step", steps ? 1000 * run.cpu_s / steps : 0.0},
          {"peak_rss_mib", run.peak_rss_mib}};
}

}  // namespace

nlohmann::json BenchDataset(const AssetSource& assets, const std::string& backends, int episodes,
                            int size) {
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  const fs::path dir =
      fs::temp_directory_path() / ("fetchscope-bench-dataset-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string backend = backends.substr(0, backends.find(','));
  const std::string n = std::to_string(episodes), px = std::to_string(size);
  const std::vector<std::string> common =
      Concat({"--env-id", "FetchPickAndPlace-v4", "--policy", "scripted", "--episodes", n,
              "--steps", "50", "--jobs", "1"},
             AssetsArg(assets));
  const long steps = 51L * episodes;  // frames: the reset and 50 steps per episode
  std::printf(
      "dataset: FetchPickAndPlace-v4, %d scripted episodes of 50 steps, external_camera_0 "
      "at %dx%d, %s, --jobs 1\n",
      episodes, size, size, backend.c_str());
  nlohmann::json rows = nlohmann::json::array();
  const ChildRun pixels = RunChild(Concat(
      Concat({self, "rollout"}, common),
      {"--minari", "bench/pixels-v0", "--minari-root", (dir / "ds").string(), "--overwrite",
       "--obs-camera", "external_camera_0", "--obs-size", px + "x" + px, "--backend", backend}));
  rows.push_back(Row("rollout --minari --obs-camera (rgb)", pixels, steps));
  std::error_code ec;
  const double bytes =
      static_cast<double>(fs::file_size(dir / "ds/bench/pixels-v0/data/main_data.hdf5", ec));
  const ChildRun record =
      RunChild(Concat(Concat({self, "record", "--quiet"}, common),
                      {"--camera", "external_camera_0", "--width", px, "--height", px, "--overlay",
                       "none", "--format", "webm", "--no-sheets", "--no-report", "--backend",
                       backend, "--out", (dir / "record").string()}));
  rows.push_back(Row("record, the same camera (webm, no sheets)", record, steps));
  const ChildRun state = RunChild(Concat(
      Concat({self, "rollout"}, common),
      {"--minari", "bench/state-v0", "--minari-root", (dir / "ds").string(), "--overwrite"}));
  rows.push_back(Row("rollout --minari (state only)", state, steps));
  fs::remove_all(dir, ec);
  const double ratio = record.wall_s > 0 && pixels.wall_s > 0 ? record.wall_s / pixels.wall_s : 0;
  std::printf(
      "  images into a dataset at %.2fx record's frames/s; %.1f MB of main_data.hdf5 "
      "(%.0f KB per image)\n",
      ratio, bytes / 1e6, steps ? bytes / 1e3 / steps : 0.0);
  return {{"episodes", episodes}, {"size", size},   {"backend", backend},
          {"rows", rows},         {"ratio", ratio}, {"hdf5_bytes", bytes}};
}

}  // namespace fetchscope::bench
