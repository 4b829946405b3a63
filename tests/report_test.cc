// `report` and `compare` against real record runs: the page's embedded data says what the
// manifest and the trajectories say, every video format and extra per-episode videos, interrupted,
// re-rendered and sharded runs, the record and merge-manifests hooks, the Wilson interval, the
// video reader, and compare's verdicts, labelled side-by-side videos and heat maps (identical
// runs, a changed policy, bundled against genuine assets, no video format in common).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "encode/video_reader.h"
#include "encode/video_writer.h"
#include "inspect/html_page.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::GenuineAssetsDir;
using testing::ReadFile;
using testing::RunFetchscope;
using testing::TempDir;

// The JSON a page carries (the embedded data element).
json PageData(const fs::path& html) {
  return testing::PageBlock(ReadFile(html), "fetchscope-data");
}

json ReadJsonFile(const fs::path& path) { return json::parse(ReadFile(path)); }

void WriteJsonFile(const fs::path& path, const json& j) { std::ofstream(path) << j.dump(2); }

// A small run: Push, scripted, 64x64, 12 steps.
std::string Record(const fs::path& out, const std::string& extra = "", int episodes = 3,
                   const std::string& policy = "scripted") {
  return "record --env-id FetchPush-v4 --policy " + policy +
         " --steps 12 --width 64 --height 64 "
         "--quiet --episodes " +
         std::to_string(episodes) + " --out " + out.string() + " " + extra;
}

double Distance(const json& step) {
  double sum = 0;
  for (int i = 0; i < 3; ++i) {
    const double d = step["achieved_goal"][i].get<double>() - step["desired_goal"][i].get<double>();
    sum += d * d;
  }
  return std::sqrt(sum);
}

TEST(WilsonIntervalTest, MatchesPublishedValues) {
  // Wilson (1927) / Newcombe (1998) table: 8 of 10 -> 0.4902 .. 0.9433; 0 of 10 -> 0 .. 0.2775
  auto [lo, hi] = WilsonInterval(8, 10);
  EXPECT_NEAR(lo, 0.4902, 5e-5);
  EXPECT_NEAR(hi, 0.9433, 5e-5);
  std::tie(lo, hi) = WilsonInterval(0, 10);
  EXPECT_DOUBLE_EQ(lo, 0.0);
  EXPECT_NEAR(hi, 0.2775, 5e-5);
  std::tie(lo, hi) = WilsonInterval(10, 10);
  EXPECT_NEAR(lo, 0.7225, 5e-5);
  EXPECT_DOUBLE_EQ(hi, 1.0);
  std::tie(lo, hi) = WilsonInterval(0, 0);
  EXPECT_EQ(lo, 0.0);
  EXPECT_EQ(hi, 1.0);
}

TEST(VideoReaderTest, ReadsBackWhatTheWriterWrote) {
  TempDir tmp;
  VideoOptions options;
  options.width = 32;
  options.height = 16;
  options.codec = "libx264";
  options.crf = 0;
  const std::string path = (tmp.path() / "v.mp4").string();
  {
    VideoWriter writer(path, options);
    std::vector<uint8_t> rgb(32 * 16 * 3);
    for (int f = 0; f < 5; ++f) {
      for (size_t i = 0; i < rgb.size(); i += 3) {
        rgb[i] = static_cast<uint8_t>(f * 50);  // red ramps up frame by frame
        rgb[i + 1] = 0;
        rgb[i + 2] = 0;
      }
      writer.AddFrame(rgb.data());
    }
    writer.Finish();
  }
  int w = 0, h = 0;
  const auto frames = ReadAllFrames(path, &w, &h);
  ASSERT_EQ(frames.size(), 5u);
  EXPECT_EQ(w, 32);
  EXPECT_EQ(h, 16);
  for (int f = 0; f < 5; ++f) {
    // the middle pixel: yuv420p rounding keeps red within a few levels of what went in
    const uint8_t* p = &frames[f][(8 * 32 + 16) * 3];
    EXPECT_NEAR(p[0], f * 50, 4) << "frame " << f;
    EXPECT_LE(p[1], 4);
  }
  EXPECT_THROW(VideoReader((tmp.path() / "nothing.mp4").string()), std::exception);
}

class ReportTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    run_ = new TempDir();
    const auto r = RunFetchscope(Record(run_->path() / "run"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static void TearDownTestSuite() { delete run_; }
  static fs::path Run() { return run_->path() / "run"; }
  static TempDir* run_;
};
TempDir* ReportTest::run_ = nullptr;

TEST_F(ReportTest, RecordWritesAPageWhoseDataIsTheManifestsAndTrajectories) {
  const fs::path page = Run() / "index.html";
  ASSERT_TRUE(fs::is_regular_file(page));
  const std::string html = ReadFile(page);
  // self-contained: uPlot inlined, nothing from elsewhere
  EXPECT_NE(html.find("uPlot"), std::string::npos);
  EXPECT_EQ(html.find("src=\"http"), std::string::npos);
  EXPECT_EQ(html.find("href=\"http"), std::string::npos);
  EXPECT_EQ(html.find("stylesheet"), std::string::npos);

  const json data = PageData(page);
  const json manifest = ReadJsonFile(Run() / "manifest.json");
  ASSERT_EQ(data["kind"], "report");
  EXPECT_DOUBLE_EQ(data["threshold"].get<double>(), 0.05);
  ASSERT_EQ(data["episodes"].size(), 3u);
  int successes = 0;
  for (size_t k = 0; k < 3; ++k) {
    const json& e = data["episodes"][k];
    const json& m = manifest["episodes"][k];
    EXPECT_EQ(e["index"], m["index"]);
    EXPECT_EQ(e["status"], "ok");
    EXPECT_EQ(e["success"], m["is_success"]);
    EXPECT_EQ(e["return"], m["return"]);
    EXPECT_EQ(e["length"], 12);
    EXPECT_EQ(e["video"], m["video"]);
    EXPECT_EQ(e["video_format"], "mp4");
    ASSERT_EQ(e["videos"].size(), 1u);
    EXPECT_EQ(e["videos"][0]["format"], "mp4");
    EXPECT_EQ(e["videos"][0]["file"], m["video"]);
    EXPECT_EQ(e["videos"][0]["frames"], 13);
    EXPECT_TRUE(e["other_videos"].empty());
    EXPECT_EQ(e["sheet"], m["sheet"]);
    const json trajectory = ReadJsonFile(Run() / m["trajectory"].get<std::string>());
    const json& steps = trajectory["episodes"][0]["steps"];
    ASSERT_EQ(e["distances"].size(), steps.size());
    EXPECT_DOUBLE_EQ(e["final_distance"].get<double>(), Distance(steps.back()));
    EXPECT_NEAR(e["distances"][5].get<double>(), Distance(steps[5]), 1e-6);
    successes += m["is_success"].get<bool>();
  }
  EXPECT_EQ(data["summary"]["successes"], successes);
  EXPECT_EQ(data["summary"]["complete"], 3);
  const auto [lo, hi] = WilsonInterval(successes, 3);
  EXPECT_DOUBLE_EQ(data["summary"]["wilson_low"].get<double>(), lo);
  EXPECT_DOUBLE_EQ(data["summary"]["wilson_high"].get<double>(), hi);
  EXPECT_EQ(data["running_success"]["n"].size(), 3u);
  int binned = 0;
  for (const json& c : data["returns_histogram"]["counts"]) binned += c.get<int>();
  EXPECT_EQ(binned, 3);

  // provenance: env, seed, policy, assets hash, encoder, GL device, version, all from the manifest
  std::string provenance;
  for (const json& row : data["provenance"]) {
    provenance += row["label"].get<std::string>() + "=" + row["value"].get<std::string>() + "\n";
  }
  EXPECT_NE(provenance.find("env=FetchPush-v4"), std::string::npos) << provenance;
  EXPECT_NE(provenance.find("seed=0"), std::string::npos);
  EXPECT_NE(provenance.find("policy=scripted"), std::string::npos);
  EXPECT_NE(provenance.find(manifest["assets"]["sha256"].get<std::string>()), std::string::npos);
  EXPECT_NE(provenance.find("encoder=" + manifest["video"]["codec"].get<std::string>()),
            std::string::npos);
  EXPECT_NE(provenance.find(manifest["backend"]["gl_renderer"].get<std::string>()),
            std::string::npos);
  EXPECT_NE(provenance.find("fetchscope version=" +
                            manifest["versions"]["fetchscope"].get<std::string>()),
            std::string::npos);
}

TEST_F(ReportTest, NoReportFlagWritesNone) {
  TempDir tmp;
  const auto r = RunFetchscope(Record(tmp.path() / "run", "--no-report", 1));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(tmp.path() / "run" / "manifest.json"));
  EXPECT_FALSE(fs::exists(tmp.path() / "run" / "index.html"));
}

TEST_F(ReportTest, InterruptedRunShowsMissingEpisodesAndHindsightCounts) {
  TempDir tmp;
  fs::copy(Run(), tmp.path() / "run");
  // as record leaves a run cut short: episode 1 never finished, episode 2 stopped at step 7
  json manifest = ReadJsonFile(tmp.path() / "run" / "manifest.json");
  json kept = json::array();
  for (json e : manifest["episodes"]) {
    if (e["index"] == 1) continue;
    if (e["index"] == 2) {
      e["complete"] = false;
      e["steps"] = 7;
      e.erase("hindsight");  // record writes counts for every episode; the page shows them only
                             // where present
    }
    if (e["index"] == 0) e["hindsight"] = {{"relabelled_successes", 9}, {"original_successes", 2}};
    kept.push_back(e);
  }
  manifest["episodes"] = kept;
  manifest["missing"] = {1};
  manifest["interrupted"] = true;
  manifest["signal"] = "SIGINT";
  fs::remove(tmp.path() / "run" / "index.html");
  WriteJsonFile(tmp.path() / "run" / "manifest.json", manifest);
  const auto r = RunFetchscope("report " + (tmp.path() / "run").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json data = PageData(tmp.path() / "run" / "index.html");
  ASSERT_EQ(data["episodes"].size(), 3u);
  EXPECT_EQ(data["episodes"][1]["status"], "missing");
  EXPECT_NE(data["episodes"][1]["reason"].get<std::string>().find("interrupted"),
            std::string::npos);
  EXPECT_EQ(data["episodes"][2]["status"], "incomplete");
  EXPECT_EQ(data["episodes"][2]["complete"], false);
  EXPECT_EQ(data["summary"]["complete"], 1);  // only episode 0 counts towards the rate
  EXPECT_EQ(data["summary"]["incomplete"], 1);
  // ... and towards the histogram: an interrupted episode's return covers a few steps only
  int binned = 0;
  for (const json& c : data["returns_histogram"]["counts"]) binned += c.get<int>();
  EXPECT_EQ(binned, 1);
  EXPECT_EQ(data["returns_histogram"]["centres"].size(), 1u);
  EXPECT_NEAR(data["returns_histogram"]["centres"][0].get<double>(),
              manifest["episodes"][0]["return"].get<double>(), 1e-9);
  EXPECT_EQ(data["summary"]["recorded"], 2);
  EXPECT_EQ(data["summary"]["expected"], 3);
  EXPECT_NE(data["notes"][0].get<std::string>().find("SIGINT"), std::string::npos);
  EXPECT_TRUE(data["has_hindsight"].get<bool>());
  EXPECT_EQ(data["episodes"][0]["hindsight"]["relabelled_successes"], 9);
  EXPECT_FALSE(data["episodes"][2].contains("hindsight"));
  // an older manifest without "complete" flags: complete
  for (json& e : manifest["episodes"]) e.erase("complete");
  WriteJsonFile(tmp.path() / "run" / "manifest.json", manifest);
  ASSERT_EQ(RunFetchscope("report -q " + (tmp.path() / "run").string()).exit_code, 0);
  EXPECT_EQ(PageData(tmp.path() / "run" / "index.html")["episodes"][2]["complete"], true);
}

// The provenance rows as "label=value" lines.
std::string ProvenanceText(const json& data) {
  std::string text;
  for (const json& row : data["provenance"]) {
    text += row["label"].get<std::string>() + "=" + row["value"].get<std::string>() + "\n";
  }
  return text;
}

const json* ProvenanceRow(const json& data, const std::string& label) {
  for (const json& row : data["provenance"]) {
    if (row["label"] == label) return &row;
  }
  return nullptr;
}

TEST_F(ReportTest, EveryFormatIsLinkedAndTheBestPlayableShown) {
  TempDir tmp;
  const fs::path run = tmp.path() / "run";
  ASSERT_EQ(RunFetchscope(Record(run, "--format gif,webm,mp4", 2)).exit_code, 0);
  json data = PageData(run / "index.html");
  const json manifest = ReadJsonFile(run / "manifest.json");
  for (size_t k = 0; k < 2; ++k) {
    const json& e = data["episodes"][k];
    const json& videos = manifest["episodes"][k]["videos"];
    // mp4 (H.264) plays in every browser: shown; all three linked, mp4, webm, then gif
    EXPECT_EQ(e["video"], videos["mp4"]["file"]);
    EXPECT_EQ(e["video_format"], "mp4");
    ASSERT_EQ(e["videos"].size(), 3u) << e.dump();
    const char* order[] = {"mp4", "webm", "gif"};
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(e["videos"][i]["format"], order[i]);
      EXPECT_EQ(e["videos"][i]["file"], videos[order[i]]["file"]);
      EXPECT_EQ(e["videos"][i]["frames"], videos[order[i]]["frames"]);
      EXPECT_TRUE(fs::is_regular_file(run / e["videos"][i]["file"].get<std::string>()));
    }
  }
  EXPECT_NE(ProvenanceText(data).find("formats gif, webm, mp4"), std::string::npos)
      << ProvenanceText(data);

  // record --layers' per-layer videos and legend (as record lists them): linked, a missing
  // one noted; any other video the entry names: linked too
  json edited = manifest;
  fs::copy_file(run / "episode_000.mp4", run / "episode_000_segmentation.mp4");
  fs::copy_file(run / "episode_000.gif", run / "episode_000_segmentation.gif");
  fs::copy_file(run / "episode_000.json", run / "episode_000_segmentation_legend.json");
  fs::copy_file(run / "episode_000.mp4", run / "episode_000_top.mp4");
  edited["episodes"][0]["layers"] = {
      {"segmentation",
       {{"video", "episode_000_segmentation.gif"},
        {"videos",
         {{"gif", {{"file", "episode_000_segmentation.gif"}, {"frames", 13}}},
          {"mp4", {{"file", "episode_000_segmentation.mp4"}, {"frames", 13}}}}},
        {"legend", "episode_000_segmentation_legend.json"}}},
      {"depth",
       {{"video", "episode_000_depth.mp4"},
        {"videos", {{"mp4", {{"file", "episode_000_depth.mp4"}, {"frames", 13}}}}}}}};
  edited["episodes"][0]["views"] = {{"top", "episode_000_top.mp4"}};
  WriteJsonFile(run / "manifest.json", edited);
  ASSERT_EQ(RunFetchscope("report -q " + run.string()).exit_code, 0);
  data = PageData(run / "index.html");
  const json& layers = data["episodes"][0]["layers"];
  ASSERT_EQ(layers.size(), 2u) << layers.dump();
  EXPECT_EQ(layers[0]["name"], "depth");
  EXPECT_TRUE(layers[0]["videos"].empty());  // its file is missing
  EXPECT_EQ(layers[1]["name"], "segmentation");
  ASSERT_EQ(layers[1]["videos"].size(), 2u) << layers.dump();
  EXPECT_EQ(layers[1]["videos"][0]["file"], "episode_000_segmentation.mp4");  // mp4 first
  EXPECT_EQ(layers[1]["videos"][1]["file"], "episode_000_segmentation.gif");
  EXPECT_EQ(layers[1]["legend"], "episode_000_segmentation_legend.json");
  EXPECT_EQ(data["episodes"][0]["other_videos"], json({"episode_000_top.mp4"}));
  EXPECT_EQ(data["episodes"][0]["videos"].size(), 3u);
  EXPECT_TRUE(data["episodes"][1]["layers"].empty());
  EXPECT_TRUE(data["episodes"][1]["other_videos"].empty());
  EXPECT_NE(data["notes"].dump().find("depth video 'episode_000_depth.mp4' is missing"),
            std::string::npos)
      << data["notes"].dump();

  // a gif-only run: the gif is what the page shows (as an image)
  const fs::path gif = tmp.path() / "gif";
  ASSERT_EQ(RunFetchscope(Record(gif, "--format gif", 1)).exit_code, 0);
  data = PageData(gif / "index.html");
  EXPECT_EQ(data["episodes"][0]["video_format"], "gif");
  EXPECT_EQ(data["episodes"][0]["video"], "episode_000.gif");
  EXPECT_EQ(data["episodes"][0]["videos"].size(), 1u);
}

TEST_F(ReportTest, ARerenderedRunNamesItsSource) {
  TempDir tmp;
  const fs::path again = tmp.path() / "again";
  const auto r = RunFetchscope("record --quiet --from " + Run().string() +
                               " --width 64 --height 64 --out " + again.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json data = PageData(again / "index.html");
  const json* from = ProvenanceRow(data, "from");
  ASSERT_NE(from, nullptr) << ProvenanceText(data);
  EXPECT_NE((*from)["value"].get<std::string>().find(Run().string()), std::string::npos)
      << from->dump();
  // the source run's report, relative to this one
  ASSERT_TRUE((*from)["href"].is_string()) << from->dump();
  EXPECT_TRUE(fs::equivalent(again / (*from)["href"].get<std::string>(), Run() / "index.html"));
  // a run recorded afresh has no such row
  EXPECT_EQ(ProvenanceRow(PageData(Run() / "index.html"), "from"), nullptr);
}

// The report's legend of the markers in the frames: each in the colour it is drawn with; the
// ghost (a dataset's own achieved goal) only where record --from replayed a dataset with it on.
std::vector<std::string> LegendNames(const json& data) {
  std::vector<std::string> names;
  for (const json& m : data["overlay_legend"]) names.push_back(m["name"]);
  return names;
}

std::string LegendColor(const json& data, const std::string& name) {
  for (const json& m : data["overlay_legend"]) {
    if (m["name"] == name) return m["color"];
  }
  return "";
}

TEST_F(ReportTest, TheMarkersLegendHasTheGhostOnlyForADatasetReplay) {
  const auto has = [](const std::vector<std::string>& names, const std::string& name) {
    return std::find(names.begin(), names.end(), name) != names.end();
  };
  const json fresh = PageData(Run() / "index.html");
  EXPECT_EQ(
      LegendNames(fresh),
      (std::vector<std::string>{"goal", "goal shell", "achieved (success)", "achieved (not yet)"}));
  EXPECT_EQ(LegendColor(fresh, "goal"), "#ff0000");
  EXPECT_EQ(LegendColor(fresh, "achieved (not yet)"), "#ff8c00");
  TempDir tmp;
  const fs::path root = tmp.path() / "datasets";
  auto r = RunFetchscope(
      "rollout --env-id FetchReach-v4 --episodes 1 --steps 6 --seed 3 --minari-root " +
      root.string() + " --minari lg/reach-v0");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string from = "record --quiet --from lg/reach-v0 --minari-root " + root.string() +
                           " --width 32 --height 32 ";
  r = RunFetchscope(from + "--out " + (tmp.path() / "ghost").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json ghost = PageData(tmp.path() / "ghost" / "index.html");
  EXPECT_TRUE(has(LegendNames(ghost), "ghost")) << ghost["overlay_legend"];
  // kGhostBlue {0.15, 0.25, 1.0}: the cross's colour, and the HUD row's "(blue +)"
  EXPECT_EQ(LegendColor(ghost, "ghost"), "#2640ff");
  // without the ghost overlay, or replaying a run (no dataset's achieved goal to show): none
  r = RunFetchscope(from + "--overlay goal,hud,trail --out " + (tmp.path() / "plain").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json plain = PageData(tmp.path() / "plain" / "index.html");
  EXPECT_FALSE(has(LegendNames(plain), "ghost")) << plain["overlay_legend"];
  EXPECT_TRUE(has(LegendNames(plain), "trail")) << plain["overlay_legend"];
  r = RunFetchscope("record --quiet --from " + Run().string() + " --width 32 --height 32 --out " +
                    (tmp.path() / "again").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(has(LegendNames(PageData(tmp.path() / "again" / "index.html")), "ghost"));
}

TEST_F(ReportTest, AFailedReportIsAWarningNotAFailedRun) {
  TempDir tmp;
  fs::create_directories(tmp.path() / "run" / "index.html" / "in-the-way");
  const auto r = RunFetchscope(Record(tmp.path() / "run", "", 1));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("warning"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(tmp.path() / "run" / "manifest.json"));
}

TEST_F(ReportTest, ShardedRunGetsItsReportFromMergeManifests) {
  TempDir tmp;
  const fs::path run = tmp.path() / "run";
  for (const char* shard : {"0/2", "1/2"}) {
    const auto r = RunFetchscope(Record(run, std::string("--shard ") + shard, 3));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  EXPECT_FALSE(fs::exists(run / "index.html"));  // a shard is only part of the run
  const auto refused = RunFetchscope("report " + run.string());
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.output.find("merge-manifests"), std::string::npos) << refused.output;
  const auto merged = RunFetchscope("merge-manifests -q " + run.string());
  ASSERT_EQ(merged.exit_code, 0) << merged.output;
  const json data = PageData(run / "index.html");
  ASSERT_EQ(data["episodes"].size(), 3u);
  for (const json& e : data["episodes"]) EXPECT_EQ(e["status"], "ok");
  EXPECT_NE(ProvenanceRow(data, "shards"), nullptr);
  // the commands: both shards' record commands, and the merge apart from them
  EXPECT_EQ(ProvenanceRow(data, "command"), nullptr) << ProvenanceText(data);
  const json* records = ProvenanceRow(data, "record commands");
  ASSERT_NE(records, nullptr) << ProvenanceText(data);
  const std::string text = (*records)["value"].get<std::string>();
  EXPECT_NE(text.find("record --env-id FetchPush-v4"), std::string::npos) << text;
  EXPECT_NE(text.find("--shard 0/2"), std::string::npos) << text;
  EXPECT_NE(text.find("--shard 1/2"), std::string::npos) << text;
  EXPECT_EQ(text.find("merge-manifests"), std::string::npos) << text;
  const json* merge = ProvenanceRow(data, "merge command");
  ASSERT_NE(merge, nullptr) << ProvenanceText(data);
  EXPECT_NE((*merge)["value"].get<std::string>().find("merge-manifests -q " + run.string()),
            std::string::npos)
      << merge->dump();
}

TEST_F(ReportTest, ShardsInTwoFoldersMergeWithEveryFormatsFiles) {
  TempDir tmp;
  for (int shard : {0, 1}) {
    const auto r =
        RunFetchscope(Record(tmp.path() / ("s" + std::to_string(shard)),
                             "--format mp4,gif --shard " + std::to_string(shard) + "/2", 3));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  const fs::path merged = tmp.path() / "s0" / "manifest.json";
  const auto m = RunFetchscope("merge-manifests -q " + (tmp.path() / "s0").string() + " " +
                               (tmp.path() / "s1").string() + " --out " + merged.string());
  ASSERT_EQ(m.exit_code, 0) << m.output;
  const json data = PageData(tmp.path() / "s0" / "index.html");
  ASSERT_EQ(data["episodes"].size(), 3u);
  EXPECT_TRUE(data["notes"].empty()) << data["notes"].dump();
  for (const json& e : data["episodes"]) {
    ASSERT_EQ(e["videos"].size(), 2u) << e.dump();
    for (const json& v : e["videos"]) {
      // episode 1 lives in s1: its files, every format's, are found from s0
      EXPECT_TRUE(fs::is_regular_file(tmp.path() / "s0" / v["file"].get<std::string>()))
          << e.dump();
      if (e["index"] == 1) {
        EXPECT_EQ(v["file"].get<std::string>().rfind("../s1/", 0), 0u) << e.dump();
      }
    }
  }
  // a shard whose gif is gone: the merge names it
  fs::remove(tmp.path() / "s1" / "episode_001.gif");
  const auto broken = RunFetchscope("merge-manifests -q " + (tmp.path() / "s0").string() + " " +
                                    (tmp.path() / "s1").string() + " --out " + merged.string());
  EXPECT_EQ(broken.exit_code, 1) << broken.output;
  EXPECT_NE(broken.output.find("episode 1: video '"), std::string::npos) << broken.output;
  EXPECT_NE(broken.output.find("episode_001.gif' is missing"), std::string::npos) << broken.output;
}

// ---- compare

class CompareTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    runs_ = new TempDir();
    for (const auto& [name, policy] : {std::pair<const char*, const char*>{"a", "scripted"},
                                       {"a_again", "scripted"},
                                       {"zero", "zero"}}) {
      const auto r = RunFetchscope(Record(runs_->path() / name, "", 2, policy));
      ASSERT_EQ(r.exit_code, 0) << r.output;
    }
  }
  static void TearDownTestSuite() { delete runs_; }
  static std::string Dir(const char* name) { return (runs_->path() / name).string(); }
  static TempDir* runs_;
};
TempDir* CompareTest::runs_ = nullptr;

// The largest channel value in the right third (the heat map) of every frame, below the label
// strip (`top` rows) and away from the column where B's pixels meet it (chroma is shared by
// pixel pairs).
int HeatMapMax(const fs::path& video, int top, int* frames) {
  int w = 0, h = 0;
  const auto all = ReadAllFrames(video.string(), &w, &h);
  *frames = static_cast<int>(all.size());
  int largest = 0;
  const int third = w / 3;
  for (const auto& rgb : all) {
    for (int y = top + 2; y < h; ++y) {
      for (int x = 2 * third + 2; x < w; ++x) {
        for (int c = 0; c < 3; ++c) largest = std::max<int>(largest, rgb[(y * w + x) * 3 + c]);
      }
    }
  }
  return largest;
}

TEST_F(CompareTest, IdenticalRunsAreTheSameWithABlackHeatMap) {
  TempDir out;
  const auto r =
      RunFetchscope("compare " + Dir("a") + " " + Dir("a_again") + " --out " + out.path().string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("compare: same"), std::string::npos) << r.output;
  const json result = ReadJsonFile(out.path() / "compare.json");
  EXPECT_TRUE(result["summary"]["same"].get<bool>());
  ASSERT_EQ(result["episodes"].size(), 2u);
  for (const json& e : result["episodes"]) {
    EXPECT_TRUE(e["first_divergence_step"].is_null());
    EXPECT_EQ(e["max_state_difference"].get<double>(), 0.0);
    EXPECT_EQ(e["max_pixel_difference"], 0);
    int frames = 0, w = 0, h = 0;
    const int top = e["label_height"].get<int>();
    EXPECT_EQ(HeatMapMax(out.path() / e["video"].get<std::string>(), top, &frames), 0);
    EXPECT_EQ(frames, 13);
    const auto all = ReadAllFrames((out.path() / e["video"].get<std::string>()).string(), &w, &h);
    EXPECT_EQ(w, 3 * 64);
    // a strip above the frames names the panels: A's and B's run and the heat map
    EXPECT_GE(top, 10);
    EXPECT_EQ(top % 2, 0);
    EXPECT_EQ(h, top + 64);
    ASSERT_FALSE(all.empty());
    int bright[3] = {0, 0, 0};  // text pixels per panel's label
    for (int y = 0; y < top; ++y) {
      for (int x = 0; x < w; ++x) bright[x / 64] += all[0][(y * w + x) * 3] > 160;
    }
    for (int i = 0; i < 3; ++i) EXPECT_GT(bright[i], 15) << "panel " << i;
    EXPECT_NE(bright[0], bright[1]);  // "A: a" and "B: a_again" differ
  }
  const json page = PageData(out.path() / "index.html");
  EXPECT_EQ(page["kind"], "compare");
  EXPECT_TRUE(page["report_a"].is_string());  // record wrote A's report: the page links to it
}

TEST_F(CompareTest, AChangedPolicyIsCaughtAtStepOne) {
  TempDir out;
  const auto r =
      RunFetchscope("compare " + Dir("a") + " " + Dir("zero") + " --out " + out.path().string());
  ASSERT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("compare: different"), std::string::npos) << r.output;
  const json result = ReadJsonFile(out.path() / "compare.json");
  EXPECT_FALSE(result["summary"]["same"].get<bool>());
  for (const json& e : result["episodes"]) {
    // the same seed resets to the same state; the first action differs
    EXPECT_EQ(e["state_difference"][0].get<double>(), 0.0);
    EXPECT_EQ(e["first_divergence_step"], 1);
    EXPECT_GT(e["max_state_difference"].get<double>(), 1e-3);
    EXPECT_GT(e["max_pixel_difference"].get<int>(), 32);
    int frames = 0;
    EXPECT_GT(HeatMapMax(out.path() / e["video"].get<std::string>(), e["label_height"].get<int>(),
                         &frames),
              32);
  }
  // --states-only: the same verdict without videos
  TempDir states;
  const auto s = RunFetchscope("compare --states-only -q " + Dir("a") + " " + Dir("zero") +
                               " --out " + states.path().string());
  EXPECT_EQ(s.exit_code, 1) << s.output;
  EXPECT_FALSE(fs::exists(states.path() / "compare_episode_000.mp4"));
  EXPECT_TRUE(fs::exists(states.path() / "index.html"));
}

TEST_F(CompareTest, RunsWithoutAVideoFormatInCommonCompareStatesOnly) {
  TempDir tmp;
  const auto gif = RunFetchscope(Record(tmp.path() / "gif", "--format gif --no-report", 2));
  ASSERT_EQ(gif.exit_code, 0) << gif.output;
  const auto r = RunFetchscope("compare -q " + Dir("a") + " " + (tmp.path() / "gif").string() +
                               " --out " + (tmp.path() / "c").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("no video format in common (mp4 in A, gif in B)"), std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(tmp.path() / "c"));
  const auto states =
      RunFetchscope("compare -q --states-only " + Dir("a") + " " + (tmp.path() / "gif").string() +
                    " --out " + (tmp.path() / "c").string());
  EXPECT_EQ(states.exit_code, 0) << states.output;  // the same episodes, recorded as gif
}

TEST_F(CompareTest, ToleranceDecidesWhatCountsAsTheSame) {
  TempDir out;
  const auto r = RunFetchscope("compare --states-only -q --tolerance 1e9 " + Dir("a") + " " +
                               Dir("zero") + " --out " + out.path().string());
  // states within 1e9 of each other, but the scripted policy succeeds where zero does not
  const json result = ReadJsonFile(out.path() / "compare.json");
  bool successes_differ = false;
  for (const json& e : result["episodes"]) {
    EXPECT_TRUE(e["first_divergence_step"].is_null());
    successes_differ = successes_differ || e["a"]["success"] != e["b"]["success"];
  }
  EXPECT_EQ(r.exit_code, successes_differ ? 1 : 0) << r.output;
}

TEST_F(CompareTest, BundledAgainstGenuineAssetsDivergesPlausibly) {
  const fs::path genuine = GenuineAssetsDir();
  if (genuine.empty()) GTEST_SKIP() << "genuine Gymnasium-Robotics assets absent (../shared)";
  TempDir tmp;
  const auto rec = RunFetchscope(Record(tmp.path() / "genuine", "--assets " + genuine.string(), 2));
  ASSERT_EQ(rec.exit_code, 0) << rec.output;
  const auto r = RunFetchscope("compare " + Dir("a") + " " + (tmp.path() / "genuine").string() +
                               " --out " + (tmp.path() / "cmp").string());
  ASSERT_EQ(r.exit_code, 1) << r.output;
  const json result = ReadJsonFile(tmp.path() / "cmp" / "compare.json");
  for (const json& e : result["episodes"]) {
    // the bundled models match the genuine ones to about a micrometre after settling: the reset
    // states differ, beyond 1e-9, but by far less than a millimetre, and so do the first steps
    EXPECT_EQ(e["first_divergence_step"], 0);
    for (int t = 0; t < 3; ++t) {
      EXPECT_GT(e["state_difference"][t].get<double>(), 1e-9) << "step " << t;
      EXPECT_LT(e["state_difference"][t].get<double>(), 1e-3) << "step " << t;
    }
    // different meshes: the pictures differ from the first frame on
    EXPECT_GT(e["pixel_difference"][0].get<int>(), 0);
  }
}

TEST_F(CompareTest, RunsOfDifferentEnvsOrEpisodesAreRefused) {
  TempDir tmp;
  const auto reach = RunFetchscope(
      "record --env-id FetchReach-v4 --steps 12 --width 64 --height 64 "
      "--quiet --episodes 2 --no-report --out " +
      (tmp.path() / "reach").string());
  ASSERT_EQ(reach.exit_code, 0) << reach.output;
  auto r = RunFetchscope("compare " + Dir("a") + " " + (tmp.path() / "reach").string() + " --out " +
                         (tmp.path() / "c").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("env_id"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("FetchReach-v4"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp.path() / "c"));

  const auto one = RunFetchscope(Record(tmp.path() / "one", "--no-report", 1));
  ASSERT_EQ(one.exit_code, 0) << one.output;
  r = RunFetchscope("compare " + Dir("a") + " " + (tmp.path() / "one").string() + " --out " +
                    (tmp.path() / "c").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("different episodes"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp.path() / "c"));
}

}  // namespace
}  // namespace fetchscope
