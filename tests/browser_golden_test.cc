// golden check's review page in real headless Chromium (Debian's chromium driven by
// playwright-core, web/test/check_golden_review.mjs): the block's red 0.2 -> 0.25 fails a
// same-backend check, and the page shows that scene with its golden, actual and diff images
// loaded, a box round the block (the changed region, the same rectangle on each image, inside
// it and far smaller than it), the diff's colour scale, the assets-changed note, the passing
// scene listed below, no console error and no network request. Skipped when node, chromium or
// playwright-core is absent. The screenshot goes to build/test-screenshots/<test>.png.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/browser_util.h"
#include "tests/test_util.h"

namespace fs = std::filesystem;

namespace fetchscope {
namespace {

using nlohmann::json;
using testing::BrowserTest;
using testing::Chromium;
using testing::LastJson;
using testing::ReadFile;
using testing::RunCommand;
using testing::ScreenshotPath;
using testing::SourceDir;
using testing::TempDir;

class GoldenReviewPage : public BrowserTest {};

TEST_F(GoldenReviewPage, ShowsTheFailedSceneWithItsImagesScaleAndChangedRegion) {
  TempDir tmp;
  const fs::path golden = tmp.path() / "golden";
  fs::copy(SourceDir() / "golden", golden, fs::copy_options::recursive);
  // the bundled models with the block's red channel 0.2 -> 0.25
  const fs::path fetch = golden / "redder" / "fetch";
  fs::create_directories(fetch);
  for (const auto& entry : fs::directory_iterator(SourceDir() / "models")) {
    if (entry.path().extension() == ".xml") fs::copy(entry.path(), fetch / entry.path().filename());
  }
  std::string shared = ReadFile(fetch / "fetch_shared.xml");
  const std::string from = R"(name="block_mat" rgba="0.2 0.2 0.2 1")";
  ASSERT_NE(shared.find(from), std::string::npos);
  shared.replace(shared.find(from), from.size(), R"(name="block_mat" rgba="0.25 0.2 0.2 1")");
  std::ofstream(fetch / "fetch_shared.xml") << shared;
  json manifest = json::parse(ReadFile(golden / "manifest.json"));
  for (auto& s : manifest["scenes"]) {
    if (s["name"] == "push_reset_external") s["assets"] = "redder";
  }
  std::ofstream(golden / "manifest.json") << manifest.dump(2);
  const fs::path out = tmp.path() / "out";
  const auto check =
      RunCommand("FETCHSCOPE_SHARED_DIR=" + tmp.path().string() + "/none " + FETCHSCOPE_BIN +
                 " golden check --backend osmesa --golden-dir " + golden.string() +
                 " --only push_reset_external,reach_reset --out " + out.string());
  ASSERT_EQ(check.exit_code, 1) << check.output;

  const auto r =
      RunCommand("node " + (SourceDir() / "web" / "test" / "check_golden_review.mjs").string() +
                 " --page " + (out / "index.html").string() + " --screenshot " +
                 ScreenshotPath().string() + " --chromium " + Chromium());
  const json page = LastJson(r.output);
  ASSERT_TRUE(page.is_object()) << r.output;
  EXPECT_EQ(page["console_errors"], json::array()) << r.output;
  EXPECT_EQ(page["page_errors"], json::array()) << r.output;
  EXPECT_EQ(page["network_requests"], json::array()) << r.output;
  ASSERT_EQ(page["sections"].size(), 1u) << r.output;
  const json& s = page["sections"][0];
  EXPECT_EQ(s["id"], "scene-push_reset_external");
  EXPECT_NE(s["heading"].get<std::string>().find("model appearance"), std::string::npos) << s;
  EXPECT_NE(s["items"].dump().find("the assets changed since these goldens were made"),
            std::string::npos)
      << s;
  ASSERT_EQ(s["figures"].size(), 3u) << s;
  const char* captions[3] = {"golden", "actual", "diff"};
  for (int i = 0; i < 3; ++i) {
    const json& f = s["figures"][i];
    EXPECT_EQ(f["caption"], captions[i]);
    EXPECT_TRUE(f["complete"].get<bool>()) << f;
    EXPECT_EQ(f["natural_width"], 240) << f;  // loaded: the scene's 240x240 frame
    ASSERT_TRUE(f["box"].is_object()) << f;
    EXPECT_TRUE(f["box"]["inside"].get<bool>()) << f;
    EXPECT_EQ(f["box"]["border"], "2px") << f;
    // the block, not the whole frame
    const double area = f["box"]["width"].get<double>() * f["box"]["height"].get<double>();
    const double shown = f["shown_width"].get<double>();
    EXPECT_GT(area, 16.0) << f;
    EXPECT_LT(area, 0.1 * shown * shown) << f;
    EXPECT_EQ(f["box"]["x"], s["figures"][0]["box"]["x"]) << f;
    EXPECT_EQ(f["box"]["y"], s["figures"][0]["box"]["y"]) << f;
  }
  EXPECT_TRUE(page["scale"]["complete"].get<bool>()) << page["scale"];
  EXPECT_EQ(page["scale"]["natural_width"], 256) << page["scale"];
  EXPECT_EQ(page["others"], json::array({"reach_reset: ok"})) << page;
  EXPECT_TRUE(fs::exists(ScreenshotPath()));
}

}  // namespace
}  // namespace fetchscope
