#include "run/run_folder.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>

#include "base/atomic_file.h"
#include "base/confined_file.h"
#include "base/errors.h"
#include "encode/video_format.h"
#include "run/run_files.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;

// The manifest at `path`; nullopt when it cannot be read as one.
std::optional<Manifest> ReadManifestOrNull(const fs::path& path) {
  try {
    return ReadManifest(path);
  } catch (const ManifestError&) {
    return std::nullopt;
  }
}

// "--steps is 50 there and 20 here" for the first parameter in which `theirs` and `ours`
// differ; empty when they are the same run in `scope`.
std::string Difference(const RunParameters& theirs, const RunParameters& ours, SameRunScope scope) {
  const std::optional<RunDifference> d = SameRun(theirs, ours, scope);
  return d ? d->parameter + " is " + d->a + " there and " + d->b + " here" : "";
}

// The start of the hidden folder's name inside --out where --overwrite keeps the earlier run
// until the new one has its manifest (the process id follows): ".manifest.replaced-",
// ".manifest_shard_0001_of_0004.replaced-".
std::string AsideFolderPrefix(const std::string& manifest_name) {
  return "." + fs::path(manifest_name).stem().string() + ".replaced-";
}

std::string Listed(const std::vector<std::string>& names) {
  std::string s;
  for (size_t i = 0; i < names.size() && i < 3; ++i) s += (i ? ", " : "") + names[i];
  if (names.size() > 3) s += " and " + std::to_string(names.size() - 3) + " more";
  return s;
}

// `p` as the file system resolves it: absolute, symlinks followed as far as it exists, no
// trailing separator.
fs::path Resolved(const fs::path& p) {
  std::error_code ec;
  fs::path r = fs::weakly_canonical(fs::absolute(p, ec), ec);
  if (ec) r = fs::absolute(p).lexically_normal();
  if (!r.has_filename() && r.has_relative_path()) r = r.parent_path();
  return r;
}

// True when `inner` is `outer` or lies inside it (both resolved).
bool Within(const fs::path& inner, const fs::path& outer) {
  const size_t n = std::distance(outer.begin(), outer.end());
  return static_cast<size_t>(std::distance(inner.begin(), inner.end())) >= n &&
         std::equal(outer.begin(), outer.end(), inner.begin());
}

// Refuses an --out that is, holds or lies inside what the run reads: recording there would
// replace (or bury) the run it replays.
void CheckNotASource(const fs::path& out, const std::string& quoted,
                     const std::vector<std::pair<std::string, std::string>>& sources) {
  const fs::path o = Resolved(out);
  for (const auto& [option, source] : sources) {
    if (source.empty()) continue;
    const fs::path s = Resolved(source);
    const char* how = s == o         ? " is "
                      : Within(s, o) ? " holds "
                      : Within(o, s) ? " lies inside "
                                     : "";
    if (!*how) continue;
    throw UsageError(quoted + how + option + " '" + source + "' (" +
                     (s == o ? "both " + o.string() : o.string() + " and " + s.string()) +
                     "): a run never writes where it reads; choose another --out");
  }
}

// Refuses a folder nothing can be written in, before anything is rendered (root ignores the
// permission bits, so the check writes a file rather than asking access()).
void CheckWritable(const fs::path& out, const std::string& quoted) {
  const fs::path probe = out / (".fetchscope-write-check-" + std::to_string(::getpid()));
  const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) {
    const int err = errno;
    throw UsageError(quoted + " is not writable (" + std::strerror(err) +
                     "): choose a folder you can write to");
  }
  ::close(fd);
  ::unlink(probe.c_str());
}

}  // namespace

ReuseMode ParseReuseMode(bool overwrite, bool resume) {
  if (overwrite && resume) {
    throw UsageError(
        "--overwrite and --resume contradict each other: --overwrite replaces the run "
        "in --out, --resume continues it; pass one");
  }
  return overwrite ? ReuseMode::kOverwrite : resume ? ReuseMode::kResume : ReuseMode::kRefuse;
}

bool RunFolder::Ours(const std::string& name) const {
  const std::optional<RunFileName> parsed = ParseRunFileName(name);
  if (!parsed) return false;
  if (parsed->manifest) {
    std::string visible = name;
    if (parsed->hidden) visible = name.substr(1, name.find(".tmp-") - 1);
    return visible == request_.manifest_name;
  }
  if (parsed->report) return !request_.sharded;  // a sharded run's report: merge-manifests'
  return !request_.sharded || request_.owns(parsed->episode);
}

RunFolder::RunFolder(const RunFolderRequest& request) : request_(request) {
  const fs::path out = request.out.empty() ? fs::path(".") : fs::path(request.out);
  const std::string quoted = "--out '" + request.out + "'";
  CheckNotASource(out, quoted, request.sources);
  std::error_code ec;
  for (fs::path p = out; !p.empty() && !fs::exists(p, ec); p = p.parent_path()) {
    created_dirs_.push_back(p);
    if (p == p.parent_path()) break;
  }
  Listing listing;
  if (created_dirs_.empty()) {
    if (fs::is_directory(out, ec)) lock_ = FolderLock(out, LockKind(), "--out");
    listing = ListFolder(out, quoted);
  }
  FindAside(out, quoted);
  CheckOtherManifests(out, quoted, listing.manifests, &listing.run_files);
  std::vector<std::string> remove;
  todo_ = request.episodes;
  if (!PlanRemovals(out, quoted, listing, &remove)) return;  // --resume of a whole run
  PrepareFolder(out, quoted, remove);
}

FolderLock::Kind RunFolder::LockKind() const {
  return request_.sharded ? FolderLock::Kind::kShared : FolderLock::Kind::kExclusive;
}

RunFolder::Listing RunFolder::ListFolder(const fs::path& out, const std::string& quoted) const {
  Listing listing;
  std::error_code ec;
  if (!fs::is_directory(out, ec)) {
    throw UsageError("cannot create output folder '" + request_.out + "': a file is in the way");
  }
  for (const auto& entry : fs::directory_iterator(out, ec)) {
    const std::string name = entry.path().filename().string();
    const std::optional<RunFileName> parsed = ParseRunFileName(name);
    if (!parsed || entry.is_directory(ec)) continue;  // record writes files only
    if (parsed->manifest && !parsed->hidden && name != request_.manifest_name) {
      listing.manifests.push_back(name);
    } else if (Ours(name)) {
      (parsed->hidden ? listing.hidden : listing.run_files).push_back(name);
    }
  }
  if (ec) throw RunError("cannot list " + quoted + ": " + ec.message());
  std::sort(listing.run_files.begin(), listing.run_files.end());
  std::sort(listing.manifests.begin(), listing.manifests.end());
  CheckWritable(out, quoted);
  RefuseForeignFiles(out, quoted, &listing.run_files, listing.manifests);
  return listing;
}

void RunFolder::FindAside(const fs::path& out, const std::string& quoted) {
  // --overwrite sets the earlier run aside in a hidden folder; one still there is from an
  // --overwrite that was killed outright (SIGKILL): never lost silently
  std::error_code ec;
  const std::string aside_prefix = AsideFolderPrefix(request_.manifest_name);
  aside_ = out / (aside_prefix + std::to_string(::getpid()));
  if (created_dirs_.empty()) {
    for (const auto& entry : fs::directory_iterator(out, ec)) {
      if (entry.path().filename().string().rfind(aside_prefix, 0) == 0) {
        stale_aside_.push_back(entry.path());
      }
    }
    std::sort(stale_aside_.begin(), stale_aside_.end());
  }
  for (int n = 1; fs::exists(aside_, ec); ++n) {  // a killed run had this process id
    aside_ = out / (aside_prefix + std::to_string(::getpid()) + "-" + std::to_string(n));
  }
  if (!stale_aside_.empty() && request_.mode != ReuseMode::kOverwrite) {
    throw UsageError(quoted + " holds " + stale_aside_.front().filename().string() +
                     ", an earlier run that --overwrite set aside before it was killed: move its "
                     "files back into " +
                     quoted +
                     " to keep that run, or pass --overwrite to "
                     "replace both");
  }
}

void RunFolder::CheckOtherManifests(const fs::path& out, const std::string& quoted,
                                    const std::vector<std::string>& manifests,
                                    std::vector<std::string>* run_files) const {
  // Other manifests: a sharded run shares the folder with the other shards of the same run;
  // anything else is another run.
  for (const std::string& name : manifests) {
    const std::optional<Manifest> m = ReadManifestOrNull(out / name);
    const bool recorded = m && m->parameters.recorded;
    const bool same_run =
        request_.sharded && recorded &&
        Difference(m->parameters, request_.parameters, SameRunScope::kShards).empty();
    if (same_run) continue;
    if (!request_.sharded && request_.mode == ReuseMode::kOverwrite) {
      run_files->push_back(name);  // replaced with the rest of the earlier run
      continue;
    }
    std::string why;
    if (recorded) why = Difference(m->parameters, request_.parameters, SameRunScope::kRun);
    throw UsageError(quoted + " holds another record run (" + name +
                     (why.empty() ? "" : ": " + why) + "): choose another --out" +
                     (request_.sharded ? "" : ", or pass --overwrite to replace it"));
  }
}

bool RunFolder::PlanRemovals(const fs::path& out, const std::string& quoted, const Listing& listing,
                             std::vector<std::string>* remove) {
  const std::vector<std::string>& run_files = listing.run_files;
  const std::vector<std::string>& hidden = listing.hidden;
  const bool has_manifest =
      std::find(run_files.begin(), run_files.end(), request_.manifest_name) != run_files.end();
  switch (request_.mode) {
    case ReuseMode::kRefuse:
      if (has_manifest) {
        // the episodes' files only: not the manifest, nor the report
        const long episode_files =
            std::count_if(run_files.begin(), run_files.end(), [](const std::string& n) {
              const std::optional<RunFileName> parsed = ParseRunFileName(n);
              return parsed && parsed->episode >= 0;
            });
        throw UsageError(quoted + " already holds a record run (" + request_.manifest_name +
                         " and " + std::to_string(episode_files) +
                         " episode files): pass --resume to continue it, --overwrite to replace "
                         "it, or choose another --out");
      }
      // a sharded run's own episodes without its manifest: an attempt that was killed (a
      // retried pod), recorded again; unsharded, they could be any run's
      if (!run_files.empty() && !request_.sharded) {
        throw UsageError(quoted + " holds files of a record run (" + Listed(run_files) +
                         ") without its manifest (killed before writing it): pass --resume to "
                         "record that run again, --overwrite to replace them, or choose another "
                         "--out");
      }
      *remove = run_files;
      remove->insert(remove->end(), hidden.begin(), hidden.end());
      break;
    case ReuseMode::kOverwrite:
      *remove = run_files;
      remove->insert(remove->end(), hidden.begin(), hidden.end());
      break;
    case ReuseMode::kResume:
      if (!has_manifest) {
        // nothing to resume (a requeued job that never started, say), or only the files of an
        // attempt killed before its manifest (fetchscope's, checked above): a fresh run
        CheckSameRunWithoutManifest(out, quoted, run_files);
        notice_ = "--resume: " + quoted + " holds no " + request_.manifest_name +
                  (run_files.empty() ? ": nothing to resume, recording the whole run"
                                     : " (an attempt killed before writing it left " +
                                           Listed(run_files) + "): recording the whole run");
        *remove = run_files;
        remove->insert(remove->end(), hidden.begin(), hidden.end());
        break;
      }
      return PlanResume(out, quoted, listing, remove);
  }
  return true;
}

bool RunFolder::PlanResume(const fs::path& out, const std::string& quoted, const Listing& listing,
                           std::vector<std::string>* remove) {
  std::error_code ec;
  const std::optional<Manifest> m = ReadManifestOrNull(out / request_.manifest_name);
  if (!m || !m->parameters.recorded) {
    throw UsageError("cannot --resume " + quoted + ": its " + request_.manifest_name +
                     " does not record the run's parameters (written by an older fetchscope, "
                     "or not a record manifest): pass --overwrite instead");
  }
  CheckResumable(quoted, m->parameters);
  std::set<int> done;
  for (const ManifestEpisode& e : m->episodes) {
    const int k = e.index;
    if (!e.complete.value_or(false) ||
        !std::binary_search(request_.episodes.begin(), request_.episodes.end(), k))
      continue;
    // its video, sheet and trajectory, and every other file it names, all there
    bool files = !e.video.empty() && (!e.sheet.empty() || request_.parameters.sheet_every < 0) &&
                 !e.trajectory.empty();
    for (const std::string& file : e.FileNames()) {
      files = files && fs::is_regular_file(out / file, ec);
    }
    if (!files) continue;
    kept_.push_back(e);
    done.insert(k);
  }
  todo_.clear();
  for (int k : request_.episodes) {
    if (!done.count(k)) todo_.push_back(k);
  }
  already_complete_ = todo_.empty() && !m->interrupted && m->missing.empty() &&
                      m->failures.empty() && m->episodes_requested == request_.parameters.episodes;
  if (already_complete_) {  // nothing to record, nothing to change
    // but the temporaries of an attempt killed after its manifest (writing its report)
    for (const std::string& name : listing.hidden) fs::remove(out / name, ec);
    committed_ = true;
    return false;
  }
  // the files of the episodes to redo go first (an incomplete one's); the manifest stays
  // until the new one replaces it, so that a failed --resume leaves the run resumable
  // (the report stays too: the new manifest's report replaces it)
  for (const std::string& name : listing.run_files) {
    const std::optional<RunFileName> parsed = ParseRunFileName(name);
    if (!parsed->manifest && !parsed->report && !done.count(parsed->episode)) {
      remove->push_back(name);
    }
  }
  remove->insert(remove->end(), listing.hidden.begin(), listing.hidden.end());
  return true;
}

void RunFolder::CheckResumable(const std::string& quoted, RunParameters theirs) const {
  if (theirs.episodes > request_.parameters.episodes) {
    throw UsageError("cannot --resume " + quoted + " with --episodes " +
                     std::to_string(request_.parameters.episodes) + ": the run there has " +
                     std::to_string(theirs.episodes) + "; pass --episodes " +
                     std::to_string(theirs.episodes) + ", or more to extend it");
  }
  theirs.episodes = request_.parameters.episodes;  // --resume may extend the run
  const std::string why = Difference(theirs, request_.parameters, SameRunScope::kRun);
  if (!why.empty()) {
    throw UsageError("cannot --resume " + quoted + " with other parameters: " + why +
                     "; pass the options of the run being resumed, or --overwrite to replace it");
  }
}

void RunFolder::PrepareFolder(const fs::path& out, const std::string& quoted,
                              const std::vector<std::string>& remove) {
  std::error_code ec;
  if (request_.mode == ReuseMode::kOverwrite) {
    SetAside(out, remove);
  } else {
    for (const std::string& name : remove) {
      fs::remove(out / name, ec);
      if (ec) throw RunError("cannot remove '" + (out / name).string() + "': " + ec.message());
    }
  }

  CreateOutputFolder(request_.out);
  if (!lock_.held()) {
    // made just now, by this run or by another one racing it: the lock decides, and the loser
    // leaves the folders alone (the winner may be writing in them)
    try {
      lock_ = FolderLock(out, LockKind(), "--out");
    } catch (...) {
      created_dirs_.clear();
      throw;
    }
  }
  if (!created_dirs_.empty()) {
    try {
      CheckWritable(out, quoted);
    } catch (...) {
      for (const fs::path& dir : created_dirs_) fs::remove(dir, ec);
      throw;
    }
  }
  for (const auto& entry : fs::directory_iterator(out, ec)) {
    before_.insert(entry.path().filename().string());
  }
}

namespace {

// A manifest that is not JSON at all (cut short, or damaged) is not a user's file under our name:
// say so, with where the JSON breaks, rather than "not written by fetchscope".
void RefuseBrokenManifest(const fs::path& path, const std::string& quoted) {
  std::string text;
  try {
    text = ReadFileCapped(path, kMaxJsonFileBytes);  // UsageError: a FIFO, a device, huge
  } catch (const RunError& e) {
    throw UsageError(quoted + " holds " + path.filename().string() + ", which cannot be read (" +
                     e.what() +
                     "): restore it, remove it to start afresh, or choose another --out");
  }
  try {
    const nlohmann::json parsed = nlohmann::json::parse(text);
    (void)parsed;
  } catch (const nlohmann::json::parse_error& e) {
    const bool cut = e.byte >= text.size();
    throw UsageError(quoted + " holds " + path.filename().string() + ", which is " +
                     (cut ? "truncated (its JSON ends at byte " + std::to_string(text.size()) +
                                " before it is complete)"
                          : "not valid JSON (at byte " + std::to_string(e.byte) + " of " +
                                std::to_string(text.size()) + ")") +
                     ": restore it, remove it to start afresh, or choose another --out");
  }
}

}  // namespace

void RunFolder::RefuseForeignFiles(const fs::path& out, const std::string& quoted,
                                   std::vector<std::string>* run_files,
                                   const std::vector<std::string>& manifests) const {
  // what the record manifests in the folder list is fetchscope's, and so are they
  std::set<std::string> listed;
  std::vector<std::string> names = manifests;
  names.insert(names.end(), run_files->begin(), run_files->end());
  for (const std::string& name : names) {
    if (!IsManifestFileName(name)) continue;
    const std::optional<Manifest> m = ReadManifestOrNull(out / name);
    if (!m) {
      RefuseBrokenManifest(out / name, quoted);
      continue;
    }
    listed.insert(name);
    for (const ManifestEpisode& e : m->episodes) {
      for (const std::string& file : e.FileNames()) listed.insert(file);
    }
  }
  std::vector<std::string> foreign;
  std::set<std::string> left_alone;
  std::map<int, bool> videos;  // episode -> it has a video with fetchscope's tags (looked up once)
  for (const std::string& name : names) {
    const RunFileName parsed = *ParseRunFileName(name);
    bool ours = listed.count(name) > 0;
    if (!ours && parsed.report) {
      ours = IsFetchscopeReport(out / name);
      if (!ours && !request_.report) {  // never written, never removed: the user's page stays
        left_alone.insert(name);
        continue;
      }
    }
    // an episode of an attempt killed before its manifest: beside its fetchscope trajectory, or
    // (killed before the trajectory was written) a video with fetchscope's tags for that episode,
    // or a file beside one (its sheet, layers, a trajectory cut short)
    if (!ours && parsed.episode >= 0) {
      ours = IsFetchscopeTrajectory(out / EpisodeTrajectoryFileName(parsed.episode)) ||
             EpisodeHasFetchscopeVideo(out, parsed.episode, names, &videos);
    }
    if (!ours) foreign.push_back(name);
  }
  if (!foreign.empty()) {
    std::sort(foreign.begin(), foreign.end());
    // a user's own index.html is the one such file a run can leave alone: --no-report
    const bool only_report = std::all_of(foreign.begin(), foreign.end(), [](const std::string& n) {
      const std::optional<RunFileName> parsed = ParseRunFileName(n);
      return parsed && parsed->report;
    });
    throw UsageError(quoted + " holds " + Listed(foreign) +
                     ", not written by fetchscope, under names a run writes (--overwrite removes "
                     "only fetchscope's files): move them out of " +
                     quoted + (only_report ? ", pass --no-report to leave it alone" : "") +
                     ", or choose another --out");
  }
  run_files->erase(std::remove_if(run_files->begin(), run_files->end(),
                                  [&](const std::string& n) { return left_alone.count(n) > 0; }),
                   run_files->end());
}

void RunFolder::CheckSameRunWithoutManifest(const fs::path& out, const std::string& quoted,
                                            const std::vector<std::string>& run_files) const {
  const RunParameters& p = request_.parameters;
  std::set<int> checked;
  for (const std::string& name : run_files) {
    const std::optional<RunFileName> parsed = ParseRunFileName(name);
    if (!parsed || parsed->episode < 0 || !checked.insert(parsed->episode).second) continue;
    const int k = parsed->episode;
    // its trajectory, or (killed before that) a video titled as this run titles episode k
    const fs::path trajectory = out / EpisodeTrajectoryFileName(k);
    nlohmann::json j;
    try {  // never a FIFO, a device or a huge file: those are no trajectory of this run
      j = nlohmann::json::parse(ReadFileCapped(trajectory, kMaxJsonFileBytes), nullptr, false);
    } catch (const std::exception&) {
      j = nullptr;
    }
    bool same = false;
    if (j.is_object() && j.contains("env_id") && j.contains("seed") && j.contains("policy")) {
      same = j["env_id"] == p.env_id && j["seed"] == p.seed && j["policy"] == p.policy;
    } else {
      const std::string title = p.env_id + " seed " + std::to_string(p.seed) + " episode " +
                                std::to_string(k) + " (" + p.policy + ")";
      for (const std::string& other : run_files) {
        const std::optional<RunFileName> o = ParseRunFileName(other);
        if (!same && o && o->episode == k && IsVideoFileName(other)) {
          same = IsFetchscopeVideo(out / other, k, title);
        }
      }
    }
    if (!same) {
      throw UsageError("cannot --resume " + quoted + ": it holds files of another record run (" +
                       EpisodeStem(k) + " is not of --env-id " + p.env_id + " --seed " +
                       std::to_string(p.seed) + " --policy " + p.policy + ") without its " +
                       request_.manifest_name +
                       ": pass --overwrite to replace them, or choose "
                       "another --out");
    }
  }
}

void RunFolder::SetAside(const fs::path& out, const std::vector<std::string>& names) {
  if (names.empty()) return;
  std::error_code ec;
  fs::create_directory(aside_, ec);
  if (ec) {
    throw RunError("cannot make '" + aside_.string() +
                   "' to set the earlier run aside: " + ec.message());
  }
  for (const std::string& name : names) {
    fs::rename(out / name, aside_ / name, ec);
    if (ec) {
      const std::string why = ec.message();
      Restore();
      throw RunError(
          "cannot move '" + (out / name).string() +
          "' aside (--overwrite keeps the earlier run until the new one is written): " + why);
    }
    set_aside_.push_back(name);
  }
}

std::vector<ManifestEpisode> RunFolder::WithKept(std::vector<ManifestEpisode> entries) const {
  entries.insert(entries.end(), kept_.begin(), kept_.end());
  std::sort(entries.begin(), entries.end(),
            [](const ManifestEpisode& a, const ManifestEpisode& b) { return a.index < b.index; });
  return entries;
}

void RunFolder::Commit() {
  committed_ = true;
  std::error_code ec;
  if (!set_aside_.empty()) fs::remove_all(aside_, ec);  // the earlier run, replaced
  set_aside_.clear();
  for (const fs::path& stale : stale_aside_) fs::remove_all(stale, ec);
}

void RunFolder::Restore() noexcept {
  std::error_code ec;
  if (set_aside_.empty()) {
    fs::remove(aside_, ec);  // made, nothing in it yet (only when empty)
    return;
  }
  const fs::path out = aside_.parent_path();
  bool all_back = true;
  for (const std::string& name : set_aside_) {
    fs::rename(aside_ / name, out / name, ec);
    all_back = all_back && !ec;
  }
  set_aside_.clear();
  if (all_back) {
    fs::remove(aside_, ec);
  } else {
    std::fprintf(stderr,
                 "fetchscope: warning: could not put every file of the earlier run back "
                 "from '%s'; the rest is still there\n",
                 aside_.string().c_str());
  }
}

RunFolder::~RunFolder() {
  if (!committed_) {
    Cleanup();
    Restore();
  }
}

void RunFolder::Cleanup() noexcept {
  try {
    const fs::path out = request_.out.empty() ? fs::path(".") : fs::path(request_.out);
    std::error_code ec;
    std::vector<fs::path> remove;
    for (const auto& entry : fs::directory_iterator(out, ec)) {
      const std::string name = entry.path().filename().string();
      if (!before_.count(name) && Ours(name)) remove.push_back(entry.path());
    }
    for (const fs::path& p : remove) fs::remove(p, ec);
    for (const fs::path& dir : created_dirs_) fs::remove(dir, ec);  // only when empty again
  } catch (...) {
    // best effort: the error that is being reported matters more
  }
}

}  // namespace fetchscope
