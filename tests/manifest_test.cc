// The typed manifest: its one reader and writer round-trip, its schema version is written and
// checked, SameRun names the first differing record option, and the run's file names.
#include "run/manifest.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "run/run_files.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

using nlohmann::json;
using testing::TempDir;
namespace fs = std::filesystem;

// The parameters of a small record run, as record stores them.
RunParameters Parameters() {
  RunParameters p;
  p.env_id = "FetchPush-v4";
  p.seed = 11;
  p.policy = "random";
  p.episodes = 7;
  p.steps = 4;
  p.assets_sha256 = "ab12";
  p.camera = "default";
  p.overlay = "goal,achieved,hud,labels";
  p.width = 64;
  p.height = 48;
  p.msaa = "auto";
  p.codec = "libx264";
  p.crf = 23;
  p.preset = "medium";
  p.fps = 25;
  return p;
}

ManifestEpisode Episode(int k) {
  ManifestEpisode e;
  e.index = k;
  e.video = EpisodeVideoFileName(k, "mp4");
  e.videos["mp4"] = {EpisodeVideoFileName(k, "mp4"), 5};
  e.videos["gif"] = {EpisodeVideoFileName(k, "gif"), 3};
  e.sheet = EpisodeSheetFileName(k);
  e.trajectory = EpisodeTrajectoryFileName(k);
  e.frames = 5;
  e.steps = 4;
  e.complete = true;
  e.episode_return = -3.25;
  e.is_success = k % 2 == 1;
  EpisodeLayer depth;
  depth.video = EpisodeLayerVideoFileName(k, "depth", "mp4");
  depth.videos["mp4"] = {depth.video, 5};
  depth.details = {{"mapping", "grey"}, {"scales", json::array({{{"near_m", 0.5}}})}};
  e.layers["depth"] = depth;
  EpisodeLayer segmentation;
  segmentation.video = EpisodeLayerVideoFileName(k, "segmentation", "mp4");
  segmentation.videos["mp4"] = {segmentation.video, 5};
  segmentation.legend = EpisodeLegendFileName(k);
  e.layers["segmentation"] = segmentation;
  e.hindsight = EpisodeHindsight{};
  e.hindsight->extra = {{"successes", 2}};
  return e;
}

Manifest SampleManifest() {
  Manifest m;
  m.env_id = "FetchPush-v4";
  m.seed = 11;
  m.policy = "random";
  m.episodes_requested = 7;
  m.steps_per_episode = 4;
  m.episodes = {Episode(1), Episode(4)};
  m.missing = {};
  m.failures = {{0, {7}, "worker 0 died"}};
  m.shard = ManifestShard{1, 3, std::string("--shard"), std::vector<int>{1, 4}};
  m.jobs = 2;
  m.worker_mode = "process";
  m.workers = ManifestWorkersFromJson(json::array({{{"worker", 0}, {"backend", "osmesa"}}}));
  m.gpu = ManifestGpuFromJson({{"request", "auto"}, {"choice", "cpu"}, {"devices", json::array()}});
  m.assets = {{"kind", "bundled"}, {"sha256", "ab12"}};
  m.model_file = "/x/push.xml";
  m.camera = "default";
  m.overlay = "goal";
  m.msaa = 4;
  m.msaa_reason = "auto";
  m.backend.name = "osmesa";
  m.layers = {"rgb", "depth", "segmentation"};
  m.video = ManifestVideoFromJson({{"fps", 25}, {"formats", {"mp4", "gif"}}});
  m.versions = {{"fetchscope", "1.0"}};
  m.timings_s.wall = 1.5;
  m.frames = 10;
  m.interrupted = true;
  m.incomplete_episodes = {4};
  m.signal = "SIGTERM";
  m.command_line = "fetchscope record";
  m.parameters = Parameters();
  m.parameters.formats = {"mp4", "gif"};
  m.parameters.gif_fps = 7;
  m.parameters.layers = "rgb,depth,segmentation";
  m.parameters.signals = "contacts";
  m.parameters.shard_index = 1;
  m.parameters.shard_count = 3;
  m.resumed = true;
  m.extra = {{"a_member_of_a_later_fetchscope", {1, 2}}};
  return m;
}

TEST(ManifestTest, RoundTripsThroughJson) {
  const Manifest m = SampleManifest();
  const json j = ManifestToJson(m);
  EXPECT_EQ(j["schema_version"], kManifestSchemaVersion);
  EXPECT_EQ(ManifestFromJson(j), m);
  // and through the file, as record writes it
  TempDir tmp;
  WriteManifest(tmp.path() / "manifest.json", m);
  EXPECT_EQ(ReadManifest(tmp.path() / "manifest.json"), m);
  EXPECT_EQ(ManifestToJson(ReadManifest(tmp.path() / "manifest.json")), j);
}

TEST(ManifestTest, AMergedManifestHasShardsInsteadOfPerProcessMembers) {
  Manifest m = SampleManifest();
  m.merged = true;
  m.shard.reset();
  m.missing.clear();
  m.failures.clear();
  m.jobs = 1;
  m.worker_mode.clear();
  m.workers.clear();
  m.gpu = ManifestGpu{};
  m.shards = json::array({{{"index", 0}, {"count", 3}}});
  const json j = ManifestToJson(m);
  for (const char* key :
       {"shard", "jobs", "worker_mode", "workers", "missing", "failures", "gpu"}) {
    EXPECT_FALSE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["merged"], true);
  EXPECT_EQ(ManifestFromJson(j), m);
}

// The writer keeps every member record wrote before the type existed, with its value.
TEST(ManifestTest, EveryKeyOfAnUntypedManifestSurvives) {
  const json old = {{"env_id", "FetchReach-v4"},
                    {"seed", 3},
                    {"policy", "zero"},
                    {"from", nullptr},
                    {"episodes_requested", 1},
                    {"steps_per_episode", 2},
                    {"sheet_every", 0},
                    {"episodes",
                     {{{"index", 0},
                       {"video", "episode_000.mp4"},
                       {"videos", {{"mp4", {{"file", "episode_000.mp4"}, {"frames", 3}}}}},
                       {"sheet", "episode_000_sheet.png"},
                       {"trajectory", "episode_000.json"},
                       {"frames", 3},
                       {"steps", 2},
                       {"complete", true},
                       {"return", -2.0},
                       {"is_success", false},
                       {"hindsight", {{"k", 4}}}}}},
                    {"missing", json::array()},
                    {"failures", json::array()},
                    {"shard", {{"index", 0}, {"count", 1}, {"source", nullptr}, {"episodes", {0}}}},
                    {"jobs", 1},
                    {"worker_mode", "process"},
                    {"workers", json::array()},
                    {"gpu", {{"request", "auto"}}},
                    {"assets", {{"sha256", "cd"}}},
                    {"model_file", "m.xml"},
                    {"camera", "default"},
                    {"overlay", "hud"},
                    {"msaa", 0},
                    {"msaa_reason", ""},
                    {"backend", {{"name", "osmesa"}}},
                    {"layers", {"rgb"}},
                    {"video", {{"crf", 23}}},
                    {"versions", {{"fetchscope", "0.9"}}},
                    {"timings_s", {{"wall", 0.25}}},
                    {"frames", 3},
                    {"interrupted", false},
                    {"incomplete_episodes", json::array()},
                    {"signal", nullptr},
                    {"command_line", "fetchscope record"},
                    {"parameters", ManifestToJson(SampleManifest())["parameters"]},
                    {"resumed", false}};
  const Manifest m = ManifestFromJson(old);
  EXPECT_EQ(m.schema_version, 0);  // no schema_version: the format from before versions
  json written = ManifestToJson(m);
  EXPECT_EQ(written["schema_version"], kManifestSchemaVersion);
  written.erase("schema_version");
  EXPECT_EQ(written, old) << written.dump(1);
}

TEST(ManifestTest, SchemaVersions) {
  json j = ManifestToJson(SampleManifest());
  EXPECT_EQ(ManifestFromJson(j).schema_version, kManifestSchemaVersion);
  j.erase("schema_version");
  EXPECT_EQ(ManifestFromJson(j).schema_version, 0);
  j["schema_version"] = kManifestSchemaVersion + 1;
  TempDir tmp;
  const fs::path file = tmp.path() / "manifest_shard_0001_of_0003.json";
  std::ofstream(file) << j.dump();
  try {
    ReadManifest(file);
    FAIL() << "a newer schema version was read";
  } catch (const ManifestError& e) {
    EXPECT_EQ(std::string(e.what()), "'" + file.string() + "' has manifest schema version " +
                                         std::to_string(kManifestSchemaVersion + 1) +
                                         "; this fetchscope reads versions 0 to " +
                                         std::to_string(kManifestSchemaVersion) +
                                         ": use a newer fetchscope");
  }
  j["schema_version"] = "one";
  EXPECT_THROW(ManifestFromJson(j), ManifestError);
}

TEST(ManifestTest, RefusesWhatIsNotARecordManifest) {
  EXPECT_THROW(ManifestFromJson(json::array({1, 2})), ManifestError);
  EXPECT_THROW(ManifestFromJson({{"env_id", "FetchPush-v4"}}), ManifestError);
  EXPECT_THROW(ManifestFromJson({{"env_id", "x"}, {"episodes", {{{"video", "a.mp4"}}}}}),
               ManifestError);  // an episode without its index
  EXPECT_THROW(ManifestFromJson({{"env_id", "x"}, {"episodes", json::array()}, {"seed", "s"}}),
               ManifestError);
  TempDir tmp;
  std::ofstream(tmp.path() / "m.json") << "{\"env_id\": ";
  try {
    ReadManifest(tmp.path() / "m.json");
    FAIL();
  } catch (const ManifestError& e) {
    EXPECT_NE(std::string(e.what()).find("m.json' is not JSON"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ReadManifest(tmp.path() / "none.json"), ManifestError);
}

TEST(ManifestTest, OlderEpisodesAndNonFiniteReturns) {
  // before --format: "video" alone; before "complete": the step count says it
  const ManifestEpisode old =
      ManifestEpisodeFromJson({{"index", 2}, {"video", "episode_002.webm"}, {"steps", 4}});
  EXPECT_TRUE(old.IsComplete(4));
  EXPECT_FALSE(old.IsComplete(5));
  ASSERT_EQ(EpisodeVideos(old).size(), 1u);
  EXPECT_EQ(EpisodeVideos(old)[0], (EpisodeVideo{"webm", "episode_002.webm", -1}));
  EXPECT_EQ(
      ManifestEpisodeToJson(old),
      json({{"index", 2}, {"video", "episode_002.webm"}, {"steps", 4}, {"is_success", false}}));
  const ManifestEpisode nan = ManifestEpisodeFromJson({{"index", 0}, {"return", "nan"}});
  ASSERT_TRUE(nan.episode_return);
  EXPECT_TRUE(std::isnan(*nan.episode_return));
  EXPECT_EQ(ManifestEpisodeToJson(nan)["return"], "nan");
  EXPECT_EQ(ManifestEpisodeFromJson(ManifestEpisodeToJson(nan)), nan);
  // the videos in the order a browser plays them best
  const std::vector<EpisodeVideo> videos = EpisodeVideos(Episode(3));
  ASSERT_EQ(videos.size(), 2u);
  EXPECT_EQ(videos[0].format, "mp4");
  EXPECT_EQ(videos[1].format, "gif");
}

TEST(ManifestTest, FilesNamesEveryFileOfAnEpisode) {
  const ManifestEpisode e = Episode(7);
  EXPECT_EQ(e.FileNames(),
            (std::vector<std::string>{
                "episode_007.mp4", "episode_007.gif", "episode_007.mp4", "episode_007_sheet.png",
                "episode_007.json", "episode_007_depth.mp4", "episode_007_depth.mp4",
                "episode_007_segmentation.mp4", "episode_007_segmentation.mp4",
                "episode_007_segmentation_legend.json"}));
}

// Each record option, changed alone, is named by SameRun with both values.
struct ParameterCase {
  std::string option;
  void (*change)(RunParameters*);
  std::string a, b;
};

void PrintTo(const ParameterCase& c, std::ostream* os) { *os << c.option; }

class SameRunTest : public ::testing::TestWithParam<ParameterCase> {};

TEST_P(SameRunTest, NamesTheParameterAndBothValues) {
  const ParameterCase& c = GetParam();
  const RunParameters a = Parameters();
  RunParameters b = a;
  c.change(&b);
  const std::optional<RunDifference> d = SameRun(a, b);
  ASSERT_TRUE(d) << c.option;
  EXPECT_EQ(d->parameter, c.option);
  EXPECT_EQ(d->a, c.a);
  EXPECT_EQ(d->b, c.b);
  // the same difference after a round trip through the manifest's JSON
  Manifest ma, mb;
  ma.parameters = a;
  mb.parameters = b;
  const std::optional<RunDifference> read =
      SameRun(ManifestFromJson(ManifestToJson(ma)).parameters,
              ManifestFromJson(ManifestToJson(mb)).parameters);
  ASSERT_TRUE(read);
  EXPECT_EQ(read->parameter, c.option);
}

INSTANTIATE_TEST_SUITE_P(
    EveryOption, SameRunTest,
    ::testing::Values(
        ParameterCase{"--env-id", [](RunParameters* p) { p->env_id = "FetchReach-v4"; },
                      "FetchPush-v4", "FetchReach-v4"},
        ParameterCase{"--seed", [](RunParameters* p) { p->seed = 12; }, "11", "12"},
        ParameterCase{"--policy", [](RunParameters* p) { p->policy = "zero"; }, "random", "zero"},
        ParameterCase{"--replay-dtype", [](RunParameters* p) { p->replay_dtype = "float32"; }, "",
                      "float32"},
        ParameterCase{"--episodes", [](RunParameters* p) { p->episodes = 8; }, "7", "8"},
        ParameterCase{"--steps", [](RunParameters* p) { p->steps = 5; }, "4", "5"},
        ParameterCase{"--sheet-every", [](RunParameters* p) { p->sheet_every = 2; }, "0", "2"},
        ParameterCase{"--assets", [](RunParameters* p) { p->assets_sha256 = "ff"; }, "ab12", "ff"},
        ParameterCase{"--camera", [](RunParameters* p) { p->camera = "front,side"; }, "default",
                      "front,side"},
        ParameterCase{"--overlay", [](RunParameters* p) { p->overlay = "none"; },
                      "goal,achieved,hud,labels", "none"},
        ParameterCase{"--width", [](RunParameters* p) { p->width = 96; }, "64", "96"},
        ParameterCase{"--height", [](RunParameters* p) { p->height = 72; }, "48", "72"},
        ParameterCase{"--msaa", [](RunParameters* p) { p->msaa = "4"; }, "auto", "4"},
        ParameterCase{"--codec", [](RunParameters* p) { p->codec = "h264_nvenc"; }, "libx264",
                      "h264_nvenc"},
        ParameterCase{"--crf", [](RunParameters* p) { p->crf = 30; }, "23", "30"},
        ParameterCase{"--preset", [](RunParameters* p) { p->preset = "fast"; }, "medium", "fast"},
        ParameterCase{"--fps", [](RunParameters* p) { p->fps = 30; }, "25", "30"},
        ParameterCase{"--shard", [](RunParameters* p) { p->shard_index = 0, p->shard_count = 2; },
                      "0/1", "0/2"},
        ParameterCase{"--format",
                      [](RunParameters* p) {
                        p->formats = {"webm", "mp4"};
                      },
                      "mp4", "webm,mp4"},
        ParameterCase{"--layers", [](RunParameters* p) { p->layers = "rgb,depth"; }, "rgb",
                      "rgb,depth"},
        ParameterCase{"--signals", [](RunParameters* p) { p->signals = "contacts"; }, "none",
                      "contacts"}));

TEST(SameRunTest, GifOptionsCountOnlyWithGifs) {
  RunParameters a = Parameters(), b = Parameters();
  b.gif_fps = 5;
  b.gif_width = 100;
  EXPECT_FALSE(SameRun(a, b));  // no gif written: they changed no file
  a.formats = b.formats = {"mp4", "gif"};
  ASSERT_TRUE(SameRun(a, b));
  EXPECT_EQ(SameRun(a, b)->parameter, "--gif-fps");
  EXPECT_EQ(SameRun(a, b)->b, "5");
  b.gif_fps = a.gif_fps;
  ASSERT_TRUE(SameRun(a, b));
  EXPECT_EQ(SameRun(a, b)->parameter, "--gif-width");
}

TEST(SameRunTest, ScopesForShardsAndForCompare) {
  RunParameters a = Parameters(), b = Parameters();
  a.shard_count = b.shard_count = 3;
  a.shard_index = 0;
  b.shard_index = 2;
  EXPECT_TRUE(SameRun(a, b, SameRunScope::kRun));  // --resume: the very same shard
  EXPECT_FALSE(SameRun(a, b, SameRunScope::kShards));
  b.shard_count = 4;
  b.shard_index = 0;
  ASSERT_TRUE(SameRun(a, b, SameRunScope::kShards));  // another split: not one run
  EXPECT_EQ(SameRun(a, b, SameRunScope::kShards)->parameter, "--shard");
  // compare: the same episodes of runs that differ in anything else
  b = Parameters();
  b.policy = "zero";
  b.msaa = "0";
  b.assets_sha256 = "ee";
  EXPECT_FALSE(SameRun(a, b, SameRunScope::kEpisodes));
  b.steps = 9;
  ASSERT_TRUE(SameRun(a, b, SameRunScope::kEpisodes));
  EXPECT_EQ(SameRun(a, b, SameRunScope::kEpisodes)->parameter, "--steps");
  // a manifest from before "parameters" still says env, seed and steps
  const Manifest old = ManifestFromJson({{"env_id", "FetchPush-v4"},
                                         {"seed", 11},
                                         {"steps_per_episode", 4},
                                         {"episodes", json::array()}});
  EXPECT_FALSE(old.parameters.recorded);
  EXPECT_FALSE(SameRun(old.parameters, Parameters(), SameRunScope::kEpisodes));
  EXPECT_FALSE(ManifestToJson(old).contains("parameters"));
}

TEST(SameRunTest, NamesEveryParameterOnce) {
  const std::vector<std::string> names = RunParameterNames();
  EXPECT_EQ(names.front(), "--env-id");
  EXPECT_EQ(names.size(), 23u);
  const json stored = ManifestToJson(SampleManifest())["parameters"];
  for (const std::string& name : names) EXPECT_TRUE(stored.contains(name)) << name;
}

TEST(RunFilesTest, NamesRecordWrites) {
  EXPECT_EQ(EpisodeStem(7), "episode_007");
  EXPECT_EQ(EpisodeStem(1234), "episode_1234");
  EXPECT_EQ(EpisodeVideoFileName(3, "webm"), "episode_003.webm");
  EXPECT_EQ(EpisodeLayerVideoFileName(3, "depth", "gif"), "episode_003_depth.gif");
  EXPECT_EQ(EpisodeLegendFileName(3), "episode_003_segmentation_legend.json");
  EXPECT_EQ(EpisodeSheetFileName(3), "episode_003_sheet.png");
  EXPECT_EQ(EpisodeTrajectoryFileName(3), "episode_003.json");
  EXPECT_EQ(ManifestFileName(0, 1), "manifest.json");
  EXPECT_EQ(ManifestFileName(2, 16), "manifest_shard_0002_of_0016.json");
  EXPECT_EQ(std::string(kReportFileName), "index.html");
  // every name built here is one the run folder recognises as the run's
  for (const std::string& name :
       {EpisodeVideoFileName(3, "gif"), EpisodeLayerVideoFileName(3, "segmentation", "webm"),
        EpisodeLegendFileName(3), EpisodeSheetFileName(3), EpisodeTrajectoryFileName(3)}) {
    const std::optional<RunFileName> parsed = ParseRunFileName(name);
    ASSERT_TRUE(parsed) << name;
    EXPECT_EQ(parsed->episode, 3) << name;
  }
  EXPECT_TRUE(ParseRunFileName(ManifestFileName(1, 4))->manifest);
  EXPECT_TRUE(ParseRunFileName(kReportFileName)->report);
  EXPECT_TRUE(IsShardManifestFileName(ManifestFileName(1, 4)));
  EXPECT_FALSE(IsShardManifestFileName(kManifestFileName));
  EXPECT_TRUE(IsManifestFileName(kManifestFileName));
}

}  // namespace
}  // namespace fetchscope
