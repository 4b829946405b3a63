// Options and helpers shared by the subcommands.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace fetchscope::cli {

/// --env-id, --assets, --seed as every env-driven subcommand takes them.
struct EnvOptions {
  std::string env_id = "auto";     ///< a v4 id or auto (FetchReachDense-v4)
  std::string assets = "bundled";  ///< bundled | auto | DIR
  std::string seed = "0";          ///< non-negative integer, parsed by ParseSeed
};

/// Adds --env-id/--assets (and --seed when with_seed) to `sub`.
void AddEnvOptions(CLI::App* sub, EnvOptions* options, bool with_seed = true);

/// Parses a Gymnasium seed: a non-negative integer below 2^64. Throws UsageError.
uint64_t ParseSeed(const std::string& text);

/// `--json-out P` naming: P itself if it ends in .json, else P + "_" + suffix + ".json".
std::string JsonOutPath(const std::string& prefix, const std::string& suffix);

/// Writes JSON atomically (temporary name, then rename) with a trailing newline.
void WriteJson(const std::string& path, const nlohmann::json& json);

/// Versions of fetchscope and MuJoCo, for every output.
nlohmann::json VersionsJson();

/// The cores this process may use, and why that many.
struct Cores {
  int usable = 1;      ///< what --jobs 0 and the encoder budget count
  int online = 1;      ///< the machine's online CPUs
  std::string source;  ///< "online", "affinity" (taskset, Slurm, cpusets) or "cgroup quota"
};

/// The cores this process may use: the CPUs in its affinity mask (Slurm's and Kubernetes'
/// cpusets, taskset), capped by a cgroup CPU quota (cgroup v2 cpu.max, v1 cfs_quota_us) rounded
/// up, as containers with CPU limits have. Never below 1.
Cores UsableCores();

/// The cgroup CPU quota in cores (quota / period; the smallest along the cgroup's ancestors), or
/// 0 when there is none: `proc_self_cgroup` is /proc/self/cgroup, `cgroup_root` /sys/fs/cgroup.
double CgroupCpuQuota(const std::string& proc_self_cgroup, const std::string& cgroup_root);

/// For `--policy replay:FILE.json` holding fetchscope's trajectory JSON: the file's episode
/// indices, ascending, which a run replaying it plays (each under its own index, so with its own
/// reset); nullopt for any other policy. `episodes` is --episodes when the user gave it
/// (0: not given): a different count is a UsageError. Warns on stderr (unless `quiet`) when the
/// file was recorded on another env or seed than `env_id` / `seed`.
std::optional<std::vector<int>> ReplayedEpisodes(const std::string& policy, int episodes,
                                                 const std::string& env_id, uint64_t seed,
                                                 bool quiet);

/// Exit status a subcommand asks for (0 unless it set one).
int& ExitStatus();

/// Makes SIGINT and SIGTERM request a stop instead of killing the process, so long commands
/// (record, golden update) can finish the file in progress; clears any earlier request.
void InstallStopSignals();

/// The signal that requested a stop (SIGINT or SIGTERM), or 0. Safe from any thread.
int StopSignal();

/// The command line as typed (set by main), recorded in manifests.
std::string& CommandLine();

/// The --help formatter of every command: a placeholder named after the option instead of
/// CLI11's type names ("--seed SEED", not "--seed TEXT=0"), defaults in the description, no
/// "{false}" after negated flags. Set on the app before the subcommands are added (they inherit
/// it).
std::shared_ptr<CLI::Formatter> MakeHelpFormatter();

/// Registration of each subcommand (one file each).
void RegisterListEnvs(CLI::App& app);
void RegisterDescribe(CLI::App& app);
void RegisterRewardCheck(CLI::App& app);
void RegisterRandomEpisodes(CLI::App& app);
void RegisterRollout(CLI::App& app);
void RegisterRender(CLI::App& app);
void RegisterListCameras(CLI::App& app);
void RegisterRecord(CLI::App& app);
void RegisterBench(CLI::App& app);
void RegisterProbeActions(CLI::App& app);
void RegisterMergeManifests(CLI::App& app);
void RegisterGolden(CLI::App& app);
void RegisterListGpus(CLI::App& app);
void RegisterAnatomy(CLI::App& app);
void RegisterReport(CLI::App& app);
void RegisterCompare(CLI::App& app);

}  // namespace fetchscope::cli
