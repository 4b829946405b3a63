// The report and compare pages in real headless Chromium (Debian's chromium driven by
// playwright-core from web/node_modules, see web/test/check_page.mjs): they load from file://
// with no console errors and no network request, every video reaches readyState >= 2 with the
// duration of its frames, the plots paint their canvases, the episode table sorts on a click,
// and a full-page screenshot is written to the build folder (its path printed and recorded as
// the test's "screenshot" property). Skipped when node, chromium or playwright-core is absent.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

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

fs::path ScreenshotDir() {
  const fs::path dir = fs::path(FETCHSCOPE_BIN).parent_path() / "test-screenshots";
  fs::create_directories(dir);
  return dir;
}

// Runs the page check on `page` (a file, or an http:// URL) and returns what it found.
json CheckPage(const std::string& page, const fs::path& screenshot, int sort_column) {
  const std::string where = page.rfind("http://", 0) == 0 ? " --url " : " --page ";
  const auto r =
      RunCommand("node " + (SourceDir() / "web" / "test" / "check_page.mjs").string() + where +
                 page + " --screenshot " + screenshot.string() + " --sort-column " +
                 std::to_string(sort_column) + " --chromium " + Chromium());
  const size_t line = r.output.rfind("\n{");
  const std::string last = r.output.substr(line == std::string::npos ? 0 : line + 1);
  json result = json::parse(last, nullptr, /*allow_exceptions=*/false);
  EXPECT_FALSE(result.is_discarded()) << r.output;
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return result;
}

// The checks both pages share; `duration` is the videos' expected length in seconds.
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
  for (const json& p : result["plots"]) {
    EXPECT_GT(p["width"].get<int>(), 100) << p.dump();
    // axes, grid and series: a blank canvas paints nothing
    EXPECT_GT(p["painted"].get<int>(), 1000) << p.dump();
  }
  const std::string screenshot = result.value("screenshot", "");
  ASSERT_FALSE(screenshot.empty());
  EXPECT_EQ(ReadFile(screenshot).substr(1, 3), "PNG");
  std::cout << "screenshot: " << screenshot << std::endl;
  ::testing::Test::RecordProperty("screenshot", screenshot);
}

// The column's cells as numbers ("—" and other non-numbers as NaN, which sort last).
std::vector<double> Numbers(const json& cells) {
  std::vector<double> out;
  for (const json& c : cells) {
    const std::string s = c.get<std::string>();
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    out.push_back(end == s.c_str() ? std::nan("") : v);
  }
  return out;
}

void ExpectSorts(const json& table) {
  EXPECT_EQ(table["first_click"]["aria_sort"], "ascending");
  EXPECT_EQ(table["second_click"]["aria_sort"], "descending");
  const std::vector<double> up = Numbers(table["first_click"]["cells"]);
  const std::vector<double> down = Numbers(table["second_click"]["cells"]);
  ASSERT_EQ(up.size(), down.size());
  std::vector<double> known_up, known_down;
  for (double v : up)
    if (!std::isnan(v)) known_up.push_back(v);
  for (double v : down)
    if (!std::isnan(v)) known_down.push_back(v);
  EXPECT_TRUE(std::is_sorted(known_up.begin(), known_up.end())) << table.dump();
  EXPECT_TRUE(std::is_sorted(known_down.rbegin(), known_down.rend())) << table.dump();
  // the clicks reorder the rows: the two orders are each other's reverse (ties aside)
  EXPECT_EQ(known_up.front(), known_down.back());
}

std::string Record(const fs::path& out, const std::string& policy) {
  return "record --env-id FetchPush-v4 --policy " + policy +
         " --steps 20 --width 96 --height 96 --episodes 3 --quiet --out " + out.string();
}

TEST(BrowserTest, ReportLoadsPlaysPlotsAndSorts) {
  const std::string missing = MissingTool();
  if (!missing.empty()) GTEST_SKIP() << missing;
  TempDir tmp;
  const auto r = RunFetchscope(Record(tmp.path() / "run", "scripted"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json result =
      CheckPage((tmp.path() / "run" / "index.html").string(), ScreenshotDir() / "report.png",
                /*sort_column: return*/ 2);
  ExpectHealthyPage(result, 3, 21 / 25.0, 96, 3);
  EXPECT_EQ(result["table"]["header"], "return");
  ExpectSorts(result["table"]);
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

TEST(BrowserTest, ReportWorksFromAStaticServer) {
  const std::string missing = MissingTool();
  if (!missing.empty()) GTEST_SKIP() << missing;
  if (RunCommand("command -v python3").exit_code != 0) GTEST_SKIP() << "python3 is not installed";
  TempDir tmp;
  const auto r = RunFetchscope(Record(tmp.path() / "run", "scripted"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  StaticServer server(tmp.path() / "run");
  ASSERT_GT(server.port(), 0) << ReadFile(tmp.path() / "server.log");
  const json result =
      CheckPage("http://127.0.0.1:" + std::to_string(server.port()) + "/index.html",
                ScreenshotDir() / "report_http.png", /*sort_column: final distance*/ 3);
  // a request the server answers 404 (e.g. /favicon.ico) shows up as a console error
  ExpectHealthyPage(result, 3, 21 / 25.0, 96, 3);
  ExpectSorts(result["table"]);
}

TEST(BrowserTest, ComparePageLoadsPlaysPlotsAndSorts) {
  const std::string missing = MissingTool();
  if (!missing.empty()) GTEST_SKIP() << missing;
  TempDir tmp;
  for (const char* policy : {"scripted", "zero"}) {
    const auto r = RunFetchscope(Record(tmp.path() / policy, policy) + " --no-report");
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  const auto c =
      RunFetchscope("compare -q " + (tmp.path() / "scripted").string() + " " +
                    (tmp.path() / "zero").string() + " --out " + (tmp.path() / "cmp").string());
  ASSERT_EQ(c.exit_code, 1) << c.output;
  const json result =
      CheckPage((tmp.path() / "cmp" / "index.html").string(), ScreenshotDir() / "compare.png",
                /*sort_column: max state difference*/ 3);
  ExpectHealthyPage(result, 3, 21 / 25.0, 3 * 96, 2);
  EXPECT_EQ(result["table"]["header"], "max state difference");
  ExpectSorts(result["table"]);
}

}  // namespace
}  // namespace fetchscope
