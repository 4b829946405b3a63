// Reading the files of a folder someone else may have made (a run folder for serve, report,
// compare, export and record --from; a trajectory, manifest or dataset metadata file) without
// reading anything else: every file a run folder names resolves inside that folder (symbolic
// links and '..' followed), is a regular file (never a FIFO, a device or a folder), and is read
// only up to a size cap, checked before reading and enforced while reading. Messages name the
// file and what was wrong, never its bytes.
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

namespace fetchscope {

/// The most bytes fetchscope reads from one trajectory, manifest, replay or dataset metadata JSON
/// file: 256 MiB. A 10,000-step trajectory of FetchPickAndPlace-v4 (each step its observation,
/// goals, action, reward) weighs 14,592,035 bytes (about 14 MiB, measured with rollout --steps
/// 10000 --json-out; record's episode_NNN.json has the same rows), and a manifest entry about
/// 0.4 to 1 KB (under 10 MiB for 10,000 episodes): the cap is over 17 times the largest real file,
/// and keeps a hostile one (a symbolic link to /dev/zero, a file that grows while it is read) from
/// taking more memory than that.
inline constexpr uint64_t kMaxJsonFileBytes = uint64_t{256} << 20;

/// The bytes of the file `path`, read whole. Throws UsageError naming `path` when it is not a
/// regular file (a FIFO, a character or block device, a socket, a folder: it is opened without
/// blocking and never read) or holds more than `max_bytes` (its size is checked before reading,
/// and reading stops one byte past the cap, so a file that grows or lies about its size cannot
/// take more memory); RunError ("cannot read 'PATH': REASON") when it cannot be opened or read.
std::string ReadFileCapped(const std::filesystem::path& path, uint64_t max_bytes);

/// True when `path` lies inside `folder` (below it, not the folder itself), symbolic links and
/// '..' resolved on both; false too when either cannot be resolved.
bool LiesInside(const std::filesystem::path& folder, const std::filesystem::path& path);

/// The file `entry` of `folder` (`folder / entry`, as given: the path messages show) after
/// checking that it lies inside `folder`, symbolic links and '..' resolved on both (an absolute
/// entry too must resolve inside). Otherwise throws UsageError: "`named_by` 'ENTRY', which lies
/// outside the run folder 'FOLDER': a run's files must lie inside it", where `named_by` says
/// who names the entry ("manifest.json names trajectory", "--from 'run' holds"). A missing
/// entry is not refused here (its reader says it is missing); nor is a file that is not regular
/// (ReadFileCapped and RequireRegularIfPresent refuse those).
std::filesystem::path ResolveInside(const std::filesystem::path& folder, const std::string& entry,
                                    const std::string& named_by);

/// Throws UsageError "`named_by` 'ENTRY', which is a KIND, not a regular file" when `path`
/// exists (symbolic links followed) and is not a regular file; a missing file passes.
void RequireRegularIfPresent(const std::filesystem::path& path, const std::string& entry,
                             const std::string& named_by);

/// What went wrong parsing `text_size` bytes as JSON, without quoting any of them (nlohmann's own
/// what() shows the bytes it last read): "its JSON ends at byte N before it is complete" or
/// "it is not valid JSON at byte N of M".
std::string DescribeJsonError(const nlohmann::json::parse_error& e, size_t text_size);

}  // namespace fetchscope
