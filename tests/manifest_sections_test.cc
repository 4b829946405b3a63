// The manifest's typed sections (run/manifest_sections.h): each round-trips through the one reader
// and writer, keeps what it does not know, refuses what is not an object; a too-new manifest is
// refused; and an episode's result (encode/episode_result.h) crosses the worker channel's JSON
// (run/record_run.h) unchanged.
#include "run/manifest_sections.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "run/manifest.h"
#include "run/record_run.h"

namespace fetchscope {
namespace {

using nlohmann::json;

ManifestVideo SampleVideo() {
  ManifestVideo v;
  v.codec = "libx264, gif";
  v.codecs = std::map<std::string, std::string>{{"mp4", "libx264"}, {"gif", "gif"}};
  v.codec_reason = "libx264: no NVENC";
  v.crf = 23;
  v.preset = "medium";
  v.fps = 25;
  v.width = 63;
  v.height = 48;
  v.encoded_width = 64;
  v.encoded_height = 48;
  v.encoder_threads = 1;
  v.x264_params = "threads=1";
  v.encoders_per_worker = 2;
  v.container = "mp4";
  v.formats = std::vector<std::string>{"mp4", "gif"};
  v.gif = ManifestVideoGif{10, 320, json::object()};
  v.pix_fmt = "yuv420p";
  return v;
}

ManifestWorker SampleWorker(int w) {
  ManifestWorker worker;
  worker.worker = w;
  worker.pid = 4242 + w;
  worker.backend = "egl";
  worker.device = "EGL device 1";
  worker.device_selection = "--gpu 1";
  worker.gl_vendor = "NVIDIA Corporation";
  worker.gl_renderer = "NVIDIA H100";
  worker.gl_version = "4.6";
  worker.msaa = 4;
  worker.msaa_reason = "auto";
  worker.readback = "async";
  worker.episodes = std::vector<int>{w, w + 2};
  return worker;
}

ManifestTimings SampleTimings() {
  ManifestTimings t;
  t.wall = 2.5;
  t.sim = 0.25;
  t.render = 1.125;
  t.encode = 0.75;
  t.write = 0.0625;
  t.cpu_s = std::map<std::string, double>{{"gl", 0.5}, {"process", 3.0}};
  t.cpu_ms_per_frame = std::map<std::string, double>{{"gl", 1.5}, {"process", 9.0}};
  return t;
}

TEST(ManifestSections, VideoRoundTrips) {
  const ManifestVideo v = SampleVideo();
  const json j = ManifestVideoToJson(v);
  EXPECT_EQ(j["gif"]["fps"], 10);
  EXPECT_EQ(j["codecs"]["gif"], "gif");
  EXPECT_EQ(j.size(), 17u);  // every member written, none twice
  EXPECT_EQ(ManifestVideoFromJson(j), v);
  EXPECT_EQ(ManifestVideoToJson(ManifestVideoFromJson(j)).dump(), j.dump());
}

TEST(ManifestSections, BackendGpuWorkersAndTimingsRoundTrip) {
  ManifestBackend b;
  b.name = "osmesa";
  b.device = "cpu";
  b.gl_vendor = "Mesa";
  b.gl_renderer = "llvmpipe";
  b.gl_version = "4.5";
  EXPECT_EQ(ManifestBackendFromJson(ManifestBackendToJson(b)), b);
  EXPECT_EQ(ManifestBackendToJson(b)["gl_renderer"], "llvmpipe");

  ManifestGpu g;
  g.request = "cuda:1";
  g.choice = "--gpu cuda:1 = EGL device 2";
  g.devices = std::vector<int>{2};
  EXPECT_EQ(ManifestGpuFromJson(ManifestGpuToJson(g)), g);
  EXPECT_EQ(ManifestGpuToJson(g)["devices"], json::array({2}));

  const std::vector<ManifestWorker> workers = {SampleWorker(0), SampleWorker(1)};
  const json wj = ManifestWorkersToJson(workers);
  ASSERT_EQ(wj.size(), 2u);
  EXPECT_EQ(wj[1]["pid"], 4243);
  EXPECT_EQ(ManifestWorkersFromJson(wj), workers);

  const ManifestTimings t = SampleTimings();
  const json tj = ManifestTimingsToJson(t);
  EXPECT_FALSE(tj.contains("wall_sum"));  // an unset member is not written
  EXPECT_DOUBLE_EQ(tj["cpu_ms_per_frame"]["gl"].get<double>(), 1.5);
  EXPECT_EQ(ManifestTimingsFromJson(tj), t);
}

// What a later fetchscope adds, and a member of an unexpected type, come back exactly as they were.
TEST(ManifestSections, UnknownMembersAndOtherTypesAreKeptAsTheyWere) {
  const json video = {{"fps", 25.0},  // a double where an int is read: kept, not read
                      {"crf", 23},
                      {"hdr", {{"transfer", "pq"}}},
                      {"gif", {{"fps", 10}, {"dither", "bayer"}}}};
  const ManifestVideo v = ManifestVideoFromJson(video);
  EXPECT_FALSE(v.fps);
  EXPECT_EQ(v.crf, 23);
  ASSERT_TRUE(v.gif);
  EXPECT_EQ(v.gif->fps, 10);
  EXPECT_EQ(v.gif->extra, (json{{"dither", "bayer"}}));
  EXPECT_TRUE(v.extra.contains("hdr"));
  EXPECT_EQ(ManifestVideoToJson(v).dump(), video.dump());

  const json timings = {{"wall", 1}, {"sim", 0.5}, {"gpu_s", 0.25}};  // wall: an int
  const ManifestTimings t = ManifestTimingsFromJson(timings);
  EXPECT_FALSE(t.wall);
  EXPECT_EQ(t.sim, 0.5);
  EXPECT_EQ(ManifestTimingsToJson(t).dump(), timings.dump());
}

TEST(ManifestSections, ASectionThatIsNotAnObjectIsRefused) {
  EXPECT_THROW(ManifestVideoFromJson(json::array()), ManifestError);
  EXPECT_THROW(ManifestBackendFromJson("egl"), ManifestError);
  EXPECT_THROW(ManifestWorkersFromJson(json::object()), ManifestError);
  EXPECT_THROW(ManifestWorkersFromJson(json::array({1})), ManifestError);
  json m = {{"env_id", "FetchPush-v4"}, {"episodes", json::array()}, {"gpu", 3}};
  EXPECT_THROW(ManifestFromJson(m), ManifestError);
}

// The sections through the whole manifest: written by the one writer, read by the one reader.
TEST(ManifestSections, RoundTripThroughTheManifest) {
  Manifest m;
  m.env_id = "FetchPush-v4";
  m.video = SampleVideo();
  m.backend.name = "egl";
  m.gpu.request = "auto";
  m.workers = {SampleWorker(0)};
  m.timings_s = SampleTimings();
  const json j = ManifestToJson(m);
  EXPECT_EQ(j["video"]["container"], "mp4");
  EXPECT_EQ(j["workers"][0]["readback"], "async");
  EXPECT_EQ(j["timings_s"]["wall"], 2.5);
  const Manifest back = ManifestFromJson(j);
  EXPECT_EQ(back.video, m.video);
  EXPECT_EQ(back.workers, m.workers);
  EXPECT_EQ(back.timings_s, m.timings_s);
  EXPECT_EQ(back, m);
}

TEST(ManifestSections, ATooNewSchemaVersionIsRefused) {
  Manifest m;
  m.env_id = "FetchPush-v4";
  json j = ManifestToJson(m);
  j["schema_version"] = kManifestSchemaVersion + 1;
  j["video"] = "a layout this build does not know";
  try {
    ManifestFromJson(j);
    FAIL() << "a newer schema version was read";
  } catch (const ManifestError& e) {
    EXPECT_NE(std::string(e.what()).find("use a newer fetchscope"), std::string::npos) << e.what();
  }
}

TEST(EpisodeResultChannel, AResultThroughTheChannelsJsonComesBackEqual) {
  EpisodeResult r;
  r.worker = 3;
  ManifestEpisode& e = r.entry;
  e.index = 7;
  e.video = "episode_007.mp4";
  e.videos["mp4"] = {"episode_007.mp4", 51};
  e.sheet = "episode_007_sheet.png";
  e.trajectory = "episode_007.json";
  e.frames = 51;
  e.steps = 50;
  e.complete = false;
  e.episode_return = -1.0 / 3.0;
  e.is_success = true;
  e.hindsight = EpisodeHindsight{12, 3, 4, 50, json::object()};
  EpisodeLayer depth;
  depth.video = "episode_007_depth.mp4";
  depth.videos["mp4"] = {depth.video, 51};
  depth.details = {{"mapping", "grey"}};
  e.layers["depth"] = depth;
  r.timings = {0.1, 0.2, 0.30000000000000004, 0.4, {{"gl", 0.01}, {"sim", 1e-7}}};
  const json channel = EpisodeResultToJson(r);
  EXPECT_FALSE(channel["entry"].contains("worker"));  // the worker is the result's, not the entry's
  const EpisodeResult back = EpisodeResultFromJson(json::parse(channel.dump()));
  EXPECT_EQ(back, r);
  EXPECT_EQ(back.timings.encode, 0.30000000000000004);  // every bit of every number

  // an infinite return too (JsonDouble's "inf")
  r.entry.episode_return = HUGE_VAL;
  EXPECT_EQ(EpisodeResultFromJson(json::parse(EpisodeResultToJson(r).dump())), r);
  EXPECT_THROW(EpisodeResultFromJson({{"entry", {{"index", 1}}}}), ManifestError);
}

}  // namespace
}  // namespace fetchscope
