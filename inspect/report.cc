// fetchscope report DIR: one self-contained HTML page for a record run (provenance, a sortable
// episode table, every episode's video, contact sheet and trajectory, distance-to-goal curves,
// a histogram of returns, the success rate with its Wilson interval). Written by `record` (unless
// --no-report) and `merge-manifests` too. The page is drawn in the browser by web/src/report.js
// from the JSON this file computes; everything numeric is computed here, once.
#include "inspect/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>

#include "base/atomic_file.h"
#include "base/confined_file.h"
#include "base/errors.h"
#include "base/json_util.h"
#include "encode/video_format.h"
#include "inspect/html_page.h"
#include "inspect/run_confinement.h"
#include "inspect/viewer.h"
#include "render/overlay.h"
#include "run/run_files.h"
#include "run/run_folder.h"
#include "run/run_summary.h"
#include "src/env_spec.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Rounded for plotting: a micrometre is far below what a plot shows, and keeps the page small.
json Micro(double value) {
  if (!std::isfinite(value)) return JsonDouble(value);
  return std::round(value * 1e6) / 1e6;
}

std::string EpisodeLabel(int k) {
  char text[32];
  std::snprintf(text, sizeof(text), "%03d", k);
  return text;
}

// Distinct non-empty values, in first-seen order.
void AddUnique(std::vector<std::string>* list, const std::string& value) {
  if (value.empty()) return;
  if (std::find(list->begin(), list->end(), value) == list->end()) list->push_back(value);
}

std::string Join(const std::vector<std::string>& items, const char* separator) {
  std::string out;
  for (size_t i = 0; i < items.size(); ++i) out += (i ? separator : "") + items[i];
  return out;
}

// A typed manifest member as text: "" when absent.
std::string Str(const std::optional<std::string>& value) { return value.value_or(""); }
std::string Str(const std::optional<int>& value) {
  return value ? std::to_string(*value) : std::string();
}

std::string Str(const json& j, const char* pointer) {
  const json::json_pointer p(pointer);
  if (!j.contains(p)) return "";
  const json& v = j.at(p);
  if (v.is_string()) return v.get<std::string>();
  if (v.is_null()) return "";
  return v.dump();
}

// "device (renderer)" of every worker that reported, for a plain or merged manifest.
std::vector<std::string> GlDevices(const Manifest& manifest) {
  std::vector<std::string> devices;
  auto add_workers = [&](const std::vector<ManifestWorker>& workers) {
    for (const ManifestWorker& w : workers) {
      std::string device = Str(w.device);
      const std::string renderer = Str(w.gl_renderer);
      if (!renderer.empty()) device += (device.empty() ? "" : " — ") + renderer;
      AddUnique(&devices, device);
    }
  };
  add_workers(manifest.workers);
  for (const json& shard : manifest.shards) {
    const auto workers = shard.find("workers");
    if (workers == shard.end() || !workers->is_array()) continue;
    try {
      add_workers(ManifestWorkersFromJson(*workers));
    } catch (const ManifestError&) {
      // a shard record whose workers are not worker entries: no devices from it
    }
  }
  if (devices.empty()) {  // older manifests: the backend block only
    AddUnique(&devices, Str(manifest.backend.device) + " " + Str(manifest.backend.gl_renderer));
  }
  return devices;
}

// A video of the format table's, or of another container a manifest may name
bool IsVideoFile(const std::string& name) {
  if (IsVideoFileName(name)) return true;
  const std::string ext = fs::path(name).extension().string();
  return ext == ".mkv" || ext == ".mov" || ext == ".avi";
}

void CollectVideoFiles(const json& j, std::set<std::string>* files) {
  if (j.is_string()) {
    if (IsVideoFile(j.get<std::string>())) files->insert(j.get<std::string>());
  } else if (j.is_structured()) {
    for (const json& child : j) CollectVideoFiles(child, files);
  }
}

// ", formats mp4, gif (gif: 10 frames/s, 320 px wide)" when record --format chose more or other
// than mp4; "" otherwise
std::string FormatsText(const Manifest& m) {
  if (!m.video.formats) return "";
  const std::vector<std::string>& names = *m.video.formats;
  // the default --format alone (the table's first row) goes unmentioned
  if (names.size() == 1 && names.front() == VideoFormats().front().name) return "";
  std::string text = ", formats " + Join(names, ", ");
  if (HasPaletteFormat(names)) {
    const ManifestVideoGif gif = m.video.gif.value_or(ManifestVideoGif{});
    text += " (gif: " + Str(gif.fps) + " frames/s, " + Str(gif.width) + " px wide at most)";
  }
  return text;
}

}  // namespace

std::vector<std::string> OtherEpisodeVideos(const ManifestEpisode& entry) {
  std::set<std::string> files;
  CollectVideoFiles(ManifestEpisodeToJson(entry), &files);
  for (const EpisodeVideo& v : EpisodeVideos(entry)) files.erase(v.file);
  return {files.begin(), files.end()};
}

const EpisodeVideo* PlayableVideo(const std::vector<EpisodeVideo>& videos, const fs::path& dir) {
  for (const EpisodeVideo& v : videos) {
    std::error_code ec;
    if (fs::is_regular_file(dir / v.file, ec)) return &v;
  }
  return nullptr;
}

json RunProvenance(const RecordedRun& run) {
  const Manifest& m = run.manifest;
  json rows = json::array();
  auto row = [&](const std::string& label, const std::string& value) {
    if (!value.empty()) rows.push_back({{"label", label}, {"value", value}});
  };
  row("env", m.env_id);
  row("seed", std::to_string(m.seed));
  row("policy", m.policy);
  row("episodes", std::to_string(run.recorded.size()) + " recorded of " +
                      std::to_string(run.expected.size()) + ", " +
                      std::to_string(m.steps_per_episode) + " steps each");
  std::string assets = Str(m.assets, "/kind");
  if (!Str(m.assets, "/origin").empty()) assets += " (" + Str(m.assets, "/origin") + ")";
  row("assets", assets + " " + Str(m.assets, "/path"));
  row("assets sha256", Str(m.assets, "/sha256"));
  const ManifestVideo& v = m.video;
  std::string encoder = Str(v.codec);
  if (!Str(v.codec_reason).empty()) encoder += " — " + Str(v.codec_reason);
  row("encoder", encoder);
  row("video", Str(v.width) + "×" + Str(v.height) + " at " + Str(v.fps) + " frames/s, crf " +
                   Str(v.crf) + ", preset " + Str(v.preset) + FormatsText(m));
  row("GL backend", Str(m.backend.name) + " " + Str(m.backend.gl_version));
  row(GlDevices(m).size() > 1 ? "GL devices" : "GL device", Join(GlDevices(m), "; "));
  row("GPU choice", Str(m.gpu.choice));
  row("camera", m.camera);
  row("overlay", m.overlay);
  row("MSAA", std::to_string(m.msaa) + (m.msaa_reason.empty() ? "" : " (" + m.msaa_reason + ")"));
  std::vector<std::string> versions;
  AddUnique(&versions, Str(m.versions, "/fetchscope"));
  for (const json& shard : m.shards) AddUnique(&versions, Str(shard, "/versions/fetchscope"));
  row("fetchscope version", Join(versions, ", ") + " (MuJoCo " + Str(m.versions, "/mujoco") + ")");
  if (m.merged) {
    row("shards", std::to_string(m.shards.size()) + " merged by merge-manifests");
  } else {
    row("jobs", std::to_string(m.jobs) + " (" + m.worker_mode + ")");
  }
  if (m.interrupted) row("interrupted", "by " + m.signal.value_or(""));
  // record --from: the run that was re-rendered (its trajectories replayed)
  if (!m.from.value_or("").empty()) row("from", "re-rendered from " + *m.from);
  if (m.merged) {
    // a merged run: the shards' record commands, and the merge that made this manifest
    std::vector<std::string> records;
    for (const json& shard : m.shards) AddUnique(&records, Str(shard, "/command_line"));
    constexpr size_t kShown = 8;
    const size_t all = records.size();
    if (all > kShown) {
      records.resize(kShown);
      records.push_back("... (" + std::to_string(all) + " in all)");
    }
    row(all > 1 ? "record commands" : "record command", Join(records, "\n"));
    row("merge command", m.command_line);
  } else {
    row("command", m.command_line);
  }
  return rows;
}

namespace {

// Bins for the histogram of returns: about sqrt(n) equal bins (5..20) over the range.
json Histogram(const std::vector<double>& values) {
  std::vector<double> finite;
  for (double v : values) {
    if (std::isfinite(v)) finite.push_back(v);
  }
  json out = {{"centres", json::array()}, {"counts", json::array()}, {"width", 1.0}};
  if (finite.empty()) return out;
  const auto [lo_it, hi_it] = std::minmax_element(finite.begin(), finite.end());
  double lo = *lo_it, hi = *hi_it;
  int bins = std::clamp(static_cast<int>(std::ceil(std::sqrt(finite.size()))), 5, 20);
  if (hi - lo < 1e-12) {
    lo -= 0.5;
    hi += 0.5;
    bins = 1;
  }
  const double width = (hi - lo) / bins;
  std::vector<int> counts(bins, 0);
  for (double v : finite) counts[std::min(bins - 1, static_cast<int>((v - lo) / width))]++;
  for (int b = 0; b < bins; ++b) {
    out["centres"].push_back(lo + (b + 0.5) * width);
    out["counts"].push_back(counts[b]);
  }
  out["width"] = width;
  return out;
}

}  // namespace

RecordedRun ReadRunManifest(const fs::path& manifest_path) {
  std::error_code ec;
  {  // the manifest itself: inside its folder, a regular file
    const fs::path dir = manifest_path.parent_path().empty() ? "." : manifest_path.parent_path();
    const std::string name = manifest_path.filename().string();
    const std::string named_by = "the run folder " + Quoted(dir.string()) + " holds";
    RequireRegularIfPresent(ResolveInside(dir, name, named_by), name, named_by);
  }
  if (!fs::is_regular_file(manifest_path, ec)) {
    throw UsageError("no manifest '" + manifest_path.string() +
                     "': give the folder of a record run (record --out DIR)");
  }
  RecordedRun run;
  run.manifest_path = manifest_path;
  run.dir = manifest_path.parent_path().empty() ? fs::path(".") : manifest_path.parent_path();
  try {
    run.manifest = ReadManifest(manifest_path);
  } catch (const ManifestError& e) {
    throw UsageError(e.what());  // a folder that is not a record run: the user's mistake
  }
  run.folders = RunFolders(run.dir, run.manifest);
  CheckNamedFiles(run);
  const Manifest& m = run.manifest;
  // the episodes asked for: a shard's own, else all of them
  if (m.shard && m.shard->count > 1 && m.shard->episodes) {
    run.expected = *m.shard->episodes;
  } else {
    for (int k = 0; k < m.episodes_requested; ++k) run.expected.push_back(k);
  }
  for (const ManifestEpisode& e : m.episodes) run.recorded[e.index] = e;
  for (const ManifestFailure& f : m.failures) {
    for (int k : f.episodes) run.failed[k] = f.message;
  }
  return run;
}

RecordedRun ReadRunFolder(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw UsageError("'" + dir +
                     "' is not a folder: give the folder of a record run (record --out DIR)");
  }
  const fs::path manifest = fs::path(dir) / kManifestFileName;
  if (!fs::exists(manifest, ec)) {
    int shards = 0;
    for (const auto& entry : fs::directory_iterator(dir, ec)) {
      shards += IsShardManifestFileName(entry.path().filename().string());
    }
    if (shards > 0) {
      throw UsageError("no manifest.json in '" + dir + "' but " + std::to_string(shards) +
                       " shard manifest(s): run `fetchscope merge-manifests " + dir + "` first");
    }
    throw UsageError("no manifest.json in '" + dir +
                     "': give the folder of a record run (record --out DIR)");
  }
  return ReadRunManifest(manifest);
}

std::vector<TrajectoryStep> ReadEpisodeTrajectory(const fs::path& path) {
  Trajectory trajectory = ReadTrajectory(path.string());
  if (trajectory.episodes.empty()) throw RunError(path.string() + ": holds no episode");
  return std::move(trajectory.episodes.front().steps);
}

double GoalDistance(const TrajectoryStep& step) {
  return fetchscope::GoalDistance(step.obs.achieved_goal, step.obs.desired_goal);
}

namespace {

// What the report sums up over the recorded episodes while it lists them.
struct EpisodeTally {
  json notes = json::array();   // what is missing, in episode order
  std::vector<double> returns;  // of the complete episodes
  int incomplete = 0;
  bool has_hindsight = false;
  bool has_look = false;    // --randomize: episodes drawn with a look
  bool has_replay = false;  // record --from DATASET
};

// Episode k's videos (every format record wrote, linked by its name; the page shows the one a
// browser plays best), its --layers videos and legends, and any other video its entry names.
void AddEpisodeVideos(const RecordedRun& run, int k, const ManifestEpisode& entry, json* e,
                      EpisodeTally* tally) {
  json& notes = tally->notes;
  const std::vector<EpisodeVideo> videos = EpisodeVideos(entry);
  json video_list = json::array();
  for (const EpisodeVideo& v : videos) {
    if (fs::is_regular_file(run.dir / v.file)) {
      video_list.push_back({{"format", v.format}, {"file", v.file}, {"frames", v.frames}});
    } else {
      notes.push_back("episode " + EpisodeLabel(k) + ": " + v.format + " video '" + v.file +
                      "' is missing");
    }
  }
  const EpisodeVideo* shown = PlayableVideo(videos, run.dir);
  (*e)["video"] = shown ? json(shown->file) : json(nullptr);
  (*e)["video_format"] = shown ? json(shown->format) : json(nullptr);
  // the format row's flag, so that pages never compare names: an image (gif, apng) has no seeking
  const VideoFormat* row = shown ? FindVideoFormat(shown->format) : nullptr;
  (*e)["video_image"] = row != nullptr && row->image;
  (*e)["videos"] = std::move(video_list);
  // record --layers: per layer ("depth", "segmentation") its videos and legend, linked
  json layers = json::array();
  std::set<std::string> layer_files;
  for (const auto& [name, layer] : entry.layers) {
    json layer_videos = json::array();
    for (const EpisodeVideo& v : EpisodeVideos(layer)) {
      layer_files.insert(v.file);
      if (fs::is_regular_file(run.dir / v.file)) {
        layer_videos.push_back({{"format", v.format}, {"file", v.file}, {"frames", v.frames}});
      } else {
        notes.push_back("episode " + EpisodeLabel(k) + ": " + name + " video '" + v.file +
                        "' is missing");
      }
    }
    json legend = nullptr;
    if (!layer.legend.empty() && fs::is_regular_file(run.dir / layer.legend)) {
      legend = layer.legend;
    }
    layers.push_back({{"name", name}, {"videos", std::move(layer_videos)}, {"legend", legend}});
  }
  (*e)["layers"] = std::move(layers);
  // any other video the entry names: linked
  json others = json::array();
  for (const std::string& file : OtherEpisodeVideos(entry)) {
    if (layer_files.count(file)) continue;
    if (fs::is_regular_file(run.dir / file)) {
      others.push_back(file);
    } else {
      notes.push_back("episode " + EpisodeLabel(k) + ": video '" + file + "' is missing");
    }
  }
  (*e)["other_videos"] = std::move(others);
}

// Episode k's sheet and trajectory (null when missing), hindsight counts, replay drift and
// distances to the goal.
void AddEpisodeDetails(const RecordedRun& run, int k, const ManifestEpisode& entry, json* e,
                       EpisodeTally* tally) {
  for (const auto& [kind, file] : {std::pair<const char*, const std::string&>{"sheet", entry.sheet},
                                   {"trajectory", entry.trajectory}}) {
    (*e)[kind] = file;
    if (!file.empty() && !fs::is_regular_file(run.dir / file)) {
      tally->notes.push_back("episode " + EpisodeLabel(k) + ": " + kind + " '" + file +
                             "' is missing");
      (*e)[kind] = nullptr;
    }
  }
  if (entry.hindsight) {
    (*e)["hindsight"] = EpisodeHindsightToJson(*entry.hindsight);
    tally->has_hindsight = true;
  }
  if (const auto look = entry.extra.find("look"); look != entry.extra.end() && look->is_object()) {
    (*e)["look"] = *look;  // --randomize's draw: the table and the viewer say it
    // its 64-bit seed as text: a page's numbers are doubles
    (*e)["look_seed"] = look->contains("seed") ? look->at("seed").dump() : "";
    tally->has_look = true;
  }
  // record --from DATASET: the reset used and how far the replay drifted from the dataset
  const auto divergence = entry.extra.find("divergence");
  if (divergence != entry.extra.end() && divergence->is_object()) {
    (*e)["replay"] = *divergence;
    (*e)["replay"]["reset"] = entry.extra.value("reset", "");
    tally->has_replay = true;
  }
  json distances = json::array();
  (*e)["final_distance"] = nullptr;
  if ((*e)["trajectory"].is_string()) {
    try {
      const std::vector<TrajectoryStep> steps =
          ReadEpisodeTrajectory(run.dir / (*e)["trajectory"].get<std::string>());
      for (const TrajectoryStep& s : steps) distances.push_back(Micro(GoalDistance(s)));
      if (!steps.empty()) (*e)["final_distance"] = JsonDouble(GoalDistance(steps.back()));
    } catch (const RunError& error) {
      tally->notes.push_back(std::string("episode ") + EpisodeLabel(k) + ": " + error.what());
    }
  }
  (*e)["distances"] = std::move(distances);
}

// The table row of episode k: missing (with why), or recorded (with its outcome and files).
json EpisodeRow(const RecordedRun& run, int k, EpisodeTally* tally) {
  const auto it = run.recorded.find(k);
  json e = {{"index", k}, {"label", EpisodeLabel(k)}};
  if (it == run.recorded.end()) {
    e["status"] = "missing";
    const auto failure = run.failed.find(k);
    e["reason"] = failure != run.failed.end() ? failure->second
                  : run.manifest.interrupted  ? "not recorded: the run was interrupted"
                                              : "not recorded";
    return e;
  }
  const ManifestEpisode& entry = it->second;
  const int length = entry.steps.value_or(0);
  const bool complete = entry.complete.value_or(true);  // older manifests: no flag, complete
  e["status"] = complete ? "ok" : "incomplete";
  e["complete"] = complete;
  e["success"] = entry.is_success;
  e["return"] = entry.episode_return ? JsonDouble(*entry.episode_return) : json(nullptr);
  // an interrupted episode's return covers only the steps it made: aggregates leave it out
  if (complete && entry.episode_return && std::isfinite(*entry.episode_return)) {
    tally->returns.push_back(*entry.episode_return);
  }
  tally->incomplete += !complete;
  e["length"] = length;
  e["frames"] = entry.frames.value_or(length + 1);
  AddEpisodeVideos(run, k, entry, &e, tally);
  AddEpisodeDetails(run, k, entry, &e, tally);
  return e;
}

// The success rate over the complete episodes, in index order, with its Wilson interval as it
// grows; `n` and `successes` the totals.
json RunningSuccess(const json& episodes, int* n, int* successes) {
  json running = {{"n", json::array()},
                  {"rate", json::array()},
                  {"low", json::array()},
                  {"high", json::array()}};
  for (const json& e : episodes) {
    if (e["status"] != "ok") continue;
    ++*n;
    *successes += e["success"].get<bool>();
    const auto [low, high] = WilsonInterval(*successes, *n);
    running["n"].push_back(*n);
    running["rate"].push_back(static_cast<double>(*successes) / *n);
    running["low"].push_back(low);
    running["high"].push_back(high);
  }
  return running;
}

// The markers the frames show, in their colours (the viewer's and the sheets' legend); the
// ghost where the run replayed a dataset.
json OverlayLegendJson(const Manifest& m, bool has_replay) {
  json overlay_legend = json::array();
  try {
    const OverlaySet overlays = ParseOverlays(m.overlay.empty() ? "default" : m.overlay);
    for (const OverlayLegendEntry& entry : OverlayLegend(overlays, has_replay)) {
      overlay_legend.push_back(
          {{"name", entry.name}, {"color", entry.color}, {"meaning", entry.meaning}});
    }
  } catch (const std::exception&) {
    // an --overlay this build does not know: no legend
  }
  return overlay_legend;
}

// The provenance rows, with the re-rendered run's own page linked where the path record --from
// was given still finds one.
json LinkedProvenance(const RecordedRun& run) {
  json provenance = RunProvenance(run);
  for (json& row : provenance) {
    if (row["label"] != "from") continue;
    std::error_code ec;
    fs::path source = run.manifest.from.value_or("");
    if (fs::is_directory(source, ec)) source /= kReportFileName;
    if (fs::is_regular_file(source, ec)) {
      row["href"] = fs::absolute(source)
                        .lexically_normal()
                        .lexically_relative(fs::absolute(run.dir).lexically_normal())
                        .string();
    }
  }
  return provenance;
}

}  // namespace

json ReportData(const RecordedRun& run) {
  const Manifest& m = run.manifest;
  double threshold = 0.05;
  try {
    threshold = FindEnvSpec(m.env_id).distance_threshold;
  } catch (const std::exception&) {
    // an env this build does not know: Fetch's 0.05 m
  }
  EpisodeTally tally;
  json episodes = json::array();
  std::set<int> all(run.expected.begin(), run.expected.end());
  for (const auto& [k, entry] : run.recorded) all.insert(k);
  for (int k : all) episodes.push_back(EpisodeRow(run, k, &tally));
  int n = 0, successes = 0;
  json running = RunningSuccess(episodes, &n, &successes);
  const auto [low, high] = WilsonInterval(successes, n);
  const int missing = static_cast<int>(all.size()) - static_cast<int>(run.recorded.size());
  // how to finish the run: its own command with --resume (a merged run: each shard's)
  const std::string resume = m.command_line.empty() || m.merged
                                 ? "; record them with --resume (the run's record command)"
                                 : "; to record them, run: " + ResumeCommand(m.command_line);
  json& notes = tally.notes;
  if (m.interrupted) {
    notes.insert(notes.begin(), "the run was interrupted by " + m.signal.value_or("") + ": " +
                                    std::to_string(missing) + " episode(s) missing, " +
                                    std::to_string(tally.incomplete) + " incomplete" + resume);
  } else if (missing > 0) {
    notes.insert(notes.begin(),
                 std::to_string(missing) + " episode(s) missing (see the table)" + resume);
  }
  return {{"kind", "report"},
          {"title", m.env_id + " · " + m.policy + " · seed " + std::to_string(m.seed)},
          {"generator", std::string("fetchscope ") + FETCHSCOPE_VERSION},
          {"uplot", EmbeddedUplotVersion()},
          {"provenance", LinkedProvenance(run)},
          {"notes", notes},
          {"threshold", threshold},
          {"steps_per_episode", m.steps_per_episode},
          {"fps", m.video.fps.value_or(25)},
          {"has_hindsight", tally.has_hindsight},
          {"has_replay", tally.has_replay},
          {"has_look", tally.has_look},
          {"overlay_legend", OverlayLegendJson(m, tally.has_replay)},
          {"episodes", std::move(episodes)},
          {"summary",
           {{"expected", all.size()},
            {"recorded", run.recorded.size()},
            {"complete", n},
            {"incomplete", tally.incomplete},
            {"successes", successes},
            {"rate", n ? JsonDouble(static_cast<double>(successes) / n) : json(nullptr)},
            {"wilson_low", low},
            {"wilson_high", high},
            {"confidence", 0.95}}},
          {"running_success", std::move(running)},
          {"returns_histogram", Histogram(tally.returns)}};  // complete episodes only
}

fs::path WriteRunReport(const RecordedRun& run) {
  json data = ReportData(run);
  // the episode viewer: per-step signals, parsed by the page when an episode's view opens
  const std::vector<PageBlock> blocks = AddEpisodeViewers(run.dir, run.manifest, &data);
  const fs::path out = run.dir / kReportFileName;
  std::error_code ec;
  if (fs::exists(out, ec) && !IsFetchscopeReport(out)) {  // the user's own page: never replaced
    throw UsageError("'" + out.string() +
                     "' is not a report fetchscope wrote (no generator tag): move it elsewhere "
                     "for the run's report to be written there");
  }
  WriteFileAtomically(
      out.string(),
      HtmlPage(PageKind::kReport, "fetchscope report: " + data["title"].get<std::string>(), data,
               blocks));
  return out;
}

void WriteRunReportOrWarn(const fs::path& manifest_path, bool quiet) {
  try {
    const fs::path page = WriteRunReport(ReadRunManifest(manifest_path));
    if (!quiet) std::fprintf(stderr, "report: %s\n", page.string().c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr,
                 "fetchscope: warning: the run is recorded but its report was not written: %s\n",
                 e.what());
  }
}

}  // namespace fetchscope
