// bench --what exec-images: camera images to a Python exec: policy beside the same images going
// into a dataset, and where a step's time goes (the Python loop, the images on the pipe, numpy).
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "bench/bench.h"
#include "bench/children.h"

namespace fetchscope::bench {
namespace {

namespace fs = std::filesystem;

// The child: reads each line and its images (as bytes, or as numpy arrays it touches), answers
// zeros. MODE is lines, bytes or numpy.
constexpr const char* kReader = R"(import json, sys
mode = sys.argv[1]
if mode == "numpy":
    import numpy as np
stdin, total = sys.stdin.buffer, 0.0
while True:
    line = stdin.readline()
    if not line:
        break
    for image in json.loads(line).get("images", []):
        data = stdin.read(image["bytes"])
        if mode == "numpy":
            total += float(np.frombuffer(data, image["dtype"]).reshape(image["shape"]).mean())
    sys.stdout.write("0 0 0 0\n")
    sys.stdout.flush()
)";

nlohmann::json Row(const std::string& what, const ChildRun& run, long steps) {
  const double rate = run.wall_s > 0 ? steps / run.wall_s : 0;
  const double cpu_ms = steps ? 1000 * run.cpu_s / steps : 0.0;
  std::printf("  %-46s %7.2f s wall %7.2f s CPU %7.1f steps/s %6.2f ms CPU/step%s\n", what.c_str(),
              run.wall_s, run.cpu_s, rate, cpu_ms, run.exit_code == 0 ? "" : "  (failed)");
  return {{"what", what},       {"exit_code", run.exit_code}, {"wall_s", run.wall_s},
          {"cpu_s", run.cpu_s}, {"steps_per_s", rate},        {"cpu_ms_per_step", cpu_ms}};
}

}  // namespace

nlohmann::json BenchExecImages(const AssetSource& assets, const std::string& backends, int episodes,
                               const std::string& size, const std::string& python) {
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  const fs::path dir =
      fs::temp_directory_path() / ("fetchscope-bench-exec-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const fs::path reader = dir / "reader.py";
  std::ofstream(reader) << kReader;
  const std::string backend = backends.substr(0, backends.find(','));
  const long steps = 50L * episodes;  // the policy's answers
  const std::vector<std::string> common =
      Concat({self, "rollout", "--env-id", "FetchReach-v4", "--episodes", std::to_string(episodes),
              "--steps", "50", "--jobs", "1", "--backend", backend},
             AssetsArg(assets));
  const std::vector<std::string> images = {"--obs-camera", "external_camera_0", "--obs-size", size};
  auto exec = [&](const std::string& mode) {
    return std::vector<std::string>{"--policy",
                                    "exec:" + python + " '" + reader.string() + "' " + mode};
  };
  std::printf(
      "exec-images: FetchReach-v4, %d episodes of 50 steps, external_camera_0 rgb at %s, %s, "
      "--jobs 1, policy children run by %s\n",
      episodes, size.c_str(), backend.c_str(), python.c_str());
  nlohmann::json rows = nlohmann::json::array();
  const ChildRun plain = RunChild(Concat(common, {"--policy", "zero"}));
  rows.push_back(Row("rollout --policy zero, no images", plain, steps));
  const ChildRun dataset = RunChild(
      Concat(Concat(common, images), {"--policy", "zero", "--minari", "bench/exec-v0",
                                      "--minari-root", (dir / "ds").string(), "--overwrite"}));
  rows.push_back(Row("rollout --minari --obs-camera (the dataset)", dataset, steps));
  const ChildRun lines = RunChild(Concat(common, exec("lines")));
  rows.push_back(Row("exec: python, lines only", lines, steps));
  const ChildRun bytes = RunChild(Concat(Concat(common, images), exec("bytes")));
  rows.push_back(Row("exec: python --obs-camera, images read", bytes, steps));
  const ChildRun arrays = RunChild(Concat(Concat(common, images), exec("numpy")));
  rows.push_back(Row("exec: python --obs-camera, numpy arrays", arrays, steps));
  std::error_code ec;
  fs::remove_all(dir, ec);
  const double ratio = arrays.wall_s > 0 ? dataset.wall_s / arrays.wall_s : 0;
  auto per_step = [&](const ChildRun& a, const ChildRun& b) {
    return steps ? 1000 * (a.cpu_s - b.cpu_s) / steps : 0.0;
  };
  const nlohmann::json split = {{"python_loop_ms", per_step(lines, plain)},
                                {"images_to_python_ms", per_step(bytes, lines)},
                                {"numpy_ms", per_step(arrays, bytes)},
                                {"images_into_dataset_ms", per_step(dataset, plain)}};
  std::printf(
      "  images to a Python policy at %.2fx the dataset's steps/s; CPU per step: the Python "
      "loop and its line %.2f ms, the images drawn and through the pipe %.2f ms, numpy %.2f "
      "ms (the dataset's images: %.2f ms)\n",
      ratio, split["python_loop_ms"].get<double>(), split["images_to_python_ms"].get<double>(),
      split["numpy_ms"].get<double>(), split["images_into_dataset_ms"].get<double>());
  return {{"episodes", episodes}, {"size", size},   {"backend", backend},      {"python", python},
          {"rows", rows},         {"ratio", ratio}, {"cpu_ms_per_step", split}};
}

}  // namespace fetchscope::bench
