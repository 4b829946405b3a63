// What bench's parts share: its child processes (this binary's `record`, the peers
// mujoco-record and ffmpeg) and what it reads back from them.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "base/process.h"
#include "run/manifest.h"
#include "src/assets.h"

namespace fetchscope::bench {

using Clock = std::chrono::steady_clock;

/// Seconds since `t`.
double Since(Clock::time_point t);

/// One child process's figures.
struct ChildRun {
  int exit_code = -1;       ///< the shell's convention: 128 + signal when killed
  double wall_s = 0;        ///< seconds from start to exit
  double peak_rss_mib = 0;  ///< the child's peak resident set
  double cpu_s = 0;         ///< its user + system CPU seconds (and its waited-for children's)
};

/// Spawn options with the child's stdout and stderr going to /dev/null.
SpawnOptions Quiet();

/// Runs `argv` (no shell) with its output discarded; wall time and the child's peak RSS.
ChildRun RunChild(const std::vector<std::string>& argv);

/// `a` followed by `b`.
std::vector<std::string> Concat(std::vector<std::string> a, const std::vector<std::string>& b);

/// The whole of a text file; "" when it cannot be read.
std::string ReadText(const std::string& path);

/// The manifest of the run in `dir`; nullopt when it wrote none (or not one this build reads).
std::optional<Manifest> ReadManifestIn(const std::filesystem::path& dir);

/// "auto (4)" / "0": the --msaa asked for and the samples used, for the tables.
std::string MsaaLabel(const std::string& requested, int samples);

/// True when `name` is on PATH.
bool HaveProgram(const std::string& name);

/// A comma list's items.
std::vector<std::string> Split(const std::string& list);

/// The genuine model the peers run on: $FETCHSCOPE_ASSETS, ../shared, or --assets DIR; "" when
/// none is found.
std::string GenuineModel(const AssetSource& assets, const std::string& file);

/// mujoco-record rendering `frames` frames of `model` into `rgb_out`, under xvfb-run.
nlohmann::json PeerMujocoRecord(const std::string& model, int frames, const std::string& rgb_out);

/// One `fetchscope record` child: its process figures and the manifest it wrote.
struct RecordRun {
  ChildRun child;
  std::optional<Manifest> manifest;  ///< nullopt when the run wrote none
};

/// Runs this binary's `record` with `args` into `dir` (removed afterwards).
RecordRun RunRecordChild(const std::string& self, const std::vector<std::string>& args,
                         const std::filesystem::path& dir);

/// The samples a record run used: its manifest's "msaa"; without a manifest the samples asked
/// for, or -1 (unknown) for auto.
int ManifestMsaa(const std::optional<Manifest>& manifest, const std::string& requested);

/// --assets for a record child using the same assets as this run.
std::vector<std::string> AssetsArg(const AssetSource& assets);

/// True when this binary's record takes --jobs (its help names it).
bool RecordHasJobs(const std::string& self);

/// Resident set size (VmRSS) of process `pid` in MiB, or -1 once it has gone.
double ReadRssMiB(pid_t pid);

}  // namespace fetchscope::bench
