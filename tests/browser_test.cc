// The report and compare pages in real headless Chromium (Debian's chromium driven by
// playwright-core from web/node_modules, see web/test/check_page.mjs): they load from file://
// and from a static server with no console errors and no network request; every video reaches
// readyState >= 2 with the duration of its frames (mp4 and webm), a gif-only run's clips load
// as images; the plots draw their data (uPlot's series hold every step of every episode, and
// pixels of each series' colour lie inside the plotting area: success and failure curves, the
// threshold line, the histogram, the success rate); the episode table sorts both ways from an
// order that is neither; a full-page screenshot of each page is written to
// build/test-screenshots/<test name>.png and attached to the test: tests/CMakeLists.txt gives it
// to ctest (ATTACHED_FILES) and the output names it in a <CTestMeasurementFile> tag.
// Skipped when node, chromium or playwright-core is absent.
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "encode/png_io.h"
#include "encode/video_format.h"
#include "encode/video_reader.h"
#include "tests/browser_util.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::BrowserTest;
using testing::Chromium;
using testing::LastJson;
using testing::ReadFile;
using testing::ReadJsonFile;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::ScreenshotPath;
using testing::SourceDir;
using testing::TempDir;

// The colours the page promises (web/src/page.js): a successful episode's curve, a failed one's,
// an interrupted one's, the threshold line, and the histogram's and success rate's.
constexpr char kSuccess[] = "#1a9850";
constexpr char kFailure[] = "#d73027";
constexpr char kInterrupted[] = "#8a8f94";
constexpr char kThreshold[] = "#555";
constexpr char kAccent[] = "#2c6db2";

// A report page's episode viewer plays one of the run's videos (web/src/viewer.js).
constexpr size_t kViewerVideo = 1;

// Runs the page check on `page` (a file, or an http:// URL) and returns what it found.
json CheckPage(const std::string& page, int sort_column) {
  const std::string where = page.rfind("http://", 0) == 0 ? " --url " : " --page ";
  const auto r =
      RunCommand("node " + (SourceDir() / "web" / "test" / "check_page.mjs").string() + where +
                 page + " --screenshot " + ScreenshotPath().string() + " --sort-column " +
                 std::to_string(sort_column) + " --chromium " + Chromium());
  json result = LastJson(r.output);
  EXPECT_FALSE(result.is_discarded()) << r.output;
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return result;
}

// The checks every page shares; `duration` is the videos' expected length in seconds. The
// screenshot is attached to the test's output.
void ExpectHealthyPage(const json& result, size_t videos, double duration, int video_width,
                       size_t plots) {
  ASSERT_TRUE(result.is_object());
  EXPECT_FALSE(result.contains("exception")) << result.value("exception", "");
  EXPECT_TRUE(result["console_errors"].empty()) << result["console_errors"].dump();
  EXPECT_TRUE(result["page_errors"].empty()) << result["page_errors"].dump();
  EXPECT_TRUE(result["network_requests"].empty()) << result["network_requests"].dump();
  EXPECT_TRUE(result["failed_requests"].empty()) << result["failed_requests"].dump();
  ASSERT_EQ(result["videos"].size(), videos) << result.dump();
  for (const json& v : result["videos"]) {
    EXPECT_GE(v["ready_state"].get<int>(), 2) << v.dump();
    EXPECT_NEAR(v["duration"].get<double>(), duration, 0.02) << v.dump();
    EXPECT_EQ(v["width"], video_width) << v.dump();
  }
  ASSERT_EQ(result["plots"].size(), plots) << result.dump();
  for (const json& p : result["plots"]) EXPECT_GT(p["width"].get<int>(), 100) << p.dump();
  const std::string screenshot = result.value("screenshot", "");
  ASSERT_FALSE(screenshot.empty());
  EXPECT_EQ(ReadFile(screenshot).substr(1, 3), "PNG");
  std::cout << "screenshot: " << screenshot << std::endl;
  // CTest reads this tag in a test's output and attaches the file (Test.xml, CDash)
  std::cout << "<CTestMeasurementFile type=\"image/png\" name=\"screenshot\">" << screenshot
            << "</CTestMeasurementFile>" << std::endl;
  ::testing::Test::RecordProperty("screenshot", screenshot);
}

const json& Plot(const json& result, const std::string& id) {
  for (const json& p : result["plots"]) {
    if (p["id"] == id) return p;
  }
  ADD_FAILURE() << "no plot " << id << " in " << result["plots"].dump();
  static const json none = {{"series", json::array()}};
  return none;
}

const json& Series(const json& plot, const std::string& label) {
  for (const json& s : plot["series"]) {
    if (s["label"] == label) return s;
  }
  ADD_FAILURE() << "no series '" << label << "' in " << plot.dump();
  static const json none = {{"values", -1}, {"colour_pixels", -1}, {"stroke", ""}, {"sum", -1}};
  return none;
}

// A curve or line of a plot: enough pixels of its colour inside the plotting area that it was
// drawn (axes, grid and labels lie outside it or are grey).
constexpr int kDrawnPixels = 40;

// The report's plots show the run in `dir` as its manifest describes it: one distance curve per
// episode with every step, coloured by success (grey when interrupted), the threshold line, the
// histogram of the complete episodes' returns and their success rate.
void ExpectReportPlots(const json& result, const fs::path& dir) {
  const json manifest = ReadJsonFile(dir / "manifest.json");
  const json& distance = Plot(result, "plot-distance");
  std::set<std::string> colours;
  int complete = 0;
  size_t longest = 0;
  for (const json& e : manifest["episodes"]) {
    char label[32];
    std::snprintf(label, sizeof(label), "episode %03d", e["index"].get<int>());
    const json& s = Series(distance, label);
    const size_t steps = e["steps"].get<size_t>();
    EXPECT_EQ(s["values"], steps + 1) << label;  // the reset and every step
    longest = std::max(longest, steps + 1);
    const bool ok = e.value("complete", true);
    complete += ok;
    EXPECT_EQ(s["stroke"], !ok                           ? kInterrupted
                           : e["is_success"].get<bool>() ? kSuccess
                                                         : kFailure)
        << label;
    colours.insert(s["stroke"].get<std::string>());
    EXPECT_GE(s["colour_pixels"].get<int>(), kDrawnPixels) << s.dump();
  }
  const json& threshold = Series(distance, "threshold");
  EXPECT_EQ(threshold["stroke"], kThreshold);
  EXPECT_EQ(threshold["values"], longest);
  EXPECT_GE(threshold["colour_pixels"].get<int>(), kDrawnPixels) << threshold.dump();
  const int interrupted = static_cast<int>(manifest["episodes"].size()) - complete;
  const json& returns = Plot(result, "plot-returns");
  const std::string caption = returns.value("caption", "");
  EXPECT_EQ(caption.rfind(std::to_string(complete) + " complete episode(s)", 0), 0u) << caption;
  EXPECT_EQ(caption.find(std::to_string(interrupted) + " interrupted episode(s) left out") !=
                std::string::npos,
            interrupted > 0)
      << caption;
  const json& bars = Series(returns, "episodes");
  EXPECT_EQ(bars["sum"].get<double>(), complete);  // every complete episode in one bin
  EXPECT_EQ(bars["stroke"], kAccent);
  EXPECT_GE(bars["colour_pixels"].get<int>(), kDrawnPixels) << bars.dump();
  const json& rate = Series(Plot(result, "plot-success"), "rate");
  EXPECT_EQ(rate["values"], complete);
  EXPECT_GE(rate["colour_pixels"].get<int>(), kDrawnPixels) << rate.dump();
}

// The column's cells as numbers ("—" and other non-numbers as NaN, which sort last).
double Number(const json& cell) {
  const std::string s = cell.get<std::string>();
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  return end == s.c_str() ? std::nan("") : v;
}

std::vector<double> Numbers(const json& cells) {
  std::vector<double> out;
  for (const json& c : cells) out.push_back(Number(c));
  return out;
}

// `values` sorted one way, unknown values (NaN) last either way.
std::vector<double> Sorted(std::vector<double> values, bool descending) {
  std::stable_sort(values.begin(), values.end(), [&](double a, double b) {
    if (std::isnan(a) || std::isnan(b)) return !std::isnan(a) && std::isnan(b);
    return descending ? a > b : a < b;
  });
  return values;
}

// NaN-aware equality of two value lists.
bool SameValues(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (!(a[i] == b[i] || (std::isnan(a[i]) && std::isnan(b[i])))) return false;
  }
  return true;
}

// The clicks sort the table's rows, whole, by the column: up, then down; the rows started in an
// order that is neither, so each click had rows to move.
void ExpectSorts(const json& table) {
  const json& before = table["before"];
  const std::vector<double> start = Numbers(before["cells"]);
  const std::vector<double> up = Sorted(start, false), down = Sorted(start, true);
  ASSERT_FALSE(SameValues(start, up)) << "the run's rows already sort up: " << table.dump();
  ASSERT_FALSE(SameValues(start, down)) << "the run's rows already sort down: " << table.dump();
  std::map<std::string, std::string> cell_of;  // each row's cell, by its episode
  for (size_t i = 0; i < before["rows"].size(); ++i) {
    cell_of[before["rows"][i].get<std::string>()] = before["cells"][i].get<std::string>();
  }
  for (const auto& [click, expected, direction] :
       {std::tuple<const char*, std::vector<double>, const char*>{"first_click", up, "ascending"},
        {"second_click", down, "descending"}}) {
    const json& after = table[click];
    EXPECT_EQ(after["aria_sort"], direction) << click;
    EXPECT_TRUE(SameValues(Numbers(after["cells"]), expected)) << click << ": " << table.dump();
    // whole rows moved: every episode once, with its own cell
    ASSERT_EQ(after["rows"].size(), cell_of.size()) << click;
    std::set<std::string> seen;
    for (size_t i = 0; i < after["rows"].size(); ++i) {
      const std::string row = after["rows"][i].get<std::string>();
      EXPECT_TRUE(seen.insert(row).second) << click << ": episode " << row << " twice";
      EXPECT_EQ(cell_of[row], after["cells"][i].get<std::string>()) << click << ": episode " << row;
    }
  }
}

// 5 episodes of the scripted Push at 96x96 for 20 steps: some reach the goal in time and some
// do not, so both colours are drawn, and neither the returns nor the final distances are in
// episode order.
std::string Record(const fs::path& out, const std::string& policy = "scripted",
                   const std::string& extra = "") {
  return "record --env-id FetchPush-v4 --policy " + policy +
         " --steps 20 --width 96 --height 96 --episodes 5 --quiet --out " + out.string() + " " +
         extra;
}

TEST_F(BrowserTest, ReportLoadsPlaysPlotsAndSorts) {
  TempDir tmp;
  const auto r = RunFetchscope(Record(tmp.path() / "run"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json manifest = ReadJsonFile(tmp.path() / "run" / "manifest.json");
  std::set<bool> outcomes;
  for (const json& e : manifest["episodes"]) outcomes.insert(e["is_success"].get<bool>());
  ASSERT_EQ(outcomes.size(), 2u) << "the run should hold successes and failures";
  const json result =
      CheckPage((tmp.path() / "run" / "index.html").string(), /*sort_column: return*/ 2);
  ExpectHealthyPage(result, 5 + kViewerVideo, 21 / 25.0, 96, 3);
  ExpectReportPlots(result, tmp.path() / "run");
  EXPECT_EQ(result["table"]["header"], "return");
  ExpectSorts(result["table"]);
  for (const json& links : result["video_links"]) {
    ASSERT_EQ(links.size(), 1u) << links.dump();
    EXPECT_EQ(links[0]["text"], "mp4");
  }
}

// A fetchscope built without uPlot (configured before `npm ci`, issue 37) embeds
// web/src/no-uplot.js instead: the page loads without an error, says plainly in a note and in
// every plot box that the plots are missing and how to get them, and its table still sorts.
// The same page with uPlot's script swapped for the stand-in, as such a build writes it.
TEST_F(BrowserTest, APageBuiltWithoutUplotSaysItsPlotsAreMissing) {
  TempDir tmp;
  const auto r = RunFetchscope(Record(tmp.path() / "run"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fs::path page = tmp.path() / "run" / "index.html";
  std::string html = ReadFile(page);
  // the first plain <script> is uPlot's (the data blocks carry an id and a type)
  const size_t start = html.find("<script>\n");
  ASSERT_NE(start, std::string::npos);
  const size_t end = html.find("\n</script>", start);
  ASSERT_NE(html.substr(start, 200).find("uPlot"), std::string::npos) << html.substr(start, 200);
  html.replace(start + 9, end - start - 9, ReadFile(SourceDir() / "web" / "src" / "no-uplot.js"));
  std::ofstream(page, std::ios::binary | std::ios::trunc) << html;
  const json result = CheckPage(page.string(), /*sort_column: return*/ 2);
  ASSERT_TRUE(result.is_object());
  EXPECT_EQ(result["page_errors"], json::array()) << result.dump();
  EXPECT_EQ(result["console_errors"], json::array()) << result.dump();
  const json& notes = result["missing_plot_notes"];
  ASSERT_GE(notes.size(), 4u) << "the note and one per report plot: " << notes.dump();
  for (const json& note : notes) {
    EXPECT_NE(note.get<std::string>().find("built without uPlot"), std::string::npos) << note;
    EXPECT_NE(note.get<std::string>().find("tools/install-deps.sh"), std::string::npos) << note;
  }
  ExpectSorts(result["table"]);
}

// A run cut short in its last episode (as record leaves one after SIGINT; made by editing the
// manifest and trajectory, since a real signal's timing cannot be chosen): that episode's curve
// is grey and holds the steps it made, and the histogram and success rate leave it out.
TEST_F(BrowserTest, InterruptedEpisodeIsLeftOutOfTheAggregates) {
  TempDir tmp;
  const fs::path run = tmp.path() / "run";
  const auto r = RunFetchscope(Record(run));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  json manifest = ReadJsonFile(run / "manifest.json");
  json& last = manifest["episodes"][4];
  last["complete"] = false;
  last["steps"] = 7;
  manifest["interrupted"] = true;
  manifest["signal"] = "SIGINT";
  const fs::path trajectory_file = run / last["trajectory"].get<std::string>();
  json trajectory = ReadJsonFile(trajectory_file);
  json& steps = trajectory["episodes"][0]["steps"];
  steps.erase(steps.begin() + 8, steps.end());
  std::ofstream(trajectory_file) << trajectory.dump();
  std::ofstream(run / "manifest.json") << manifest.dump();
  ASSERT_EQ(RunFetchscope("report -q " + run.string()).exit_code, 0);
  const json result = CheckPage((run / "index.html").string(), /*sort_column: return*/ 2);
  ExpectHealthyPage(result, 5 + kViewerVideo, 21 / 25.0, 96, 3);
  ExpectReportPlots(result, run);
}

// A run recorded as webm and gif: the page plays the webm and links both formats by name.
TEST_F(BrowserTest, ReportPlaysWebmAndLinksEveryFormat) {
  TempDir tmp;
  const auto r = RunFetchscope(Record(tmp.path() / "run", "scripted", "--format gif,webm"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json result =
      CheckPage((tmp.path() / "run" / "index.html").string(), /*sort_column: final distance*/ 3);
  ExpectHealthyPage(result, 5 + kViewerVideo, 21 / 25.0, 96, 3);
  for (const json& v : result["videos"]) {
    EXPECT_EQ(fs::path(v["src"].get<std::string>()).extension(), ".webm") << v.dump();
  }
  EXPECT_TRUE(result["images"].empty()) << result["images"].dump();
  ASSERT_EQ(result["video_links"].size(), 5u);
  for (const json& links : result["video_links"]) {
    ASSERT_EQ(links.size(), 2u) << links.dump();
    EXPECT_EQ(links[0]["text"], "webm");
    EXPECT_EQ(fs::path(links[0]["href"].get<std::string>()).extension(), ".webm");
    EXPECT_EQ(links[1]["text"], "gif");
    EXPECT_EQ(fs::path(links[1]["href"].get<std::string>()).extension(), ".gif");
  }
  ExpectSorts(result["table"]);
}

// A gif-only run: no video element plays a gif; each clip shows as an image that loads.
// Every image format of the format table (gif, apng: the row's `image`, which the page reads from
// its data, never from a name) is shown as an image, loaded at its own size.
TEST_F(BrowserTest, ReportOfAnImageFormatRunShowsImages) {
  TempDir tmp;
  int image_rows = 0;
  for (const VideoFormat& row : VideoFormats()) {
    if (!row.image) continue;
    ++image_rows;
    SCOPED_TRACE(std::string(row.name));
    const fs::path run = tmp.path() / std::string(row.name);
    const auto r = RunFetchscope(
        Record(run, "scripted", "--format " + std::string(row.name) + " --gif-width 64"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const json result = CheckPage((run / "index.html").string(), /*sort_column: return*/ 2);
    ExpectHealthyPage(result, 0, 0, 0, 3);
    ASSERT_EQ(result["images"].size(), 5u) << result.dump();
    // a gif is scaled to --gif-width; an apng keeps the frames' size
    const int width = row.pixels == VideoPixels::kPal8 ? 64 : 96;
    for (const json& image : result["images"]) {
      EXPECT_EQ(fs::path(image["src"].get<std::string>()).extension(),
                "." + std::string(row.extension))
          << image.dump();
      EXPECT_TRUE(image["complete"].get<bool>()) << image.dump();
      EXPECT_EQ(image["natural_width"], width) << image.dump();
      EXPECT_EQ(image["natural_height"], width) << image.dump();
    }
    for (const json& links : result["video_links"]) {
      ASSERT_EQ(links.size(), 1u) << links.dump();
      EXPECT_EQ(links[0]["text"], std::string(row.name));
    }
  }
  EXPECT_EQ(image_rows, 2);  // gif and apng
}

// The mean absolute difference per RGB sample of two images of one size (a PNG's alpha ignored),
// or a large number when their sizes differ.
double MeanDifference(const Image& a, const std::vector<uint8_t>& rgb, int width, int height) {
  if (a.width != width || a.height != height || a.bit_depth != 8 || a.channels < 3) return 1e9;
  double sum = 0;
  for (size_t p = 0; p < static_cast<size_t>(width) * height; ++p) {
    for (int c = 0; c < 3; ++c) sum += std::abs(a.pixels[p * a.channels + c] - rgb[p * 3 + c]);
  }
  return sum / (3.0 * width * height);
}

// The frame on screen is frame `t` of the video: closer to FFmpeg's decoding of frame t than to
// its neighbours', and within codec tolerance of it.
void ExpectShowsFrame(const fs::path& grab, const fs::path& video, int t) {
  const Image shown = ReadPng(grab.string());
  int width = 0, height = 0;
  const std::vector<std::vector<uint8_t>> frames = ReadAllFrames(video.string(), &width, &height);
  ASSERT_LT(t, static_cast<int>(frames.size()));
  const double own = MeanDifference(shown, frames[t], width, height);
  std::cout << grab.filename() << ": mean difference " << own << " to frame " << t;
  for (int other : {t - 1, t + 1}) {
    if (other >= 0 && other < static_cast<int>(frames.size())) {
      std::cout << ", " << MeanDifference(shown, frames[other], width, height) << " to frame "
                << other;
    }
  }
  std::cout << std::endl;
  EXPECT_LT(own, 4.0) << grab << " against frame " << t << " of " << video;
  for (int other : {t - 1, t + 1}) {
    if (other < 0 || other >= static_cast<int>(frames.size()) || frames[other] == frames[t])
      continue;
    EXPECT_LT(own, MeanDifference(shown, frames[other], width, height))
        << grab << " is closer to frame " << other << " than to frame " << t;
  }
}

// Runs web/test/check_viewer.mjs on `page` (deep links "E:T,...", a click at step `click_step`,
// the frames it grabs written to `grabs`) and returns what it found; no console or page errors.
json CheckViewer(const fs::path& page, const std::string& links, int click_step,
                 const fs::path& grabs) {
  fs::create_directories(grabs);
  const auto c =
      RunCommand("node " + (SourceDir() / "web" / "test" / "check_viewer.mjs").string() +
                 " --page " + page.string() + " --links " + links + " --click-step " +
                 std::to_string(click_step) + " --grab-dir " + grabs.string() + " --screenshot " +
                 ScreenshotPath().string() + " --chromium " + Chromium());
  json result = LastJson(c.output);
  EXPECT_EQ(c.exit_code, 0) << c.output;
  EXPECT_TRUE(result.is_object()) << c.output;
  if (!result.is_object()) return json::object({{"links", json::array()}});
  EXPECT_TRUE(result["console_errors"].empty()) << result["console_errors"].dump();
  EXPECT_TRUE(result["page_errors"].empty()) << result["page_errors"].dump();
  return result;
}

// The report's episode viewer (web/src/viewer.js, web/test/check_viewer.mjs) on a scripted
// FetchPickAndPlace run of 20 steps (episodes 0 and 1 fail, 2-4 succeed): a deep link opens its
// episode at its step, showing that frame of the video (against FFmpeg's decoding, and episode 0's
// against `render` of that step); → moves one step, cursor and video; a click on a plot seeks to
// its step; the commanded-versus-achieved plots hold the arm's lag; the filter hides the failures
// and ↓ visits the next success.
TEST_F(BrowserTest, ViewerFollowsDeepLinksKeysAndClicks) {
  TempDir tmp;
  const fs::path run = tmp.path() / "run";
  const std::string env = "--env-id FetchPickAndPlace-v4 --policy scripted --width 96 --height 96";
  const auto r =
      RunFetchscope("record " + env + " --steps 20 --episodes 5 --quiet --out " + run.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json manifest = ReadJsonFile(run / "manifest.json");
  std::vector<int> successes, failures;
  for (const json& e : manifest["episodes"]) {
    (e["is_success"].get<bool>() ? successes : failures).push_back(e["index"].get<int>());
  }
  ASSERT_EQ(failures, (std::vector<int>{0, 1})) << "the run should fail twice, then succeed";
  const fs::path grabs = tmp.path() / "grabs";
  const json result = CheckViewer(run / "index.html", "3:7,0:12,99:0", 15, grabs);
  ASSERT_EQ(result["links"].size(), 3u) << result.dump();
  // a link to an episode the run does not have says so, and shows the first one
  EXPECT_TRUE(result["links"][0]["missing_note"].is_null()) << result["links"][0].dump();
  const std::string note = result["links"][2]["missing_note"].is_string()
                               ? result["links"][2]["missing_note"].get<std::string>()
                               : "";
  EXPECT_NE(note.find("no episode 99 (episodes 000–004, 5 in all); showing episode 000"),
            std::string::npos)
      << result["links"][2].dump();
  EXPECT_EQ(result["links"][2]["state"]["episode"], 0);
  // the step cursor's colour is far from every plotted series' (it was the object-goal
  // distance's magenta, 39 apart in RGB)
  ASSERT_TRUE(result["cursor_color"].is_string()) << result.dump();
  ASSERT_GT(result["series_colors"].size(), 5u) << result.dump();
  const auto parse_rgb = [](const json& c) {
    std::array<int, 3> v{};
    std::sscanf(c.get<std::string>().c_str(), "rgb(%d, %d, %d)", &v[0], &v[1], &v[2]);
    return v;
  };
  const std::array<int, 3> cursor = parse_rgb(result["cursor_color"]);
  for (const json& c : result["series_colors"]) {
    const std::array<int, 3> s = parse_rgb(c);
    const double d = std::hypot(cursor[0] - s[0], cursor[1] - s[1], cursor[2] - s[2]);
    EXPECT_GT(d, 90) << c << " is near the cursor's " << result["cursor_color"];
  }
  const double fps = 25;

  // the deep link: episode 3 at step 7, frame 7 on screen
  const json& link = result["links"][0];
  EXPECT_EQ(link["state"]["episode"], 3) << link.dump();
  EXPECT_EQ(link["state"]["step"], 7) << link.dump();
  EXPECT_EQ(link["state"]["steps"], 20) << link.dump();
  EXPECT_EQ(link["state"]["label"], "t = 7 / 20");
  EXPECT_NEAR(link["state"]["current_time"].get<double>(), 7.5 / fps, 1e-3);
  ExpectShowsFrame(link["grab"].get<std::string>(), run / "episode_003.mp4", 7);
  // → : exactly one step on, the cursor and the video; the address follows
  EXPECT_EQ(link["right"]["step"], 8) << link.dump();
  EXPECT_EQ(link["right"]["label"], "t = 8 / 20");
  EXPECT_EQ(link["right"]["hash"], "#episode=3&t=8");
  EXPECT_NEAR(link["right"]["current_time"].get<double>(), 8.5 / fps, 1e-3);
  ExpectShowsFrame(link["right_grab"].get<std::string>(), run / "episode_003.mp4", 8);
  // a click on the distance plot at step 15
  EXPECT_EQ(link["click"]["state"]["step"], 15) << link.dump();
  EXPECT_NEAR(link["click"]["state"]["current_time"].get<double>(), 15.5 / fps, 1e-3);
  // End: the last step (frame 20 of 0..20); Home: the reset frame
  EXPECT_EQ(link["end"]["step"], 20) << link.dump();
  EXPECT_EQ(link["end"]["label"], "t = 20 / 20");
  EXPECT_NEAR(link["end"]["current_time"].get<double>(), 20.5 / fps, 1e-3);
  EXPECT_EQ(link["home"]["step"], 0) << link.dump();
  EXPECT_NEAR(link["home"]["current_time"].get<double>(), 0.5 / fps, 1e-3);
  // a drag from step 2 to step 14: the cursor passes through the steps between, ends on 14
  const json& seen = link["drag"]["steps_seen"];
  ASSERT_EQ(seen.size(), 8u) << link.dump();
  for (size_t j = 1; j < seen.size(); ++j) EXPECT_GE(seen[j].get<int>(), seen[j - 1].get<int>());
  EXPECT_GT(seen[3].get<int>(), 2) << seen;
  EXPECT_LT(seen[3].get<int>(), 14) << seen;
  EXPECT_EQ(link["drag"]["state"]["step"], 14) << link.dump();
  EXPECT_NEAR(link["drag"]["state"]["current_time"].get<double>(), 14.5 / fps, 1e-3);

  // episode 0 at step 12: what `render` draws after 12 steps of the same policy and seed
  const json& first = result["links"][1];
  EXPECT_EQ(first["state"]["episode"], 0);
  EXPECT_EQ(first["state"]["step"], 12);
  const fs::path rendered = tmp.path() / "render_12.png";
  const auto rr = RunFetchscope("render " + env + " --seed 0 --steps 12 -o " + rendered.string());
  ASSERT_EQ(rr.exit_code, 0) << rr.output;
  const Image frame = ReadPng(rendered.string());
  const Image shown = ReadPng(first["grab"].get<std::string>());
  std::vector<uint8_t> rgb;
  for (size_t p = 0; p < static_cast<size_t>(frame.width) * frame.height; ++p) {
    for (int ch = 0; ch < 3; ++ch) rgb.push_back(frame.pixels[p * frame.channels + ch]);
  }
  const double to_render = MeanDifference(shown, rgb, frame.width, frame.height);
  std::cout << "episode 0 step 12 against render --steps 12: mean difference " << to_render
            << std::endl;
  EXPECT_LT(to_render, 6.0) << "the viewer's frame 12 of episode 0 against render --steps 12";

  // every plot has its cursor line; every recorded episode its two thumbnails
  ASSERT_TRUE(result["plots"].is_object()) << result.dump();
  EXPECT_EQ(result["cursor_lines"], result["plots"].size());
  EXPECT_EQ(result["thumbs"], 2 * manifest["episodes"].size());
  // the titles name the observation indices the report's data gives (src/observation_layout.h)
  const std::string titles = result["plot_titles"].dump();
  EXPECT_NE(titles.find("Finger width (obs[9] + obs[10])"), std::string::npos) << titles;
  EXPECT_NE(titles.find("Object height (obs[5]) and"), std::string::npos) << titles;
  // the lag, in the data episode 3's plots hold: at |a| = 1 (commanded 0.05 m) the grip moves
  // about 0.03 m a step once moving, less than commanded
  int saturated = 0;
  double sum = 0;
  for (const char* axis : {"x", "y", "z"}) {
    const json& plot = result["plots"][std::string("displacement-") + axis];
    const json& commanded = plot[std::string("commanded ") + axis];
    const json& achieved = plot[std::string("achieved ") + axis];
    ASSERT_EQ(commanded.size(), 21u) << plot.dump();
    ASSERT_EQ(achieved.size(), 21u) << plot.dump();
    EXPECT_TRUE(commanded[0].is_null() && achieved[0].is_null());  // the reset: no step
    for (size_t t = 2; t < commanded.size(); ++t) {
      const double now = commanded[t].get<double>(), before = commanded[t - 1].get<double>();
      if (std::abs(now) < 0.05 - 1e-9 || now != before) continue;  // saturated two steps running
      const double moved = achieved[t].get<double>() * (now > 0 ? 1 : -1);
      EXPECT_GT(moved, 0.02) << axis << " t=" << t;
      EXPECT_LT(moved, 0.04) << axis << " t=" << t;
      ++saturated;
      sum += moved;
    }
  }
  ASSERT_GE(saturated, 3) << result["plots"].dump();
  std::cout << "achieved per step at |a| = 1: " << sum / saturated << " m over " << saturated
            << " steps" << std::endl;
  // once moving freely the grip covers 0.032 m a step (a constant +y or +z replay gives
  // 0.0322-0.0328 from its second step on); probe-actions' 0.0257 on PickAndPlace is the mean
  // over 10 steps of +x, which include the first step and the arm's reach
  // (docs/guide/report-and-viewer.md)
  EXPECT_NEAR(sum / saturated, 0.032, 0.003);

  // the filter: the successes alone, the failures alone, then all again
  auto episodes_of = [](const json& rows) {
    std::vector<int> out;
    for (const json& row : rows) out.push_back(row["episode"].get<int>());
    return out;
  };
  EXPECT_EQ(episodes_of(result["filter"]["all"]), (std::vector<int>{0, 1, 2, 3, 4}));
  EXPECT_EQ(episodes_of(result["filter"]["success"]), successes);
  EXPECT_EQ(episodes_of(result["filter"]["failure"]), failures);
  // ↓ from episode 3 with the successes shown: episode 4
  EXPECT_EQ(result["after_down"]["episode"], 4) << result["after_down"].dump();
  EXPECT_EQ(result["after_down"]["step"], 0);
  // space plays: the cursor follows the video; space again pauses on the frame on screen
  EXPECT_EQ(result["while_playing"]["playing"], "1") << result["while_playing"].dump();
  const json& paused = result["after_pause"];
  EXPECT_EQ(paused["episode"], 4) << paused.dump();
  EXPECT_GE(paused["step"].get<int>(), 3) << paused.dump();
  EXPECT_EQ(paused["step"].get<int>(),
            std::min(20, static_cast<int>(std::floor(paused["current_time"].get<double>() * fps))))
      << paused.dump();
}

// compare's page: its viewer shows run A (solid) and B (dashed) on one step cursor over the
// comparison video A | B | difference; a deep link opens its episode and step, → moves one.
TEST_F(BrowserTest, CompareViewerShowsAAndBOnOneCursor) {
  TempDir tmp;
  for (const char* policy : {"scripted", "zero"}) {
    const auto r = RunFetchscope(Record(tmp.path() / policy, policy, "--no-report"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  const fs::path cmp = tmp.path() / "cmp";
  const auto c = RunFetchscope("compare -q " + (tmp.path() / "scripted").string() + " " +
                               (tmp.path() / "zero").string() + " --out " + cmp.string());
  ASSERT_EQ(c.exit_code, 1) << c.output;
  const json result = CheckViewer(cmp / "index.html", "2:6", 12, tmp.path() / "grabs");
  ASSERT_EQ(result["links"].size(), 1u) << result.dump();
  const json& link = result["links"][0];
  EXPECT_EQ(link["state"]["episode"], 2) << link.dump();
  EXPECT_EQ(link["state"]["step"], 6) << link.dump();
  EXPECT_NEAR(link["state"]["current_time"].get<double>(), 6.5 / 25, 1e-3);
  ExpectShowsFrame(link["grab"].get<std::string>(), cmp / "compare_episode_002.mp4", 6);
  EXPECT_EQ(link["right"]["step"], 7) << link.dump();
  ExpectShowsFrame(link["right_grab"].get<std::string>(), cmp / "compare_episode_002.mp4", 7);
  EXPECT_EQ(link["click"]["state"]["step"], 12) << link.dump();
  EXPECT_EQ(result["after_down"]["episode"], 3) << result.dump();
  // both runs' distances, every step: the scripted A closes in, the zero policy's B stays put
  const json& distance = result["plots"]["distance"];
  ASSERT_EQ(distance["A distance"].size(), 21u) << distance.dump();
  ASSERT_EQ(distance["B distance"].size(), 21u) << distance.dump();
  EXPECT_EQ(distance["A distance"][0], distance["B distance"][0]);  // the same reset
  EXPECT_LT(distance["A distance"][20].get<double>(), distance["B distance"][20].get<double>());
  EXPECT_EQ(distance["B distance"][20], distance["B distance"][0]);
  EXPECT_EQ(result["cursor_lines"], result["plots"].size());
}

// A static web server (Python's http.server) on a free port, serving `dir`, for the test's life.
class StaticServer {
 public:
  explicit StaticServer(const fs::path& dir) : log_(dir.parent_path() / "server.log") {
    const auto r = RunCommand("python3 -u -m http.server 0 --bind 127.0.0.1 --directory " +
                              dir.string() + " >" + log_.string() + " 2>&1 & echo $!");
    pid_ = std::atoi(r.output.c_str());
    for (int i = 0; i < 100 && port_ == 0; ++i) {  // "Serving HTTP on 127.0.0.1 port N ..."
      const std::string text = ReadFile(log_);
      const size_t at = text.find(" port ");
      if (at != std::string::npos) port_ = std::atoi(text.c_str() + at + 6);
      if (port_ == 0) RunCommand("sleep 0.1");
    }
  }
  ~StaticServer() {
    if (pid_ > 0) RunCommand("kill " + std::to_string(pid_));
  }
  int port() const { return port_; }

 private:
  fs::path log_;
  int pid_ = 0;
  int port_ = 0;
};

TEST_F(BrowserTest, ReportWorksFromAStaticServer) {
  if (RunCommand("command -v python3").exit_code != 0) GTEST_SKIP() << "python3 is not installed";
  TempDir tmp;
  const auto r = RunFetchscope(Record(tmp.path() / "run"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  StaticServer server(tmp.path() / "run");
  ASSERT_GT(server.port(), 0) << ReadFile(tmp.path() / "server.log");
  const json result = CheckPage("http://127.0.0.1:" + std::to_string(server.port()) + "/index.html",
                                /*final distance*/ 3);
  // a request the server answers 404 (e.g. /favicon.ico) shows up as a console error
  ExpectHealthyPage(result, 5 + kViewerVideo, 21 / 25.0, 96, 3);
  ExpectReportPlots(result, tmp.path() / "run");
  EXPECT_EQ(result["table"]["header"], "final distance (m)");
  ExpectSorts(result["table"]);
}

TEST_F(BrowserTest, ComparePageLoadsPlaysPlotsAndSorts) {
  TempDir tmp;
  for (const char* policy : {"scripted", "zero"}) {
    const auto r = RunFetchscope(Record(tmp.path() / policy, policy, "--no-report"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  const auto c =
      RunFetchscope("compare -q " + (tmp.path() / "scripted").string() + " " +
                    (tmp.path() / "zero").string() + " --out " + (tmp.path() / "cmp").string());
  ASSERT_EQ(c.exit_code, 1) << c.output;
  const json result = CheckPage((tmp.path() / "cmp" / "index.html").string(),
                                /*sort_column: max state difference*/ 3);
  ExpectHealthyPage(result, 5 + kViewerVideo, 21 / 25.0, 3 * 96, 2);
  // one state curve and one pixel curve per episode, with every step and frame, and drawn (the
  // curves lie close together, one may hide another: their colours together)
  const json compare = ReadJsonFile(tmp.path() / "cmp" / "compare.json");
  for (const char* id : {"plot-state", "plot-pixels"}) {
    std::map<std::string, int> drawn;  // colour -> pixels
    for (const json& e : compare["episodes"]) {
      const std::string label = "episode " + e["label"].get<std::string>();
      const json& s = Series(Plot(result, id), label);
      EXPECT_EQ(s["values"], 21) << id << " " << label;
      EXPECT_EQ(s["values"], id == std::string("plot-state") ? e["state_difference"].size()
                                                             : e["pixel_difference"].size())
          << id << " " << label;
      if (s["colour_pixels"].is_number()) drawn[s["stroke"]] = s["colour_pixels"];
    }
    int pixels = 0;
    for (const auto& [colour, n] : drawn) pixels += n;
    EXPECT_GE(pixels, kDrawnPixels) << id << ": " << Plot(result, id).dump();
  }
  const json& tolerance = Series(Plot(result, "plot-state"), "tolerance");
  EXPECT_GE(tolerance["colour_pixels"].get<int>(), kDrawnPixels) << tolerance.dump();
  EXPECT_EQ(result["table"]["header"], "max state difference");
  ExpectSorts(result["table"]);
}

// record --from DATASET: the viewer plots how far the replay is from the dataset (gripper and
// object position error per step, mm) on the same cursor. Scripted episodes (float64 actions
// stored as float32) drift, so the divergence column holds its longest text.
TEST_F(BrowserTest, ViewerPlotsTheReplayAgainstTheDataset) {
  TempDir tmp;
  const fs::path root = tmp.path() / "datasets", run = tmp.path() / "run";
  auto r = RunFetchscope(
      "rollout --env-id FetchPush-v4 --policy scripted --episodes 2 --steps 30 --seed 0 "
      "--minari-root " +
      root.string() + " --minari br/push-v0");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunFetchscope("record --from br/push-v0 --minari-root " + root.string() +
                    " --width 96 --height 96 --quiet --out " + run.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json result = CheckViewer(run / "index.html", "1:4", 6, tmp.path() / "grabs");
  ASSERT_TRUE(result["plots"].contains("replay")) << result["plots"].dump();
  const json& replay = result["plots"]["replay"];
  ASSERT_TRUE(replay.contains("gripper error") && replay.contains("object error")) << replay;
  EXPECT_EQ(replay["gripper error"].size(), 31u) << replay;
  EXPECT_EQ(replay["object error"][0], 0.0) << replay;  // its reset continued the generator
  // the ghost is in the markers' legend, under the videos and above the sheets, in the blue
  // the marker is drawn with (render/overlay.cc kGhostBlue {0.15, 0.25, 1})
  for (const char* id : {"viewer-overlay-legend", "sheet-overlay-legend"}) {
    const json& legend = result["overlay_legends"][id];
    ASSERT_TRUE(legend.is_array() && !legend.empty()) << id << ": " << result["overlay_legends"];
    const json ghost = {{"name", "ghost"}, {"color", "rgb(38, 64, 255)"}};
    EXPECT_NE(std::find(legend.begin(), legend.end(), ghost), legend.end()) << id << ": " << legend;
    EXPECT_EQ(legend[0]["name"], "goal") << legend;
  }
  // the episode table, divergence and reset columns included, fits the 1,280 px window
  ASSERT_TRUE(result["table"].is_object()) << result.dump();
  EXPECT_LE(result["table"]["width"], result["table"]["box"]) << result["table"];
}

}  // namespace
}  // namespace fetchscope
