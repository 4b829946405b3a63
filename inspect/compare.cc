// Two record runs of the same episodes side by side: per episode the states step by step and the
// frames as A | B | heat map, then compare.json and the page (see inspect/compare.h).
#include "inspect/compare.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <optional>
#include <set>

#include "base/atomic_file.h"
#include "base/errors.h"
#include "base/json_util.h"
#include "encode/video_format.h"
#include "encode/video_reader.h"
#include "encode/video_writer.h"
#include "inspect/html_page.h"
#include "inspect/report.h"
#include "inspect/viewer.h"
#include "render/text.h"
#include "run/manifest.h"
#include "run/run_files.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
// report and the HTML pages are still in namespace cli

std::string EpisodeName(int k) {
  char text[32];
  std::snprintf(text, sizeof(text), "%03d", k);
  return text;
}

std::string IndexList(const std::map<int, ManifestEpisode>& episodes) {
  std::string out;
  for (const auto& [k, e] : episodes) out += (out.empty() ? "" : ",") + std::to_string(k);
  return out.empty() ? "none" : out;
}

// The state compared at a step: observation, achieved goal and desired goal, in that order.
std::vector<double> StateVector(const TrajectoryStep& step) {
  std::vector<double> v = step.obs.observation;
  v.insert(v.end(), step.obs.achieved_goal.begin(), step.obs.achieved_goal.end());
  v.insert(v.end(), step.obs.desired_goal.begin(), step.obs.desired_goal.end());
  return v;
}

// The amplification of the heat map (HeatColour), as its panel label says.
constexpr int kHeatGain = 4;

// Colour of a difference of `d` (0..255) in the heat map: black for none, then through dark
// purple, red and orange to pale yellow (matplotlib's "inferno" at 5 anchors), 4x amplified so
// that a few levels of difference are visible.
void HeatColour(int d, uint8_t* rgb) {
  static constexpr uint8_t kAnchors[5][3] = {
      {0, 0, 4}, {87, 16, 110}, {188, 55, 84}, {249, 142, 9}, {252, 255, 164}};
  if (d == 0) {
    rgb[0] = rgb[1] = rgb[2] = 0;
    return;
  }
  const double x = std::min(1.0, kHeatGain * d / 255.0) * 4.0;
  const int i = std::min(3, static_cast<int>(x));
  const double f = x - i;
  for (int c = 0; c < 3; ++c) {
    rgb[c] = static_cast<uint8_t>(
        std::lround(kAnchors[i][c] + f * (kAnchors[i + 1][c] - kAnchors[i][c])));
  }
}

struct PixelStats {
  int max = 0;          // largest channel difference in the frame
  double mean = 0;      // mean of the per-pixel largest channel difference
  double fraction = 0;  // pixels whose difference exceeds the pixel tolerance
};

// Writes A | B | heat map into `out` (3w x h RGB24 rows) and measures the difference.
PixelStats SideBySide(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b, int w, int h,
                      int tolerance, uint8_t* side) {
  PixelStats stats;
  long long sum = 0, over = 0;
  for (int y = 0; y < h; ++y) {
    const uint8_t* pa = &a[static_cast<size_t>(y) * w * 3];
    const uint8_t* pb = &b[static_cast<size_t>(y) * w * 3];
    uint8_t* out = side + static_cast<size_t>(y) * w * 9;
    std::copy(pa, pa + w * 3, out);
    std::copy(pb, pb + w * 3, out + w * 3);
    uint8_t* heat = out + w * 6;
    for (int x = 0; x < w; ++x) {
      int d = 0;
      for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(pa[x * 3 + c] - pb[x * 3 + c]));
      HeatColour(d, heat + x * 3);
      stats.max = std::max(stats.max, d);
      sum += d;
      over += d > tolerance;
    }
  }
  const double pixels = static_cast<double>(w) * h;
  stats.mean = sum / pixels;
  stats.fraction = over / pixels;
  return stats;
}

// The strip above the side-by-side frames that names the three panels: `labels` (A, B, heat
// map), each in its third of a 3w-wide strip, sized to the frame height `h`. Its height is even
// (yuv420p) and its rows are RGB24.
std::vector<uint8_t> LabelStrip(const std::string (&labels)[3], int w, int h, int* strip_height) {
  const Font& font = Font::Default();
  const int pixels = std::clamp(h / 16, 9, 24);
  const int pad = std::max(2, pixels / 4);
  const TextMetrics m = font.Measure("Ag", pixels);
  *strip_height = (m.ascent + m.descent + 2 * pad + 1) & ~1;
  const int width = 3 * w;
  std::vector<uint8_t> strip(static_cast<size_t>(width) * *strip_height * 3, 40);
  TextStyle style;
  style.pixel_size = pixels;
  style.color = {235, 235, 235};
  for (int i = 0; i < 3; ++i) {
    const std::string text = font.Fit(labels[i], pixels, w - 2 * pad);
    const int x = i * w + std::max(pad, (w - font.Measure(text, pixels).width) / 2);
    font.Draw(strip.data(), width, *strip_height, x, pad, text, style);
    if (i > 0) {  // a dark line between the panels' labels
      for (int y = 0; y < *strip_height; ++y) {
        uint8_t* p = &strip[(static_cast<size_t>(y) * width + i * w) * 3];
        p[0] = p[1] = p[2] = 0;
      }
    }
  }
  return strip;
}

// A step's contacts as a sequence compares them: the pairs of geoms in touch, sorted.
std::vector<std::string> ContactKeys(const ContactSignals& c) {
  std::vector<std::string> keys;
  for (const Contact& k : c.contacts) {
    keys.push_back(std::string(ContactPairName(k.pair)) + " " + std::min(k.geom1, k.geom2) + "|" +
                   std::max(k.geom1, k.geom2));
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  return keys;
}

// Where the two runs' contact sequences first differ (--signals contacts in both): the step, and
// which pairs of geoms touch in one run and not in the other; null where both carry contacts and
// they agree, or where either run has none (then "why").
json FirstContactDifference(const std::vector<TrajectoryStep>& a,
                            const std::vector<TrajectoryStep>& b) {
  const auto has = [](const std::vector<TrajectoryStep>& steps) {
    return !steps.empty() && steps.front().contacts.has_value();
  };
  if (!has(a) || !has(b)) return nullptr;
  for (size_t t = 0; t < std::min(a.size(), b.size()); ++t) {
    if (!a[t].contacts || !b[t].contacts) continue;
    const std::vector<std::string> ka = ContactKeys(*a[t].contacts),
                                   kb = ContactKeys(*b[t].contacts);
    if (ka == kb) continue;
    json only_a = json::array(), only_b = json::array();
    std::set_difference(ka.begin(), ka.end(), kb.begin(), kb.end(), std::back_inserter(only_a));
    std::set_difference(kb.begin(), kb.end(), ka.begin(), ka.end(), std::back_inserter(only_b));
    return {{"step", t}, {"only_a", only_a}, {"only_b", only_b}};
  }
  return {{"step", nullptr}};
}

struct EpisodeComparison {
  json row;  // for compare.json and the page
  bool same = true;
};

// The trajectories of episode k, step by step (throws on a bad file: nothing written yet).
EpisodeComparison CompareStates(const CompareOptions& o, const RecordedRun& a, const RecordedRun& b,
                                int k) {
  const ManifestEpisode& ea = a.recorded.at(k);
  const ManifestEpisode& eb = b.recorded.at(k);
  EpisodeComparison result;
  json& row = result.row;
  row["index"] = k;
  row["label"] = EpisodeName(k);

  // states, step by step
  const std::vector<TrajectoryStep> ta = ReadEpisodeTrajectory(a.dir / ea.trajectory);
  const std::vector<TrajectoryStep> tb = ReadEpisodeTrajectory(b.dir / eb.trajectory);
  const size_t common = std::min(ta.size(), tb.size());
  json differences = json::array();
  std::optional<size_t> first;
  double largest = 0;
  for (size_t t = 0; t < common; ++t) {
    const std::vector<double> sa = StateVector(ta[t]), sb = StateVector(tb[t]);
    if (sa.size() != sb.size()) {
      throw UsageError("episode " + EpisodeName(k) + " step " + std::to_string(t) +
                       ": the state vectors have different sizes (" + std::to_string(sa.size()) +
                       " in A, " + std::to_string(sb.size()) + " in B): not runs of the same env");
    }
    double d = 0;
    for (size_t i = 0; i < sa.size(); ++i) {
      const double diff = std::fabs(sa[i] - sb[i]);
      d = std::isnan(diff) ? (std::isnan(sa[i]) && std::isnan(sb[i]) ? d : HUGE_VAL)
                           : std::max(d, diff);
    }
    differences.push_back(JsonDouble(d));
    largest = std::max(largest, d);
    if (!first && d > o.tolerance) first = t;
  }
  if (!first && ta.size() != tb.size()) first = common;
  row["first_contact_difference"] = FirstContactDifference(ta, tb);
  row["steps_a"] = static_cast<int>(ta.size()) - 1;
  row["steps_b"] = static_cast<int>(tb.size()) - 1;
  row["first_divergence_step"] = first ? json(*first) : json(nullptr);
  row["max_state_difference"] = JsonDouble(largest);
  row["state_difference"] = std::move(differences);
  auto outcome = [](const ManifestEpisode& entry, const std::vector<TrajectoryStep>& steps) {
    return json{
        {"success", entry.is_success},
        {"return", entry.episode_return ? JsonDouble(*entry.episode_return) : json(nullptr)},
        {"final_distance", steps.empty() ? json(nullptr) : JsonDouble(GoalDistance(steps.back()))},
        {"complete", entry.complete.value_or(true)}};
  };
  row["a"] = outcome(ea, ta);
  row["b"] = outcome(eb, tb);
  // within the tolerance the returns may differ in their last digits: states and success decide
  result.same = !first && row["a"]["success"] == row["b"]["success"];
  row["video"] = nullptr;
  row["same"] = result.same;
  return result;
}

// The video format episode k is compared in: the first that A and B both hold (mp4, webm, gif:
// see EpisodeVideos), with the two files. Throws UsageError when they have none in common.
struct VideoPair {
  std::string format;
  fs::path a, b;
};
VideoPair ChooseVideos(const RecordedRun& a, const RecordedRun& b, int k) {
  const std::vector<EpisodeVideo> va = EpisodeVideos(a.recorded.at(k));
  const std::vector<EpisodeVideo> vb = EpisodeVideos(b.recorded.at(k));
  std::string formats_a, formats_b;
  for (const EpisodeVideo& x : va) {
    formats_a += (formats_a.empty() ? "" : ",") + x.format;
    for (const EpisodeVideo& y : vb) {
      if (x.format == y.format) return {x.format, a.dir / x.file, b.dir / y.file};
    }
  }
  for (const EpisodeVideo& y : vb) formats_b += (formats_b.empty() ? "" : ",") + y.format;
  throw UsageError("episode " + EpisodeName(k) + ": the runs have no video format in common (" +
                   (formats_a.empty() ? "none" : formats_a) + " in A, " +
                   (formats_b.empty() ? "none" : formats_b) +
                   " in B): record both with one --format, or use --states-only");
}

// Opens episode k's videos in A and B; throws UsageError when they differ in size.
std::pair<VideoReader, VideoReader> OpenVideos(const RecordedRun& a, const RecordedRun& b, int k) {
  const VideoPair files = ChooseVideos(a, b, k);
  VideoReader ra(files.a.string());
  VideoReader rb(files.b.string());
  if (ra.width() != rb.width() || ra.height() != rb.height()) {
    throw UsageError("episode " + EpisodeName(k) + ": the videos differ in size (" +
                     std::to_string(ra.width()) + "x" + std::to_string(ra.height()) + " in A, " +
                     std::to_string(rb.width()) + "x" + std::to_string(rb.height()) +
                     " in B): compare needs runs recorded at the same --width/--height");
  }
  return {std::move(ra), std::move(rb)};
}

// Episode k's frames: the side-by-side video A | B | heat map under a strip naming the panels
// (`labels`), and the pixel differences.
void CompareFrames(const CompareOptions& o, const RecordedRun& a, const RecordedRun& b, int k,
                   const std::string (&labels)[3], EpisodeComparison* result) {
  json& row = result->row;
  {
    const std::string format = ChooseVideos(a, b, k).format;
    // a palette (GIF) video holds every n-th frame: it plays at its own rate
    const VideoFormat* format_row = FindVideoFormat(format);
    const ManifestVideo& recorded = a.manifest.video;
    const std::optional<int> rate =
        format_row != nullptr && format_row->pixels == VideoPixels::kPal8
            ? recorded.gif.value_or(ManifestVideoGif{}).fps
            : recorded.fps;
    const int fps = rate.value_or(25);
    auto [ra, rb] = OpenVideos(a, b, k);
    const int w = ra.width(), h = ra.height();
    int strip_height = 0;
    const std::vector<uint8_t> strip = LabelStrip(labels, w, h, &strip_height);
    VideoOptions video;
    video.width = 3 * w;
    video.height = strip_height + h;
    video.fps = fps;
    video.codec = "libx264";
    video.crf = 18;
    const std::string name = "compare_episode_" + EpisodeName(k) + ".mp4";
    VideoWriter writer((fs::path(o.out) / name).string(), video);
    std::vector<uint8_t> fa, fb;
    std::vector<uint8_t> side(static_cast<size_t>(video.width) * video.height * 3);
    std::copy(strip.begin(), strip.end(), side.begin());  // the frames go below it
    uint8_t* frames_at = side.data() + strip.size();
    row["format"] = format;
    row["label_height"] = strip_height;
    int frames_a = 0, frames_b = 0, max_pixel = 0;
    double mean_sum = 0;
    json per_frame = json::array();
    while (true) {
      const bool has_a = ra.Next(&fa), has_b = rb.Next(&fb);
      frames_a += has_a;
      frames_b += has_b;
      if (!has_a || !has_b) {
        while (has_a && ra.Next(&fa)) ++frames_a;  // count what the longer one has left
        while (has_b && rb.Next(&fb)) ++frames_b;
        break;
      }
      const PixelStats stats = SideBySide(fa, fb, w, h, o.pixel_tolerance, frames_at);
      writer.AddFrame(side.data());
      max_pixel = std::max(max_pixel, stats.max);
      mean_sum += stats.mean;
      per_frame.push_back(stats.max);
    }
    writer.Finish();
    const int frames = std::min(frames_a, frames_b);
    row["video"] = name;
    row["frames_a"] = frames_a;
    row["frames_b"] = frames_b;
    row["max_pixel_difference"] = max_pixel;
    row["mean_pixel_difference"] = frames ? mean_sum / frames : 0.0;
    row["pixel_difference"] = std::move(per_frame);
    result->same = result->same && frames_a == frames_b && max_pixel <= o.pixel_tolerance;
  }
  row["same"] = result->same;
}

// The last component of a folder's path ("runs/a/" -> "a").
std::string FolderName(const std::string& dir) {
  fs::path p = fs::absolute(dir).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  return p.filename().string();
}

// The relative link from the compare folder to a run's report, or null when it has none.
json ReportLink(const RecordedRun& run, const std::string& out) {
  const fs::path page = run.dir / kReportFileName;
  if (!fs::is_regular_file(page)) return nullptr;
  return fs::absolute(page)
      .lexically_normal()
      .lexically_relative(fs::absolute(out).lexically_normal())
      .string();
}

// The episodes both runs recorded, once they are found to be the same episodes; throws UsageError
// naming what differs.
std::vector<int> CommonEpisodes(const CompareOptions& o, const RecordedRun& a,
                                const RecordedRun& b) {
  // compare asks for the same episodes (their resets), not the same run: the policy, the
  // assets, the size or anything else may differ, and that is what it shows
  const std::optional<RunDifference> d =
      SameRun(a.manifest.parameters, b.manifest.parameters, SameRunScope::kEpisodes);
  if (d) {
    // named as the manifests name it too: env_id, seed, steps_per_episode
    const std::string member = d->parameter == "--env-id" ? "env_id"
                               : d->parameter == "--seed" ? "seed"
                                                          : "steps_per_episode";
    throw UsageError("the runs differ in " + member + " (" + d->parameter + "): " + d->a + " in '" +
                     o.run_a + "' but " + d->b + " in '" + o.run_b +
                     "'; compare needs two runs of the same env, seed and episodes");
  }
  std::vector<int> ka, kb;
  for (const auto& [k, e] : a.recorded) ka.push_back(k);
  for (const auto& [k, e] : b.recorded) kb.push_back(k);
  if (ka != kb) {
    throw UsageError("the runs recorded different episodes: " + IndexList(a.recorded) + " in '" +
                     o.run_a + "' but " + IndexList(b.recorded) + " in '" + o.run_b +
                     "'; compare needs the same episodes in both");
  }
  if (ka.empty()) throw UsageError("'" + o.run_a + "' holds no recorded episode to compare");
  return ka;
}

// Writes compare.json and the page (index.html) of the compared episodes `rows`; returns the
// page's path.
fs::path WriteComparison(const CompareOptions& o, const RecordedRun& a, const RecordedRun& b,
                         const json& rows, bool same, int differing) {
  const int fps = a.manifest.video.fps.value_or(25);
  // the title names what differs: the policies when they do, else the two folders
  const std::string policy_a = a.manifest.policy;
  const std::string policy_b = b.manifest.policy;
  const std::string title =
      a.manifest.env_id + " · " +
      (policy_a != policy_b ? policy_a + " vs " + policy_b
                            : FolderName(o.run_a) + " vs " + FolderName(o.run_b));
  const json summary = {{"same", same},
                        {"episodes", rows.size()},
                        {"differing_episodes", differing},
                        {"tolerance", JsonDouble(o.tolerance)},
                        {"pixel_tolerance", o.pixel_tolerance},
                        {"states_only", o.states_only}};
  const json result = {{"run_a", o.run_a},       {"run_b", o.run_b},
                       {"summary", summary},     {"episodes", rows},
                       {"versions", o.versions}, {"command_line", o.command_line}};
  WriteFileAtomically((fs::path(o.out) / "compare.json").string(), DumpJson(result) + "\n");
  const json page = {{"kind", "compare"},
                     {"title", title},
                     {"generator", std::string("fetchscope ") + FETCHSCOPE_VERSION},
                     {"uplot", EmbeddedUplotVersion()},
                     {"run_a", o.run_a},
                     {"run_b", o.run_b},
                     {"report_a", ReportLink(a, o.out)},
                     {"report_b", ReportLink(b, o.out)},
                     {"provenance_a", RunProvenance(a)},
                     {"provenance_b", RunProvenance(b)},
                     {"threshold_note", "state = observation, achieved goal, desired goal"},
                     {"fps", fps},
                     {"summary", summary},
                     {"episodes", rows}};
  // the episode viewer: A's and B's per-step signals on one cursor over the comparison video
  json page_data = page;
  const std::vector<PageBlock> blocks = AddCompareViewers(a, b, &page_data);
  const fs::path html = fs::path(o.out) / "index.html";
  WriteFileAtomically(html.string(), HtmlPage(PageKind::kCompare, "fetchscope compare: " + title,
                                              page_data, blocks));
  return html;
}

}  // namespace

namespace {

// compare's --out must not be one of the runs or hold a run of its own: its index.html is the
// run's report, and compare would replace it.
void RefuseRunFolderAsOut(const CompareOptions& o) {
  std::error_code ec;
  for (const std::string& run : {o.run_a, o.run_b}) {
    if (fs::equivalent(o.out, run, ec)) {
      throw UsageError("--out '" + o.out + "' is the run '" + run +
                       "' being compared: compare writes index.html there; choose a new folder");
    }
  }
  if (fs::exists(fs::path(o.out) / "manifest.json", ec)) {
    throw UsageError("--out '" + o.out +
                     "' holds a record run (manifest.json): compare would replace its "
                     "index.html; choose a new folder");
  }
}

// What one comparison wrote, removed again unless it finished: a failure leaves nothing behind.
class OutputsGuard {
 public:
  explicit OutputsGuard(const fs::path& out) : out_(out) {
    std::error_code ec;
    created_ = !fs::exists(out, ec);
    if (!created_) {
      for (const auto& entry : fs::directory_iterator(out, ec)) before_.insert(entry.path());
    }
  }
  ~OutputsGuard() {
    if (done_) return;
    std::error_code ec;
    if (created_) {
      fs::remove_all(out_, ec);
      return;
    }
    std::vector<fs::path> added;
    for (const auto& entry : fs::directory_iterator(out_, ec)) {
      if (!before_.count(entry.path())) added.push_back(entry.path());
    }
    for (const fs::path& p : added) fs::remove_all(p, ec);
  }
  OutputsGuard(const OutputsGuard&) = delete;
  OutputsGuard& operator=(const OutputsGuard&) = delete;
  void Done() { done_ = true; }

 private:
  fs::path out_;
  bool created_ = false;
  bool done_ = false;
  std::set<fs::path> before_;
};

}  // namespace

CompareResult CompareRuns(const CompareOptions& o) {
  RefuseRunFolderAsOut(o);
  const RecordedRun a = ReadRunFolder(o.run_a);
  const RecordedRun b = ReadRunFolder(o.run_b);
  const std::vector<int> ka = CommonEpisodes(o, a, b);
  // everything that can be wrong with the input is found before anything is written
  std::vector<EpisodeComparison> comparisons;
  if (!o.states_only) Font::Default();  // the panel labels' font: missing, nothing is written
  for (int k : ka) {
    comparisons.push_back(CompareStates(o, a, b, k));
    if (!o.states_only) OpenVideos(a, b, k);
  }

  std::error_code ec;
  OutputsGuard guard(o.out);
  CreateOutputFolder(o.out);
  const std::string labels[3] = {"A: " + FolderName(o.run_a), "B: " + FolderName(o.run_b),
                                 "|A − B| ×" + std::to_string(kHeatGain)};
  json rows = json::array();
  bool same = true;
  int differing = 0;
  for (size_t i = 0; i < ka.size(); ++i) {
    EpisodeComparison& c = comparisons[i];
    if (!o.states_only) CompareFrames(o, a, b, ka[i], labels, &c);
    same = same && c.same;
    differing += !c.same;
    rows.push_back(std::move(c.row));
  }
  const fs::path html = WriteComparison(o, a, b, rows, same, differing);
  guard.Done();
  return {std::move(rows), same, differing, html};
}

}  // namespace fetchscope
