// The course chapter's path, black box: its three commands verbatim in an empty folder, the
// D1 layout it prints, and `anatomy`, which makes D1-D3, the D4 answers and the anatomy card.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "render/png_io.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using testing::ReadFile;
using testing::RunCommand;
using testing::TempDir;

// Runs `fetchscope ARGS` with `dir` as the working folder.
testing::CommandResult RunIn(const fs::path& dir, const std::string& args) {
  return RunCommand("cd '" + dir.string() + "' && " + FETCHSCOPE_BIN + " " + args);
}

std::vector<std::string> FilesUnder(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    names.push_back(fs::relative(e.path(), dir).string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

// The chapter's D1 checks: the Boxes directly under observation_space, one bound per element.
void ExpectChapterLayout(const nlohmann::json& d1, int observation_size) {
  const auto& space = d1.at("observation_space");
  EXPECT_EQ(space.size(), 3u) << space.dump();
  EXPECT_EQ(space.at("observation").at("shape"), nlohmann::json::array({observation_size}));
  for (const char* key : {"observation", "achieved_goal", "desired_goal"}) {
    const auto& box = space.at(key);
    EXPECT_EQ(box.at("type"), "Box") << key;
    EXPECT_EQ(box.at("dtype"), "float64") << key;
    const size_t n = box.at("shape")[0].get<size_t>();
    ASSERT_EQ(box.at("low").size(), n) << key;
    ASSERT_EQ(box.at("high").size(), n) << key;
    for (size_t i = 0; i < n; ++i) {
      EXPECT_EQ(box["low"][i], "-inf") << key << " " << i;
      EXPECT_EQ(box["high"][i], "inf") << key << " " << i;
    }
  }
  const auto& action = d1.at("action_space");
  EXPECT_EQ(action.at("type"), "Box");
  EXPECT_EQ(action.at("shape"), nlohmann::json::array({4}));
  EXPECT_EQ(action.at("dtype"), "float32");
  EXPECT_EQ(action.at("low"), nlohmann::json::parse("[-1.0, -1.0, -1.0, -1.0]"));
  EXPECT_EQ(action.at("high"), nlohmann::json::parse("[1.0, 1.0, 1.0, 1.0]"));
  EXPECT_TRUE(action.at("low")[0].is_number_float());  // written -1.0, as Python writes it
}

TEST(Chapter, ItsThreeCommandsVerbatimInAnEmptyFolder) {
  unsetenv("DISPLAY");
  TempDir tmp;
  // exactly as the chapter prints them; results/ does not exist yet
  const auto d1 = RunIn(tmp.path(), "describe --json-out results/ch01_env");
  ASSERT_EQ(d1.exit_code, 0) << d1.output;
  const auto d2 = RunIn(tmp.path(), "reward-check --json-out results/ch01");
  EXPECT_EQ(d2.exit_code, 0) << d2.output;
  const auto d3 = RunIn(tmp.path(), "random-episodes --json-out results/ch01");
  ASSERT_EQ(d3.exit_code, 0) << d3.output;

  EXPECT_EQ(FilesUnder(tmp.path()),
            (std::vector<std::string>{"results", "results/ch01_env_describe.json",
                                      "results/ch01_random_metrics.json",
                                      "results/ch01_reward_check.json"}));
  const auto describe = nlohmann::json::parse(ReadFile(tmp.path() / "results/ch01_env_describe.json"));
  EXPECT_EQ(describe.at("env_id"), "FetchReachDense-v4");  // the chapter's default env
  ExpectChapterLayout(describe, 10);
  // what code written against the chapter reads
  EXPECT_EQ(describe["observation_space"]["observation"]["shape"][0], 10);
  EXPECT_EQ(describe["observation_space"]["desired_goal"]["shape"][0], 3);

  const auto check = nlohmann::json::parse(ReadFile(tmp.path() / "results/ch01_reward_check.json"));
  EXPECT_EQ(check.at("pass"), true);
  EXPECT_EQ(check.at("mismatch_count"), 0);

  const auto metrics =
      nlohmann::json::parse(ReadFile(tmp.path() / "results/ch01_random_metrics.json"));
  EXPECT_EQ(metrics.at("env_id"), "FetchReachDense-v4");
  EXPECT_EQ(metrics.at("n_episodes"), 10);
  EXPECT_EQ(metrics.at("episodes").size(), 10u);
  EXPECT_EQ(metrics.at("std_return_ddof"), 0);
}

TEST(Chapter, DescribeLayoutForAnObjectTask) {
  const auto r = testing::RunFetchscope("describe --env-id FetchPush-v4");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  ExpectChapterLayout(j, 25);
  EXPECT_EQ(j["observation_space"]["observation"]["labels"][6]["name"], "object_rel_pos.x");
}

TEST(Chapter, StdReturnIsThePopulationStandardDeviation) {
  const auto r = testing::RunFetchscope("random-episodes --n-episodes 4 --seed 3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  double mean = 0, var = 0;
  for (const auto& e : j["episodes"]) mean += e["return"].get<double>() / 4;
  for (const auto& e : j["episodes"]) {
    var += (e["return"].get<double>() - mean) * (e["return"].get<double>() - mean) / 4;
  }
  EXPECT_NEAR(j["std_return"].get<double>(), std::sqrt(var), 1e-12);
  EXPECT_EQ(j["std_return_ddof"], 0);
}

// ---- anatomy ---------------------------------------------------------------------------------

struct Rgb8 {
  int r, g, b;
};

Rgb8 At(const Image& image, int x, int y) {
  const uint8_t* p = image.pixels.data() + (static_cast<size_t>(y) * image.width + x) * 3;
  return {p[0], p[1], p[2]};
}

TEST(Anatomy, WritesTheDeliverablesAndALabelledCard) {
  unsetenv("DISPLAY");
  TempDir tmp;
  const auto r = RunIn(tmp.path(), "anatomy --out results");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* name : {"ch01_env_describe.json", "ch01_reward_check.json",
                           "ch01_random_metrics.json", "ch01_anatomy.png",
                           "ch01_anatomy_labels.json"}) {
    EXPECT_TRUE(fs::exists(tmp.path() / "results" / name)) << name << "\n" << r.output;
  }
  EXPECT_NE(r.output.find("D4 answers"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("observation_size"), std::string::npos) << r.output;
  ExpectChapterLayout(
      nlohmann::json::parse(ReadFile(tmp.path() / "results/ch01_env_describe.json")), 10);
  EXPECT_EQ(nlohmann::json::parse(ReadFile(tmp.path() / "results/ch01_reward_check.json"))["pass"],
            true);

  const auto sidecar =
      nlohmann::json::parse(ReadFile(tmp.path() / "results/ch01_anatomy_labels.json"));
  const Image card = ReadPng((tmp.path() / "results/ch01_anatomy.png").string());
  ASSERT_EQ(card.width, sidecar["width"].get<int>());
  ASSERT_EQ(card.height, sidecar["height"].get<int>());
  ASSERT_EQ(card.channels, 3);
  ASSERT_EQ(sidecar["panels"].size(), 2u);

  // the same frames without markers or labels, rendered by `render` from the recorded views
  std::vector<Image> plain;
  for (size_t p = 0; p < 2; ++p) {
    const auto& panel = sidecar["panels"][p];
    const std::string out = (tmp.path() / ("plain" + std::to_string(p) + ".png")).string();
    const auto rr = testing::RunFetchscope(
        "render --env-id " + panel["env_id"].get<std::string>() + " --seed " +
        panel["seed"].get<std::string>() + " --assets " + panel["assets"].get<std::string>() +
        " --camera '" + panel["camera"].get<std::string>() + "' --overlay none --msaa " +
        panel["msaa"].get<std::string>() + " --width " + std::to_string(panel["box"][2].get<int>()) +
        " --height " + std::to_string(panel["box"][3].get<int>()) + " -o " + out);
    ASSERT_EQ(rr.exit_code, 0) << rr.output;
    plain.push_back(ReadPng(out));
  }
  EXPECT_EQ(sidecar["panels"][0]["env_id"], "FetchReach-v4");
  EXPECT_EQ(sidecar["panels"][1]["env_id"], "FetchPush-v4");

  std::string all_text[2];
  for (const auto& label : sidecar["labels"]) {
    const std::string text = label["text"];
    const int p = label["panel"];
    all_text[p] += text + "\n";
    const int left = sidecar["panels"][p]["box"][0];
    const int x = label["box"][0], y = label["box"][1], w = label["box"][2], h = label["box"][3];
    SCOPED_TRACE("label '" + text + "'");
    ASSERT_GE(x, left);
    ASSERT_LE(x + w, left + plain[p].width);
    ASSERT_GE(y, 0);
    ASSERT_LE(y + h, card.height);
    const Rgb8 color{label["color"][0], label["color"][1], label["color"][2]};
    long differing = 0, text_pixels = 0;
    for (int row = y; row < y + h; ++row) {
      for (int col = x; col < x + w; ++col) {
        const Rgb8 c = At(card, col, row), q = At(plain[p], col - left, row);
        if (std::abs(c.r - q.r) + std::abs(c.g - q.g) + std::abs(c.b - q.b) > 30) ++differing;
        // anti-aliased glyphs: count the pixels at or near full coverage in the label's colour
        if (std::abs(c.r - color.r) + std::abs(c.g - color.g) + std::abs(c.b - color.b) <= 60) ++text_pixels;
      }
    }
    // the box is a label: it covers the frame and holds glyphs in the label's colour
    EXPECT_GT(differing, static_cast<long>(w) * h / 2);
    EXPECT_GE(text_pixels, 4L * static_cast<long>(text.size()));
  }
  // every observation slice and action component is named with its indices
  for (const char* needle : {"grip_pos obs[0:3]", "obs[3] r", "obs[4] l", "a[0]", "a[1]", "a[2]",
                             "a[3]", "desired_goal", "r = 0.05 m", "obs[5:8] grip_velp"}) {
    EXPECT_NE(all_text[0].find(needle), std::string::npos) << needle << " in\n" << all_text[0];
  }
  for (const char* needle : {"grip_pos obs[0:3]", "x obs[0]", "y obs[1]", "z obs[2]",
                             "object_pos obs[3:6]", "object_rel_pos obs[6:9]", "obs[9] r",
                             "obs[10] l", "desired_goal", "r = 0.05 m", "obs[11:14] object_rot"}) {
    EXPECT_NE(all_text[1].find(needle), std::string::npos) << needle << " in\n" << all_text[1];
  }

  // the projection is right: each goal label points at the red goal sphere of the plain frame
  int goals = 0;
  for (const auto& label : sidecar["labels"]) {
    if (label["text"].get<std::string>().rfind("desired_goal", 0) != 0) continue;
    const int p = label["panel"];
    const int left = sidecar["panels"][p]["box"][0];
    const int ax = static_cast<int>(std::lround(label["anchor"][0].get<double>())) - left;
    const int ay = static_cast<int>(std::lround(label["anchor"][1].get<double>()));
    const Rgb8 c = At(plain[p], ax, ay);
    EXPECT_GT(c.r, 120) << "panel " << p << " at " << ax << "," << ay;
    EXPECT_LT(c.g, c.r / 2) << "panel " << p << " at " << ax << "," << ay;
    EXPECT_LT(c.b, c.r / 2) << "panel " << p << " at " << ax << "," << ay;
    ++goals;
  }
  EXPECT_EQ(goals, 2);
}

}  // namespace
}  // namespace fetchscope
