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

#include <algorithm>
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

#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::ReadFile;
using testing::RunCommand;
using testing::RunFetchscope;
using testing::SourceDir;
using testing::TempDir;

// The colours the page promises (web/src/page.js): a successful episode's curve, a failed one's,
// an interrupted one's, the threshold line, and the histogram's and success rate's.
constexpr char kSuccess[] = "#1a9850";
constexpr char kFailure[] = "#d73027";
constexpr char kInterrupted[] = "#8a8f94";
constexpr char kThreshold[] = "#555";
constexpr char kAccent[] = "#2c6db2";

std::string Chromium() {
  const char* env = std::getenv("FETCHSCOPE_CHROMIUM");
  return env && *env ? env : "/usr/bin/chromium";
}

// Why the browser tests cannot run here, or empty when they can.
std::string MissingTool() {
  if (RunCommand("command -v node").exit_code != 0) return "node is not installed";
  if (!fs::exists(Chromium())) return "chromium is not installed (" + Chromium() + ")";
  if (!fs::exists(SourceDir() / "web" / "node_modules" / "playwright-core" / "package.json")) {
    return "playwright-core is not installed in web/node_modules (tools/install-deps.sh)";
  }
  return "";
}

// build/test-screenshots/<name of the running test>.png: the path tests/CMakeLists.txt attaches.
fs::path ScreenshotPath() {
  const fs::path dir = fs::path(FETCHSCOPE_BIN).parent_path() / "test-screenshots";
  fs::create_directories(dir);
  return dir /
         (std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + ".png");
}

json ReadJsonFile(const fs::path& path) { return json::parse(ReadFile(path)); }

// Runs the page check on `page` (a file, or an http:// URL) and returns what it found.
json CheckPage(const std::string& page, int sort_column) {
  const std::string where = page.rfind("http://", 0) == 0 ? " --url " : " --page ";
  const auto r =
      RunCommand("node " + (SourceDir() / "web" / "test" / "check_page.mjs").string() + where +
                 page + " --screenshot " + ScreenshotPath().string() + " --sort-column " +
                 std::to_string(sort_column) + " --chromium " + Chromium());
  const size_t line = r.output.rfind("\n{");
  const std::string last = r.output.substr(line == std::string::npos ? 0 : line + 1);
  json result = json::parse(last, nullptr, /*allow_exceptions=*/false);
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

class BrowserTest : public ::testing::Test {
 protected:
  void SetUp() override {
    fs::remove(ScreenshotPath());  // a skipped or failed test attaches no stale screenshot
    const std::string missing = MissingTool();
    if (!missing.empty()) GTEST_SKIP() << missing;
  }
};

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
  ExpectHealthyPage(result, 5, 21 / 25.0, 96, 3);
  ExpectReportPlots(result, tmp.path() / "run");
  EXPECT_EQ(result["table"]["header"], "return");
  ExpectSorts(result["table"]);
  for (const json& links : result["video_links"]) {
    ASSERT_EQ(links.size(), 1u) << links.dump();
    EXPECT_EQ(links[0]["text"], "mp4");
  }
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
  ExpectHealthyPage(result, 5, 21 / 25.0, 96, 3);
  ExpectReportPlots(result, run);
}

// A run recorded as webm and gif: the page plays the webm and links both formats by name.
TEST_F(BrowserTest, ReportPlaysWebmAndLinksEveryFormat) {
  TempDir tmp;
  const auto r = RunFetchscope(Record(tmp.path() / "run", "scripted", "--format gif,webm"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json result =
      CheckPage((tmp.path() / "run" / "index.html").string(), /*sort_column: final distance*/ 3);
  ExpectHealthyPage(result, 5, 21 / 25.0, 96, 3);
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
TEST_F(BrowserTest, ReportOfAGifRunShowsImages) {
  TempDir tmp;
  const auto r =
      RunFetchscope(Record(tmp.path() / "run", "scripted", "--format gif --gif-width 64"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json result =
      CheckPage((tmp.path() / "run" / "index.html").string(), /*sort_column: return*/ 2);
  ExpectHealthyPage(result, 0, 0, 0, 3);
  ASSERT_EQ(result["images"].size(), 5u) << result.dump();
  for (const json& image : result["images"]) {
    EXPECT_EQ(fs::path(image["src"].get<std::string>()).extension(), ".gif") << image.dump();
    EXPECT_TRUE(image["complete"].get<bool>()) << image.dump();
    EXPECT_EQ(image["natural_width"], 64) << image.dump();
    EXPECT_EQ(image["natural_height"], 64) << image.dump();
  }
  for (const json& links : result["video_links"]) {
    ASSERT_EQ(links.size(), 1u) << links.dump();
    EXPECT_EQ(links[0]["text"], "gif");
  }
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
  ExpectHealthyPage(result, 5, 21 / 25.0, 96, 3);
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
  ExpectHealthyPage(result, 5, 21 / 25.0, 3 * 96, 2);
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

}  // namespace
}  // namespace fetchscope
