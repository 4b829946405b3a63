// fetchscope bench: throughput of simulation, rendering, encoding and recording.
#include "cli/bench.h"

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

using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// Raw physics bound: the same episodes (reset, gripper held in place) as bare mj_step calls,
// without the env's action, observation and callback work around them.
double RawSubstepsPerSecond(FetchEnv& env, double budget_s) {
  mjModel* m = env.model();
  mjData* d = env.data();
  const int substeps = env.spec().max_episode_steps * env.spec().n_substeps;
  long n = 0;
  double busy = 0;
  while (busy < budget_s) {
    env.Reset(n);
    env.Step(Action{});  // anchors the mocap on the gripper, as every episode's first step does
    const auto start = Clock::now();
    for (int i = 0; i < substeps; ++i) mj_step(m, d);
    busy += Seconds(start, Clock::now());
    n += substeps;
  }
  return n / busy;
}

// Env steps with the zero policy (no policy cost), resets every 50 steps included.
double EnvStepsPerSecond(FetchEnv& env, double budget_s) {
  Action zero;
  long n = 0;
  const auto start = Clock::now();
  while (Seconds(start, Clock::now()) < budget_s) {
    env.Reset(n);
    for (int t = 0; t < env.spec().max_episode_steps; ++t) env.Step(zero);
    n += env.spec().max_episode_steps;
  }
  return n / Seconds(start, Clock::now());
}

}  // namespace

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

double PeakRssMiB() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;
}

nlohmann::json BenchSim(const AssetSource& assets, double budget_s) {
  nlohmann::json rows = nlohmann::json::array();
  std::printf("%-22s %14s %16s %12s %8s\n", "sim", "mj_step/s", "bound steps/s", "env steps/s",
              "ratio");
  for (const EnvSpec& spec : AllEnvSpecs()) {
    if (spec.dense) continue;  // dense and sparse differ only in the reward formula
    FetchEnv env(spec, assets);
    // interleave the two measurements and keep the best of three of each
    double raw = 0, stepped = 0;
    for (int rep = 0; rep < 3; ++rep) {
      raw = std::max(raw, RawSubstepsPerSecond(env, budget_s / 6));
      stepped = std::max(stepped, EnvStepsPerSecond(env, budget_s / 6));
    }
    const double bound = raw / spec.n_substeps;
    std::printf("%-22s %14.0f %16.1f %12.1f %7.1f%%\n", spec.id.c_str(), raw, bound, stepped,
                100 * stepped / bound);
    rows.push_back({{"env_id", spec.id},
                    {"mj_step_per_s", raw},
                    {"bound_env_steps_per_s", bound},
                    {"env_steps_per_s", stepped},
                    {"ratio_to_bound", stepped / bound}});
  }
  return rows;
}

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
};

int RunBench(const BenchOptions& o) {
  const AssetSource source = ResolveAssets(o.assets);
  nlohmann::json j;
  j["machine"] = MachineJson();
  j["versions"] = VersionsJson();
  j["assets"] = AssetsJson(source);
  const bool all = o.what == "all";
  if (all || o.what == "sim") j["sim"] = BenchSim(source, o.seconds);
  if (all || o.what == "render") j["render"] = BenchRender(source, o.backends, o.seconds, o.peers);
  if (all || o.what == "encode") j["encode"] = BenchEncode(o.seconds);
  if (all || o.what == "record") j["record"] = BenchRecord(source, o.backends, o.seconds, o.peers);
  if (o.what == "node") {
    j["node"] = BenchNode(source, o.backends, o.seconds, o.node_width, o.node_height);
    const nlohmann::json rec = NodeRecommendation(j["node"]["record"]);
    j["node"]["recommendation"] = rec;
    if (rec.contains("flags")) {
      std::printf("recommended: %s (the fastest record run: %.0f frames/s at %dx%d)\n",
                  rec["flags"].get<std::string>().c_str(), rec["frames_per_s"].get<double>(),
                  o.node_width, o.node_height);
    } else {
      std::printf("recommended: nothing (%s)\n", rec["none"].get<std::string>().c_str());
    }
  }
  if (o.what == "soak") j["soak"] = BenchSoak(source, o.backends, o.soak_frames, 1.0);
  j["peak_rss_mib"] = PeakRssMiB();
  std::printf("peak RSS %.1f MiB\n", PeakRssMiB());
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
         "frames/s at --jobs 1, cores/2 and cores as processes and as threads; the encoder; "
         "and the --jobs and --worker-mode of the fastest record run, recommended); "
         "or soak: one long record run (--soak-frames, minutes) with its memory sampled "
         "every second. node and soak are not part of all")
      ->capture_default_str()
      ->check(CLI::IsMember({"sim", "render", "encode", "record", "all", "node", "soak"}));
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
