// fetchscope bench: throughput of simulation, rendering, encoding and recording.
#include "bench/bench.h"

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <sstream>
#include <string>

#include "base/json_util.h"
#include "cli/command.h"
#include "cli/common.h"
#include "src/episode.h"
#include "src/fetch_env.h"

namespace fetchscope::cli {
namespace {

struct BenchOptions {
  std::string what = "all";
  std::string json_out;
  std::string assets = "bundled";
  double seconds = 3.0;
  std::string backends = "egl,osmesa";
  bool peers = true;
  int soak_frames = 10000;
  int node_width = 480;
  int node_height = 480;
  int serve_width = 640;
  int serve_height = 480;
  int dataset_episodes = 20;
  int dataset_size = 128;
  int exec_episodes = 10;
  std::string exec_size = "96x80";
  std::string exec_python = "python3";
  int look_episodes = 8;
  int look_repeats = 3;
};

int RunBench(const BenchOptions& o) {
  const AssetSource source = ResolveAssets(o.assets);
  nlohmann::json j;
  j["machine"] = bench::MachineJson();
  j["versions"] = VersionsJson();
  j["assets"] = AssetsJson(source);
  const bool all = o.what == "all";
  if (all || o.what == "sim") j["sim"] = bench::BenchSim(source, o.seconds);
  if (all || o.what == "render")
    j["render"] = bench::BenchRender(source, o.backends, o.seconds, o.peers);
  if (all || o.what == "encode") j["encode"] = bench::BenchEncode(o.seconds);
  if (all || o.what == "record")
    j["record"] = bench::BenchRecord(source, o.backends, o.seconds, o.peers);
  if (o.what == "node") {
    j["node"] = bench::BenchNode(source, o.backends, o.seconds, o.node_width, o.node_height);
    const nlohmann::json rec = bench::NodeRecommendation(j["node"]["record"]);
    j["node"]["recommendation"] = rec;
    if (rec.contains("flags")) {
      std::printf("recommended: %s (the fastest record run: %.0f frames/s at %dx%d)\n",
                  rec["flags"].get<std::string>().c_str(), rec["frames_per_s"].get<double>(),
                  o.node_width, o.node_height);
    } else {
      std::printf("recommended: nothing (%s)\n", rec["none"].get<std::string>().c_str());
    }
  }
  if (o.what == "dataset") {
    j["dataset"] = bench::BenchDataset(source, o.backends, o.dataset_episodes, o.dataset_size);
  }
  if (o.what == "exec-images") {
    j["exec_images"] =
        bench::BenchExecImages(source, o.backends, o.exec_episodes, o.exec_size, o.exec_python);
  }
  if (o.what == "look") {
    const std::string first = o.backends.substr(0, o.backends.find(','));
    j["look"] = bench::BenchLook(source, first, o.look_episodes, o.look_repeats);
  }
  if (o.what == "soak") j["soak"] = bench::BenchSoak(source, o.backends, o.soak_frames, 1.0);
  if (o.what == "serve") {
    const std::string first = o.backends.substr(0, o.backends.find(','));
    j["serve"] = bench::BenchServe(source, first, o.seconds, o.serve_width, o.serve_height);
  }
  j["peak_rss_mib"] = bench::PeakRssMiB();
  std::printf("peak RSS %.1f MiB\n", bench::PeakRssMiB());
  if (!o.json_out.empty()) {
    const std::string path = JsonOutPath(o.json_out, "bench");
    WriteJson(path, j);
    std::printf("wrote %s\n", path.c_str());
  }
  return 0;
}

}  // namespace

Command AddBench(CLI::App& app) {
  auto o = std::make_shared<BenchOptions>();
  CLI::App* sub =
      app.add_subcommand("bench", "Measure simulation, rendering, encoding and record throughput");
  sub->add_option(
         "--what", o->what,
         "sim, render, encode, record, all (those four); node: what sizes a job on this "
         "machine (render frames/s of one context, sync and async readback; record "
         "frames/s at --jobs 1, cores/4, cores/2 and cores as processes and as threads, and "
         "msaa 0 at the fastest of those --jobs; the encoder; and the --jobs and "
         "--worker-mode of the fastest record run, recommended); record also gives each "
         "stage's CPU time per frame (the manifest's timings_s.cpu_ms_per_frame); "
         "or soak: one long record run (--soak-frames, minutes) with its memory sampled "
         "every second; or serve: serve's frame budget on its own server (render + encode per "
         "frame, frames/s of 1, 2 and 4 pages dragging, a live key step, a seek; on the first "
         "of --backends, at --serve-width x --serve-height); or dataset: images into a pixel "
         "dataset (rollout --obs-camera) beside record of the same camera and size and "
         "rollout without images (--dataset-episodes, --dataset-size); or exec-images: images "
         "to a Python exec: policy beside the same images into a dataset, and where a step's "
         "CPU goes (--exec-episodes, --exec-size, --exec-python); or look: a randomized look's "
         "CPU per recorded frame, plain beside --randomize colors,textures,lighting,camera "
         "(record runs on the first of --backends; --look-episodes, --look-repeats). node, "
         "soak, serve, dataset, exec-images and look are not part of all")
      ->capture_default_str()
      ->check(CLI::IsMember({"sim", "render", "encode", "record", "all", "node", "soak", "serve",
                             "dataset", "exec-images", "look"}));
  sub->add_option("--look-episodes", o->look_episodes, "--what look: episodes of each record run")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  sub->add_option("--look-repeats", o->look_repeats,
                  "--what look: record runs of each look (plain, randomized alternating)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  sub->add_option("--exec-episodes", o->exec_episodes, "--what exec-images: episodes of each run")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  sub->add_option("--exec-size", o->exec_size, "--what exec-images: the image's WxH")
      ->capture_default_str();
  sub->add_option("--exec-python", o->exec_python,
                  "--what exec-images: the Python (with numpy) that runs the policy child")
      ->capture_default_str();
  sub->add_option("--dataset-episodes", o->dataset_episodes, "--what dataset: episodes of each run")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  sub->add_option("--dataset-size", o->dataset_size, "--what dataset: the image's width and height")
      ->capture_default_str()
      ->check(CLI::Range(8, 4096));
  sub->add_option("--serve-width", o->serve_width, "--what serve: the live view's width")
      ->capture_default_str()
      ->check(CLI::Range(16, 4096));
  sub->add_option("--serve-height", o->serve_height, "--what serve: the live view's height")
      ->capture_default_str()
      ->check(CLI::Range(16, 4096));
  sub->add_option("--soak-frames", o->soak_frames,
                  "Frames of the soak run (whole 51-frame episodes)")
      ->capture_default_str()
      ->check(CLI::Range(51, 1000000));
  sub->add_option("--width", o->node_width,
                  "--what node: frame width, the size your jobs record at")
      ->capture_default_str()
      ->check(CLI::Range(16, 4096));
  sub->add_option("--height", o->node_height, "--what node: frame height")
      ->capture_default_str()
      ->check(CLI::Range(16, 4096));
  sub->add_option("--assets", o->assets, "bundled, auto or a Gymnasium-Robotics assets folder")
      ->capture_default_str();
  sub->add_option("--seconds", o->seconds, "Time budget per measurement group")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 600.0));
  sub->add_option("--backends", o->backends,
                  "Render backends to measure: a comma list of egl, osmesa")
      ->capture_default_str()
      ->check(
          [](const std::string& list) -> std::string {
            std::string item;
            std::stringstream stream(list);
            while (std::getline(stream, item, ',')) {
              if (item != "egl" && item != "osmesa") {
                return "backend '" + item + "' is not known; accepted: egl, osmesa (comma list)";
              }
            }
            return "";
          },
          "egl,osmesa");
  sub->add_flag("!--no-peers", o->peers, "Skip the peer measurements (mujoco-record, ffmpeg)");
  sub->add_option("--json-out", o->json_out, "Write the results as JSON (P.json or P_bench.json)");
  return {sub, [o] { return RunBench(*o); }};
}

}  // namespace fetchscope::cli
