// bench's child processes (this binary's record, the peers) and what it reads back from them.
#include "bench/children.h"

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

namespace fs = std::filesystem;

double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

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
  run.cpu_s = static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
              static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) / 1e6;
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

}  // namespace fetchscope::bench
