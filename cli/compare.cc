// fetchscope compare RUN_A RUN_B --out DIR: two record runs of the same env and episodes (two
// policies, bundled against genuine assets, two versions of fetchscope) side by side. Per episode
// a video A | B | per-pixel difference heat map, the first step at which the states differ beyond
// a tolerance and the state difference over steps; a summary table, compare.json and an HTML
// page in the report's style. Exit 0: the same run; 1: different; 2: could not compare.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "base/atomic_file.h"
#include "base/errors.h"
#include "base/json_util.h"
#include "cli/command.h"
#include "cli/common.h"
#include "encode/video_reader.h"
#include "encode/video_writer.h"
#include "inspect/html_page.h"
#include "inspect/report.h"
#include "render/text.h"

namespace fetchscope::cli {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct CompareOptions {
  std::string run_a;
  std::string run_b;
  std::string out;
  double tolerance =
      1e-9;  // states: largest |a - b| over a step's vector that still counts as equal
  int pixel_tolerance = 0;   // frames: largest channel difference (0..255) that counts as equal
  bool states_only = false;  // no videos decoded or written
  bool quiet = false;
};

// The run settings that must agree for two runs to be comparable (JSON pointers).
constexpr const char* kSameRun[] = {"/env_id", "/seed", "/steps_per_episode"};

std::string Value(const json& j, const char* pointer) {
  const json::json_pointer p(pointer);
  return j.contains(p) ? j.at(p).dump() : "(absent)";
}

std::string EpisodeName(int k) {
  char text[32];
  std::snprintf(text, sizeof(text), "%03d", k);
  return text;
}

std::string IndexList(const std::map<int, json>& episodes) {
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

struct EpisodeComparison {
  json row;  // for compare.json and the page
  bool same = true;
};

// The trajectories of episode k, step by step (throws on a bad file: nothing written yet).
EpisodeComparison CompareStates(const CompareOptions& o, const RecordedRun& a, const RecordedRun& b,
                                int k) {
  const json& ea = a.recorded.at(k);
  const json& eb = b.recorded.at(k);
  EpisodeComparison result;
  json& row = result.row;
  row["index"] = k;
  row["label"] = EpisodeName(k);

  // states, step by step
  const std::vector<TrajectoryStep> ta = ReadEpisodeTrajectory(a.dir / ea.value("trajectory", ""));
  const std::vector<TrajectoryStep> tb = ReadEpisodeTrajectory(b.dir / eb.value("trajectory", ""));
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
  row["steps_a"] = static_cast<int>(ta.size()) - 1;
  row["steps_b"] = static_cast<int>(tb.size()) - 1;
  row["first_divergence_step"] = first ? json(*first) : json(nullptr);
  row["max_state_difference"] = JsonDouble(largest);
  row["state_difference"] = std::move(differences);
  auto outcome = [](const json& entry, const std::vector<TrajectoryStep>& steps) {
    return json{
        {"success", entry.value("is_success", false)},
        {"return", entry.contains("return") ? entry["return"] : json(nullptr)},
        {"final_distance", steps.empty() ? json(nullptr) : JsonDouble(GoalDistance(steps.back()))},
        {"complete", entry.value("complete", true)}};
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
    // a gif holds every n-th frame: it plays at its own rate
    const char* fps_key = format == "gif" ? "/video/gif/fps" : "/video/fps";
    const json::json_pointer fps_at(fps_key);
    const int fps = a.manifest.contains(fps_at) && a.manifest.at(fps_at).is_number_integer()
                        ? a.manifest.at(fps_at).get<int>()
                        : 25;
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
  const fs::path page = run.dir / "index.html";
  if (!fs::is_regular_file(page)) return nullptr;
  return fs::absolute(page)
      .lexically_normal()
      .lexically_relative(fs::absolute(out).lexically_normal())
      .string();
}

int RunCompare(const CompareOptions& o) {
  const RecordedRun a = ReadRunFolder(o.run_a);
  const RecordedRun b = ReadRunFolder(o.run_b);
  for (const char* key : kSameRun) {
    if (Value(a.manifest, key) != Value(b.manifest, key)) {
      throw UsageError(std::string("the runs differ in ") + (key + 1) + ": " +
                       Value(a.manifest, key) + " in '" + o.run_a + "' but " +
                       Value(b.manifest, key) + " in '" + o.run_b +
                       "'; compare needs two runs of the same env, seed and episodes");
    }
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
  // everything that can be wrong with the input is found before anything is written
  std::vector<EpisodeComparison> comparisons;
  if (!o.states_only) Font::Default();  // the panel labels' font: missing, nothing is written
  for (int k : ka) {
    comparisons.push_back(CompareStates(o, a, b, k));
    if (!o.states_only) OpenVideos(a, b, k);
  }

  std::error_code ec;
  fs::create_directories(o.out, ec);
  if (!fs::is_directory(o.out)) {
    throw UsageError("cannot create output folder '" + o.out +
                     "': " + (ec ? ec.message() : std::string("a file is in the way")));
  }
  const int fps = a.manifest.contains("/video/fps"_json_pointer)
                      ? a.manifest.at("/video/fps"_json_pointer).get<int>()
                      : 25;
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

  // the title names what differs: the policies when they do, else the two folders
  const std::string policy_a = a.manifest.value("policy", std::string());
  const std::string policy_b = b.manifest.value("policy", std::string());
  const std::string title =
      a.manifest.value("env_id", std::string()) + " · " +
      (policy_a != policy_b ? policy_a + " vs " + policy_b
                            : FolderName(o.run_a) + " vs " + FolderName(o.run_b));
  const json summary = {{"same", same},
                        {"episodes", rows.size()},
                        {"differing_episodes", differing},
                        {"tolerance", JsonDouble(o.tolerance)},
                        {"pixel_tolerance", o.pixel_tolerance},
                        {"states_only", o.states_only}};
  const json result = {{"run_a", o.run_a},           {"run_b", o.run_b},
                       {"summary", summary},         {"episodes", rows},
                       {"versions", VersionsJson()}, {"command_line", CommandLine()}};
  WriteJson((fs::path(o.out) / "compare.json").string(), result);
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
  const fs::path html = fs::path(o.out) / "index.html";
  WriteFileAtomically(html.string(),
                      HtmlPage(PageKind::kCompare, "fetchscope compare: " + title, page));

  if (!o.quiet) {
    std::printf("compare: A = %s, B = %s\n", o.run_a.c_str(), o.run_b.c_str());
    std::printf("%-8s %-16s %-14s %-12s %-12s %s\n", "episode", "first diverges", "max |dstate|",
                "max |dpixel|", "success A/B", "return A/B");
    for (const json& r : rows) {
      const std::string diverge =
          r["first_divergence_step"].is_null() ? "-" : "step " + r["first_divergence_step"].dump();
      char state[32];
      std::snprintf(state, sizeof(state), "%.3g",
                    r["max_state_difference"].is_number() ? r["max_state_difference"].get<double>()
                                                          : HUGE_VAL);
      const std::string pixel = r["video"].is_null() ? "-" : r["max_pixel_difference"].dump();
      const std::string success = std::string(r["a"]["success"].get<bool>() ? "yes" : "no") + "/" +
                                  (r["b"]["success"].get<bool>() ? "yes" : "no");
      const std::string returns = r["a"]["return"].dump() + "/" + r["b"]["return"].dump();
      std::printf("%-8s %-16s %-14s %-12s %-12s %s\n", r["label"].get<std::string>().c_str(),
                  diverge.c_str(), state, pixel.c_str(), success.c_str(), returns.c_str());
    }
    std::printf(
        "compare: %s: %d of %zu episode(s) differ (state tolerance %g, pixel tolerance %d) -> %s\n",
        same ? "same" : "different", differing, rows.size(), o.tolerance, o.pixel_tolerance,
        html.string().c_str());
  }
  return same ? 0 : 1;
}

}  // namespace

Command AddCompare(CLI::App& app) {
  auto o = std::make_shared<CompareOptions>();
  CLI::App* sub = app.add_subcommand(
      "compare",
      "Compare two record runs of the same env, seed and episodes: per episode a video A | B | "
      "per-pixel difference heat map, the first step where the states differ beyond --tolerance "
      "and the state difference over steps; DIR/index.html, DIR/compare.json and a table on "
      "stdout. Exit 0: same run; 1: different; 2: could not compare (bad input)");
  sub->add_option("RUN_A", o->run_a, "Folder of the first record run (holding manifest.json)")
      ->required();
  sub->add_option("RUN_B", o->run_b, "Folder of the second record run")->required();
  sub->add_option("--out", o->out, "Output folder for the page, videos and compare.json")
      ->required();
  sub->add_option("--tolerance", o->tolerance,
                  "Largest |A - B| of any state component (observation, achieved and desired "
                  "goal) at a step that still counts as equal")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--pixel-tolerance", o->pixel_tolerance,
                  "Largest per-channel pixel difference (0..255) that still counts as equal")
      ->capture_default_str()
      ->check(CLI::Range(0, 255));
  sub->add_flag("--states-only", o->states_only,
                "Compare the trajectories only: no videos decoded or written (faster, for CI)");
  sub->add_flag("-q,--quiet", o->quiet, "No table on stdout");
  return {sub, [o] {
            try {
              return RunCompare(*o);
            } catch (const UsageError&) {
              throw;
            } catch (const std::exception& e) {
              // exit 1 means "different": a comparison that could not be made is exit 2
              throw UsageError(e.what());
            }
          }};
}

}  // namespace fetchscope::cli
