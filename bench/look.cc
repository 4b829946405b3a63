// bench --what look: what a randomized look (issue 49) costs a recorded frame's CPU. The same
// episodes recorded plain and with --randomize colors,textures,lighting,camera, as child
// `record` runs of this binary, alternating, each read back from its manifest's
// timings_s.cpu_ms_per_frame (thread CPU clocks, LP_NUM_THREADS=0 so that llvmpipe rasterises on
// the render thread and `gl` holds all of GL).
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "bench/bench.h"
#include "bench/children.h"

namespace fetchscope::bench {
namespace fs = std::filesystem;

namespace {

constexpr const char* kRandomize = "colors,textures,lighting,camera";

// The figures of one record run, ms of thread CPU per frame: the renderer's stages outside GL,
// the look's own, and GL.
struct LookRun {
  std::map<std::string, double> ms;  // the manifest's cpu_ms_per_frame
  double at(const std::string& stage) const {
    const auto it = ms.find(stage);
    return it == ms.end() ? 0.0 : it->second;
  }
  // the renderer's CPU outside GL: scene (with the look's per-frame edits), hud, copy, and the
  // look's once-per-episode draw and texture upload
  double Renderer() const { return at("scene") + at("hud") + at("copy") + at("look"); }
};

// The rows printed and stored: the account's name and how it is summed from a run.
struct Row {
  const char* name;
  double (*of)(const LookRun&);
};

const Row kRows[] = {
    {"sim", [](const LookRun& r) { return r.at("sim"); }},
    {"scene", [](const LookRun& r) { return r.at("scene"); }},
    {"hud", [](const LookRun& r) { return r.at("hud"); }},
    {"copy", [](const LookRun& r) { return r.at("copy"); }},
    {"look", [](const LookRun& r) { return r.at("look"); }},
    {"renderer_outside_gl", [](const LookRun& r) { return r.Renderer(); }},
    {"convert", [](const LookRun& r) { return r.at("convert"); }},
    {"encode", [](const LookRun& r) { return r.at("encode"); }},
    {"sheet", [](const LookRun& r) { return r.at("sheet"); }},
    {"outside_gl", [](const LookRun& r) { return r.at("outside_gl"); }},
    {"gl", [](const LookRun& r) { return r.at("gl"); }},
};

// Mean, min and max of `values`.
nlohmann::json Spread(const std::vector<double>& values) {
  double sum = 0;
  for (double v : values) sum += v;
  return {{"mean", values.empty() ? 0.0 : sum / static_cast<double>(values.size())},
          {"min", *std::min_element(values.begin(), values.end())},
          {"max", *std::max_element(values.begin(), values.end())},
          {"runs", values}};
}

// Prints the table: per row, plain and randomized (mean, range) and the ratio of the means.
nlohmann::json Table(const std::vector<LookRun>& plain, const std::vector<LookRun>& randomized) {
  nlohmann::json rows = nlohmann::json::object();
  std::printf("%-22s %-24s %-24s %s\n", "ms CPU per frame", "plain (mean, min-max)",
              "randomized (mean, min-max)", "randomized/plain");
  for (const Row& row : kRows) {
    std::vector<double> p, r;
    for (const LookRun& run : plain) p.push_back(row.of(run));
    for (const LookRun& run : randomized) r.push_back(row.of(run));
    const nlohmann::json ps = Spread(p), rs = Spread(r);
    const double pm = ps["mean"], rm = rs["mean"];
    // a stage the plain look does not run (look: a clock read) has no ratio
    const nlohmann::json ratio = pm >= 0.001 ? nlohmann::json(rm / pm) : nlohmann::json(nullptr);
    char pc[64], rc[64];
    std::snprintf(pc, sizeof pc, "%.3f (%.3f-%.3f)", pm, ps["min"].get<double>(),
                  ps["max"].get<double>());
    std::snprintf(rc, sizeof rc, "%.3f (%.3f-%.3f)", rm, rs["min"].get<double>(),
                  rs["max"].get<double>());
    if (pm >= 0.001) {
      std::printf("%-22s %-24s %-24s x%.3f\n", row.name, pc, rc, rm / pm);
    } else {
      std::printf("%-22s %-24s %-24s -\n", row.name, pc, rc);
    }
    rows[row.name] = {{"plain", ps}, {"randomized", rs}, {"ratio", ratio}};
  }
  return rows;
}

}  // namespace

nlohmann::json BenchLook(const AssetSource& assets, const std::string& backend, int episodes,
                         int repeats) {
  const std::string self = fs::read_symlink("/proc/self/exe").string();
  const fs::path dir =
      fs::temp_directory_path() / ("fetchscope_bench_look_" + std::to_string(getpid()));
  const std::vector<std::string> common =
      Concat({"--env-id", "FetchPush-v4", "--policy", "random", "--seed", "0", "--episodes",
              std::to_string(episodes), "--backend", backend, "--jobs", "1"},
             AssetsArg(assets));
  const char* before = std::getenv("LP_NUM_THREADS");
  const std::string kept = before ? before : "";
  setenv("LP_NUM_THREADS", "0", 1);
  std::vector<LookRun> plain, randomized;
  std::string failed;
  std::printf(
      "look: record FetchPush-v4 random 480x480, %d episodes (%d frames), --jobs 1, %s, "
      "plain and --randomize %s alternating, %d repeats (thread CPU, LP_NUM_THREADS=0)\n",
      episodes, episodes * 51, backend.c_str(), kRandomize, repeats);
  for (int i = 0; i < repeats && failed.empty(); ++i) {
    for (const bool look : {false, true}) {
      const RecordRun run =
          RunRecordChild(self, look ? Concat(common, {"--randomize", kRandomize}) : common, dir);
      if (run.child.exit_code != 0 || !run.manifest || !run.manifest->timings_s.cpu_ms_per_frame) {
        failed = run.child.exit_code != 0
                     ? "record failed (exit " + std::to_string(run.child.exit_code) + ")"
                     : "the manifest has no timings_s.cpu_ms_per_frame";
        break;
      }
      (look ? randomized : plain).push_back({*run.manifest->timings_s.cpu_ms_per_frame});
    }
  }
  if (before) {
    setenv("LP_NUM_THREADS", kept.c_str(), 1);
  } else {
    unsetenv("LP_NUM_THREADS");
  }
  if (!failed.empty()) {
    std::printf("look: skipped: %s\n", failed.c_str());
    return {{"skipped", failed}};
  }
  nlohmann::json result = {{"env_id", "FetchPush-v4"},
                           {"policy", "random"},
                           {"width", 480},
                           {"height", 480},
                           {"episodes", episodes},
                           {"frames", episodes * 51},
                           {"repeats", repeats},
                           {"backend", backend},
                           {"randomize", kRandomize},
                           {"lp_num_threads", 0}};
  result["ms_per_frame"] = Table(plain, randomized);
  const nlohmann::json& outside = result["ms_per_frame"]["outside_gl"]["ratio"];
  const nlohmann::json& renderer = result["ms_per_frame"]["renderer_outside_gl"];
  if (!outside.is_null()) {
    const double extra =
        renderer["randomized"]["mean"].get<double>() - renderer["plain"]["mean"].get<double>();
    const double plain_outside =
        result["ms_per_frame"]["outside_gl"]["plain"]["mean"].get<double>();
    result["renderer_extra_share_of_outside_gl"] = extra / plain_outside;
    std::printf(
        "look: outside GL x%.3f; the renderer's extra (scene+hud+copy+look) is %.1f%% of the "
        "plain frame's CPU outside GL (goal: at most 10%%)\n",
        outside.get<double>(), 100 * extra / plain_outside);
  }
  return result;
}

}  // namespace fetchscope::bench
