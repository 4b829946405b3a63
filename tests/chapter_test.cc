// The course chapter's path, black box: its three commands verbatim in an empty folder, the
// D1 layout it prints, and `anatomy`, which makes D1-D3, the D4 answers and the anatomy card
// (and refuses to replace another env's results without --overwrite).
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <time.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <vector>

#include "encode/png_io.h"
#include "encode/video_options.h"
#include "encode/video_writer.h"
#include "render/gl_context.h"
#include "render/renderer.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/fetch_env.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using testing::ReadFile;
using testing::RunCommand;
using testing::RunFetchscope;
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
  const auto describe =
      nlohmann::json::parse(ReadFile(tmp.path() / "results/ch01_env_describe.json"));
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
  const auto r = testing::RunFetchscopeStdout("describe --env-id FetchPush-v4");
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

int ColourDistance(Rgb8 a, Rgb8 b) {
  return std::abs(a.r - b.r) + std::abs(a.g - b.g) + std::abs(a.b - b.b);
}

Rgb8 ColourOf(const nlohmann::json& rgb) { return {rgb[0], rgb[1], rgb[2]}; }

struct Box {
  double x0, y0, x1, y1;
};

Box BoxOf(const nlohmann::json& label) {
  const auto& b = label["box"];
  return {b[0].get<double>(), b[1].get<double>(), b[0].get<double>() + b[2].get<double>(),
          b[1].get<double>() + b[3].get<double>()};
}

bool Overlap(const Box& a, const Box& b) {
  return a.x0 < b.x1 && b.x0 < a.x1 && a.y0 < b.y1 && b.y0 < a.y1;
}

// Whether segment (ax, ay)-(bx, by) meets box r: sampled every half pixel, which is finer than
// any box is thin.
bool SegmentMeets(double ax, double ay, double bx, double by, const Box& r) {
  const int n = 1 + static_cast<int>(2 * std::hypot(bx - ax, by - ay));
  for (int i = 0; i <= n; ++i) {
    const double x = ax + (bx - ax) * i / n, y = ay + (by - ay) * i / n;
    if (x > r.x0 && x < r.x1 && y > r.y0 && y < r.y1) return true;
  }
  return false;
}

// The frames of the card without anything drawn on them, rendered by `render` from the views
// the sidecar records.
std::vector<Image> PlainFrames(const nlohmann::json& sidecar, const fs::path& dir) {
  std::vector<Image> plain;
  for (size_t p = 0; p < sidecar["panels"].size(); ++p) {
    const auto& panel = sidecar["panels"][p];
    const std::string out = (dir / ("plain" + std::to_string(p) + ".png")).string();
    const auto rr = testing::RunFetchscope(
        "render --env-id " + panel["env_id"].get<std::string>() + " --seed " +
        panel["seed"].get<std::string>() + " --assets " + panel["assets"].get<std::string>() +
        " --camera '" + panel["camera"].get<std::string>() + "' --overlay none --msaa " +
        panel["msaa"].get<std::string>() + " --width " +
        std::to_string(panel["box"][2].get<int>()) + " --height " +
        std::to_string(panel["box"][3].get<int>()) + " -o " + out);
    EXPECT_EQ(rr.exit_code, 0) << rr.output;
    plain.push_back(ReadPng(out));
  }
  return plain;
}

// Runs `anatomy --out results ARGS` in `dir` and reads back the card and its sidecar.
struct Card {
  std::string output;  // what the command printed
  nlohmann::json sidecar;
  Image image;
  std::vector<Image> plain;
};

Card MakeCard(const fs::path& dir, const std::string& args) {
  const auto r = RunIn(dir, "anatomy --out results " + args);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  Card card;
  card.output = r.output;
  card.sidecar = nlohmann::json::parse(ReadFile(dir / "results/ch01_anatomy_labels.json"));
  card.image = ReadPng((dir / "results/ch01_anatomy.png").string());
  EXPECT_EQ(card.image.width, card.sidecar["width"].get<int>());
  EXPECT_EQ(card.image.height, card.sidecar["height"].get<int>());
  EXPECT_EQ(card.image.channels, 3);
  EXPECT_EQ(card.sidecar["panels"].size(), 2u);
  card.plain = PlainFrames(card.sidecar, dir);
  return card;
}

// The layout rules of the card, checked on its sidecar and its pixels: every label a readable
// box inside its panel, off every other box, its leader off every other box; every marker
// visible in its colour along its whole length.
void ExpectCleanLayout(const Card& card) {
  const auto& sidecar = card.sidecar;
  const auto& labels = sidecar["labels"];
  for (size_t i = 0; i < labels.size(); ++i) {
    const auto& label = labels[i];
    const std::string text = label["text"];
    SCOPED_TRACE("label '" + text + "'");
    const int p = label["panel"];
    const int left = sidecar["panels"][p]["box"][0];
    const Box box = BoxOf(label);
    EXPECT_GE(box.x0, left);
    EXPECT_LE(box.x1, left + card.plain[p].width);
    EXPECT_GE(box.y0, 0);
    EXPECT_LE(box.y1, card.image.height);
    // a label: a box that covers the frame and holds glyphs in the label's colour
    const Rgb8 color = ColourOf(label["color"]);
    long differing = 0, text_pixels = 0;
    for (int row = static_cast<int>(box.y0); row < static_cast<int>(box.y1); ++row) {
      for (int col = static_cast<int>(box.x0); col < static_cast<int>(box.x1); ++col) {
        const Rgb8 c = At(card.image, col, row), q = At(card.plain[p], col - left, row);
        if (ColourDistance(c, q) > 30) ++differing;
        if (ColourDistance(c, color) <= 60) ++text_pixels;
      }
    }
    const double area = (box.x1 - box.x0) * (box.y1 - box.y0);
    EXPECT_GT(differing, area / 2);
    // glyph area grows with the square of the text size: 4 pixels a character at 15 px
    const double em = sidecar["text_pixels"].get<double>() / 15;
    EXPECT_GE(text_pixels, 4 * em * em * static_cast<double>(text.size()));
    // no two boxes overlap; no leader crosses another label's box
    for (size_t j = 0; j < labels.size(); ++j) {
      if (j == i) continue;
      const Box other = BoxOf(labels[j]);
      if (j > i) {
        EXPECT_FALSE(Overlap(box, other)) << "overlaps '" << labels[j]["text"] << "'";
      }
      if (!label["leader"].is_null()) {
        const auto& l = label["leader"];
        EXPECT_FALSE(SegmentMeets(l[0], l[1], l[2], l[3], other))
            << "its leader crosses '" << labels[j]["text"] << "'";
      }
    }
    if (!label["leader"].is_null()) {
      // the leader runs from the anchor, outside the box, to the box's edge
      const auto& l = label["leader"];
      EXPECT_EQ(l[0], label["anchor"][0]);
      EXPECT_EQ(l[1], label["anchor"][1]);
      EXPECT_FALSE(SegmentMeets(l[0], l[1], l[0], l[1], box)) << "anchor inside its box";
      const double ex = l[2], ey = l[3];
      EXPECT_TRUE(std::abs(ex - box.x0) < 1e-6 || std::abs(ex - box.x1) < 1e-6 ||
                  std::abs(ey - box.y0) < 1e-6 || std::abs(ey - box.y1) < 1e-6)
          << "leader ends at " << ex << "," << ey << ", not on its box";
    }
  }
  // the fingers' detail view lies inside its panel, and each label either inside it or off it
  for (size_t p = 0; p < sidecar["panels"].size(); ++p) {
    const auto& b = sidecar["panels"][p]["detail"]["box"];
    const int left = sidecar["panels"][p]["box"][0];
    const Box detail{b[0].get<double>(), b[1].get<double>(),
                     b[0].get<double>() + b[2].get<double>(),
                     b[1].get<double>() + b[3].get<double>()};
    EXPECT_GE(detail.x0, left);
    EXPECT_LE(detail.x1, left + card.plain[p].width);
    EXPECT_GE(detail.y0, 0);
    EXPECT_LE(detail.y1, card.image.height);
    for (const auto& label : labels) {
      const Box box = BoxOf(label);
      const bool inside =
          box.x0 >= detail.x0 && box.x1 <= detail.x1 && box.y0 >= detail.y0 && box.y1 <= detail.y1;
      EXPECT_TRUE(inside || !Overlap(box, detail)) << "'" << label["text"] << "' on the detail";
    }
  }
  // every marker shows, off the labels, in its colour and drawn (with pixels that differ from
  // the plain frame: a white line on the white table shows by its dark rim) at 7 points along
  // its length (its ends may lie under an anchor dot)
  const int reach = static_cast<int>(std::ceil(std::max(2.0, sidecar["line_width"].get<double>())));
  for (const auto& marker : sidecar["markers"]) {
    const std::string name = marker["name"];
    SCOPED_TRACE("marker '" + name + "'");
    const int p = marker["panel"];
    const int left = sidecar["panels"][p]["box"][0];
    const Rgb8 color = ColourOf(marker["color"]);
    const double ax = marker["from"][0], ay = marker["from"][1];
    const double bx = marker["to"][0], by = marker["to"][1];
    int visible = 0;
    for (int k = 2; k <= 8; ++k) {
      const double t = k / 10.0;
      const double sx = ax + (bx - ax) * t, sy = ay + (by - ay) * t;
      bool under_label = false;
      for (const auto& label : labels) {
        const Box b = BoxOf(label);
        under_label = under_label || (sx >= b.x0 && sx <= b.x1 && sy >= b.y0 && sy <= b.y1);
      }
      EXPECT_FALSE(under_label) << "at " << sx << "," << sy;
      bool coloured = false, drawn = false;
      for (int y = static_cast<int>(sy) - reach; y <= static_cast<int>(sy) + reach; ++y) {
        for (int x = static_cast<int>(sx) - reach; x <= static_cast<int>(sx) + reach; ++x) {
          if (x < left || y < 0 || x >= left + card.plain[p].width || y >= card.image.height)
            continue;
          const Rgb8 c = At(card.image, x, y);
          coloured = coloured || ColourDistance(c, color) <= 45;
          drawn = drawn || ColourDistance(c, At(card.plain[p], x - left, y)) > 90;
        }
      }
      visible += coloured && drawn && !under_label;
    }
    // a leader crossing it may hide one point
    EXPECT_GE(visible, 6) << "from " << ax << "," << ay << " to " << bx << "," << by;
  }
}

// The rows of `box` that hold pixels of `color`: the height of its glyphs, in pixels.
int GlyphRows(const Image& image, const Box& box, Rgb8 color) {
  int first = -1, last = -1;
  for (int row = static_cast<int>(box.y0); row < static_cast<int>(box.y1); ++row) {
    for (int col = static_cast<int>(box.x0); col < static_cast<int>(box.x1); ++col) {
      if (ColourDistance(At(image, col, row), color) <= 60) {
        if (first < 0) first = row;
        last = row;
        break;
      }
    }
  }
  return first < 0 ? 0 : last - first + 1;
}

const nlohmann::json& LabelStartingWith(const nlohmann::json& sidecar, int panel,
                                        const std::string& prefix) {
  for (const auto& label : sidecar["labels"]) {
    if (label["panel"] == panel && label["text"].get<std::string>().rfind(prefix, 0) == 0) {
      return label;
    }
  }
  ADD_FAILURE() << "no label '" << prefix << "...' in panel " << panel;
  static const nlohmann::json none = {{"panel", panel},       {"box", {0, 0, 0, 0}},
                                      {"text", ""},           {"color", {0, 0, 0}},
                                      {"anchor", {0.0, 0.0}}, {"leader", nullptr}};
  return none;
}

const nlohmann::json& MarkerNamed(const nlohmann::json& sidecar, int panel,
                                  const std::string& name) {
  for (const auto& marker : sidecar["markers"]) {
    if (marker["panel"] == panel && marker["name"] == name) return marker;
  }
  ADD_FAILURE() << "no marker '" << name << "' in panel " << panel;
  static const nlohmann::json none = {{"panel", panel},
                                      {"name", name},
                                      {"kind", ""},
                                      {"color", {0, 0, 0}},
                                      {"from", {0.0, 0.0}},
                                      {"to", {0.0, 0.0}},
                                      {"from_world", {0.0, 0.0, 0.0}},
                                      {"to_world", {0.0, 0.0, 0.0}}};
  return none;
}

TEST(Anatomy, WritesTheDeliverablesAndALabelledCard) {
  unsetenv("DISPLAY");
  TempDir tmp;
  const Card card = MakeCard(tmp.path(), "");
  if (HasFatalFailure() || card.plain.size() != 2) return;
  for (const char* name :
       {"ch01_env_describe.json", "ch01_reward_check.json", "ch01_random_metrics.json",
        "ch01_anatomy.png", "ch01_anatomy_labels.json"}) {
    EXPECT_TRUE(fs::exists(tmp.path() / "results" / name)) << name;
  }
  EXPECT_NE(card.output.find("D4 answers"), std::string::npos) << card.output;
  EXPECT_NE(card.output.find("observation_size"), std::string::npos) << card.output;
  ExpectChapterLayout(
      nlohmann::json::parse(ReadFile(tmp.path() / "results/ch01_env_describe.json")), 10);
  EXPECT_EQ(nlohmann::json::parse(ReadFile(tmp.path() / "results/ch01_reward_check.json"))["pass"],
            true);
  const auto& sidecar = card.sidecar;
  EXPECT_EQ(sidecar["panels"][0]["env_id"], "FetchReach-v4");
  EXPECT_EQ(sidecar["panels"][1]["env_id"], "FetchPush-v4");
  ExpectCleanLayout(card);

  std::string all_text[2];
  for (const auto& label : sidecar["labels"])
    all_text[label["panel"].get<int>()] += label["text"].get<std::string>() + "\n";
  // every observation slice and action component is named with its indices, on both panels
  for (const char* needle :
       {"grip_pos obs[0:3]", "x obs[0]", "y obs[1]", "z obs[2]", "obs[3] r", "obs[4] l", "a[0]",
        "a[1]", "a[2]", "a[3]", "desired_goal", "r = 0.05 m", "obs[5:8] grip_velp"}) {
    EXPECT_NE(all_text[0].find(needle), std::string::npos) << needle << " in\n" << all_text[0];
  }
  for (const char* needle :
       {"grip_pos obs[0:3]", "x obs[0]", "y obs[1]", "z obs[2]", "a[0]", "a[1]", "a[2]", "a[3]",
        "object_pos obs[3:6]", "object_rel_pos obs[6:9]", "obs[9] r", "obs[10] l", "desired_goal",
        "r = 0.05 m", "obs[11:14] object_rot"}) {
    EXPECT_NE(all_text[1].find(needle), std::string::npos) << needle << " in\n" << all_text[1];
  }

  for (int p = 0; p < 2; ++p) {
    SCOPED_TRACE("panel " + std::to_string(p));
    // grip_pos's axes are the directions a[0:3] move the target: arrows from grip_pos along
    // world +x, +y, +z, the +z one pointing up in the image
    const auto& grip = LabelStartingWith(sidecar, p, "grip_pos");
    const char* axes[3] = {"a[0] x", "a[1] y", "a[2] z"};
    for (int k = 0; k < 3; ++k) {
      const auto& arrow = MarkerNamed(sidecar, p, axes[k]);
      EXPECT_EQ(arrow["kind"], "arrow");
      EXPECT_EQ(arrow["from"], grip["anchor"]) << axes[k];
      for (int j = 0; j < 3; ++j) {
        const double d = arrow["to_world"][j].get<double>() - arrow["from_world"][j].get<double>();
        if (j == k) {
          EXPECT_GT(d, 0.04) << axes[k];
        } else {
          EXPECT_EQ(d, 0.0) << axes[k];
        }
      }
    }
    const auto& z = MarkerNamed(sidecar, p, "a[2] z");
    EXPECT_LT(z["to"][1].get<double>(), z["from"][1].get<double>() - 20);
    // the finger width is a width: a bracket between the two fingers, a[3] arrows outward
    const auto& bracket = MarkerNamed(sidecar, p, "finger width");
    EXPECT_EQ(bracket["kind"], "bracket");
    const double span =
        std::hypot(bracket["to"][0].get<double>() - bracket["from"][0].get<double>(),
                   bracket["to"][1].get<double>() - bracket["from"][1].get<double>());
    // a width you can see: at least two lines of text long
    EXPECT_GT(span, 2 * sidecar["text_pixels"].get<double>());
    EXPECT_EQ(MarkerNamed(sidecar, p, "a[3] r")["from"], bracket["from"]);
    EXPECT_EQ(MarkerNamed(sidecar, p, "a[3] l")["from"], bracket["to"]);
  }
  const auto& rel = MarkerNamed(sidecar, 1, "object_rel_pos");
  EXPECT_EQ(rel["kind"], "arrow");
  EXPECT_EQ(rel["from"], LabelStartingWith(sidecar, 1, "grip_pos")["anchor"]);
  EXPECT_EQ(rel["to"], LabelStartingWith(sidecar, 1, "object_pos")["anchor"]);

  // the projection is right: each goal label points at the red goal sphere of the plain frame
  int goals = 0;
  for (const auto& label : sidecar["labels"]) {
    if (label["text"].get<std::string>().rfind("desired_goal", 0) != 0) continue;
    const int p = label["panel"];
    const int left = sidecar["panels"][p]["box"][0];
    const int ax = static_cast<int>(std::lround(label["anchor"][0].get<double>())) - left;
    const int ay = static_cast<int>(std::lround(label["anchor"][1].get<double>()));
    const Rgb8 c = At(card.plain[p], ax, ay);
    EXPECT_GT(c.r, 120) << "panel " << p << " at " << ax << "," << ay;
    EXPECT_LT(c.g, c.r / 2) << "panel " << p << " at " << ax << "," << ay;
    EXPECT_LT(c.b, c.r / 2) << "panel " << p << " at " << ax << "," << ay;
    ++goals;
  }
  EXPECT_EQ(goals, 2);
}

// The average width in pixels of the shaft of arrow `marker` (between 15% and 60% of its length),
// from the pixels of its colour that the plain frame lacks.
double ShaftWidth(const Card& card, const nlohmann::json& marker) {
  const int p = marker["panel"];
  const int left = card.sidecar["panels"][p]["box"][0];
  const Rgb8 color = ColourOf(marker["color"]);
  const double ax = marker["from"][0], ay = marker["from"][1];
  const double dx = marker["to"][0].get<double>() - ax, dy = marker["to"][1].get<double>() - ay;
  const double len = std::hypot(dx, dy);
  const double reach = 0.04 * card.image.height;
  long count = 0;
  for (int y = 0; y < card.image.height; ++y) {
    for (int x = left; x < left + card.plain[p].width; ++x) {
      const double px = x + 0.5 - ax, py = y + 0.5 - ay;
      const double t = (px * dx + py * dy) / (len * len);
      const double across = std::abs(px * dy - py * dx) / len;
      if (t < 0.15 || t > 0.6 || across > reach) continue;
      if (ColourDistance(At(card.image, x, y), color) <= 60 &&
          ColourDistance(At(card.plain[p], x - left, y), color) > 60) {
        ++count;
      }
    }
  }
  return count / (0.45 * len);
}

// At the smallest size and at three times that the layout stays clean, and the text (measured
// in the pixels) and the arrows grow with the card.
TEST(Anatomy, ScalesTextAndLinesWithTheCard) {
  unsetenv("DISPLAY");
  TempDir small_dir, large_dir;
  const Card small = MakeCard(small_dir.path(), "--width 480 --height 360");
  const Card large = MakeCard(large_dir.path(), "--width 1440 --height 1080");
  if (HasFailure()) return;
  {
    SCOPED_TRACE("480x360");
    ExpectCleanLayout(small);
  }
  {
    SCOPED_TRACE("1440x1080");
    ExpectCleanLayout(large);
  }
  for (int p = 0; p < 2; ++p) {
    for (const char* prefix : {"Fetch", "grip_pos", "desired_goal", "success shell"}) {
      SCOPED_TRACE("panel " + std::to_string(p) + " label '" + prefix + "...'");
      const auto& a = LabelStartingWith(small.sidecar, p, prefix);
      const auto& b = LabelStartingWith(large.sidecar, p, prefix);
      EXPECT_EQ(a["text"], b["text"]);
      const int small_rows = GlyphRows(small.image, BoxOf(a), ColourOf(a["color"]));
      const int large_rows = GlyphRows(large.image, BoxOf(b), ColourOf(b["color"]));
      // 10 px text has glyphs at least 7 rows tall; three times the card, three times the text
      EXPECT_GE(small_rows, 7);
      EXPECT_GE(large_rows, 2.6 * small_rows);
      EXPECT_LE(large_rows, 3.4 * small_rows);
      const double small_h = BoxOf(a).y1 - BoxOf(a).y0, large_h = BoxOf(b).y1 - BoxOf(b).y0;
      EXPECT_GE(large_h, 2.6 * small_h);
      EXPECT_LE(large_h, 3.4 * small_h);
    }
    for (const char* name : {"a[0] x", "a[1] y", "a[2] z"}) {
      SCOPED_TRACE("panel " + std::to_string(p) + " arrow '" + name + "'");
      const double small_width = ShaftWidth(small, MarkerNamed(small.sidecar, p, name));
      const double large_width = ShaftWidth(large, MarkerNamed(large.sidecar, p, name));
      EXPECT_GE(small_width, 1.5);
      EXPECT_GE(large_width, 2.0 * small_width);
      EXPECT_LE(large_width, 4.5 * small_width);
    }
  }
}

TEST(Anatomy, RefusesACardTooSmallToRead) {
  TempDir tmp;
  for (const char* args : {"--width 479", "--height 359"}) {
    const auto r = RunIn(tmp.path(), std::string("anatomy --out results ") + args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find(args[2] == 'w' ? "479" : "359"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(args[2] == 'w' ? "480" : "360"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(tmp.path() / "results")) << args;
  }
}

// anatomy writes D1-D3 under the chapter's names whatever the env: a second run for another env
// in the same --out is refused before it writes anything (the first run's three files stay as
// they were), and --overwrite replaces them.
TEST(AnatomyOverwrite, AnotherEnvInTheSameOutIsRefusedWholeUnlessOverwrite) {
  testing::TempDir tmp;
  const std::string out = (tmp.path() / "results").string();
  auto first = RunFetchscope("anatomy --no-card --out '" + out + "'");
  ASSERT_EQ(first.exit_code, 0) << first.output;
  const std::string names[] = {"ch01_env_describe.json", "ch01_reward_check.json",
                               "ch01_random_metrics.json"};
  std::map<std::string, std::string> before;
  for (const std::string& n : names) before[n] = ReadFile(tmp.path() / "results" / n);
  auto refused = RunFetchscope("anatomy --no-card --env-id FetchPush-v4 --out '" + out + "'");
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_NE(refused.output.find("--overwrite"), std::string::npos) << refused.output;
  for (const std::string& n : names)
    EXPECT_EQ(ReadFile(tmp.path() / "results" / n), before[n]) << n;
  auto replaced =
      RunFetchscope("anatomy --no-card --env-id FetchPush-v4 --overwrite --out '" + out + "'");
  ASSERT_EQ(replaced.exit_code, 0) << replaced.output;
  EXPECT_NE(ReadFile(tmp.path() / "results" / "ch01_env_describe.json").find("FetchPush-v4"),
            std::string::npos);
}

}  // namespace
}  // namespace fetchscope
