// The episode video sink and its parts, in-process: the frame pool (bounded, reused, blocking
// when every buffer is out), EpisodeEncoder (N frames in, an MP4 with N frames, the sheet, the
// trajectory and the manifest entry out; aborts leave no video), and render/layers (the depth
// grey scale, the segmentation legend, the --layers parser).
#include "encode/episode_sink.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "base/errors.h"
#include "cli/view_options.h"
#include "encode/frame_pool.h"
#include "encode/video_reader.h"
#include "render/layers.h"
#include "tests/test_util.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using testing::RunCommand;
using testing::TempDir;

// ---- FramePool

TEST(FramePool, MakesFramesOnlyWhenNeededWithTheirBuffersSized) {
  FramePool pool(3, 12, 2);
  EXPECT_EQ(pool.allocated(), 0u);
  Frame* f = pool.Acquire();
  ASSERT_NE(f, nullptr);
  EXPECT_EQ(pool.allocated(), 1u);
  EXPECT_EQ(f->rgb.size(), 12u);
  ASSERT_EQ(f->layers.size(), 2u);
  EXPECT_EQ(f->layers[0].size(), 12u);
  EXPECT_EQ(f->layers[1].size(), 12u);
}

TEST(FramePool, ReusesAReleasedFrameBeforeMakingANewOne) {
  FramePool pool(3, 12, 0);
  Frame* a = pool.Acquire();
  a->t = 7;
  pool.Release(a);
  Frame* b = pool.Acquire();
  EXPECT_EQ(b, a);
  EXPECT_EQ(b->t, 7);  // a reused frame keeps what it held: the pool does not clear
  EXPECT_EQ(pool.allocated(), 1u);
  pool.Release(nullptr);  // ignored
  Frame* c = pool.Acquire();
  EXPECT_NE(c, a);
  EXPECT_EQ(pool.allocated(), 2u);
}

TEST(FramePool, NeverMakesMoreThanItsCountAndBlocksUntilAFrameIsReleased) {
  FramePool pool(2, 4, 0);
  Frame* a = pool.Acquire();
  Frame* b = pool.Acquire();
  ASSERT_NE(a, b);
  std::atomic<bool> got{false};
  Frame* third = nullptr;
  std::thread waiter([&] {
    third = pool.Acquire();
    got = true;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_FALSE(got.load()) << "Acquire returned with every frame out";
  EXPECT_EQ(pool.allocated(), 2u);
  pool.Release(b);
  waiter.join();
  EXPECT_TRUE(got.load());
  EXPECT_EQ(third, b);
  EXPECT_EQ(pool.allocated(), 2u);
}

// ---- EpisodeEncoder

constexpr int kWidth = 64;
constexpr int kHeight = 48;

EpisodeSinkOptions SinkOptions(const fs::path& out, int steps) {
  EpisodeSinkOptions o;
  o.out = out.string();
  o.env_id = "FetchReachDense-v4";
  o.seed = 5;
  o.seed_text = "5";
  o.policy = "zero";
  o.assets.kind = "bundled";
  o.steps = steps;
  o.cameras = {"default"};
  o.video.width = kWidth;
  o.video.height = kHeight;
  o.video.codec = "libx264";
  o.formats = {FindVideoFormat("mp4")};
  return o;
}

// An episode of `steps` steps (steps + 1 rows) that ends in success.
EpisodeRecord MakeEpisode(int index, int steps) {
  EpisodeRecord episode;
  episode.index = index;
  for (int t = 0; t <= steps; ++t) {
    StepRecord s;
    s.obs = Observation{};  // zeros
    s.t = t;
    if (t > 0) s.reward = -0.5;
    s.is_success = t == steps;
    episode.steps.push_back(s);
  }
  episode.episode_return = -0.5 * steps;
  return episode;
}

// Frame t is a flat grey of 20 + 30 t, so that decoded frames show their order.
uint8_t Grey(int t) { return static_cast<uint8_t>(20 + 30 * t); }

// Renders `frames` frames into `encoder` through `pool`, as the render thread does.
void PushFrames(FramePool* pool, EpisodeEncoder* encoder, int frames) {
  for (int t = 0; t < frames; ++t) {
    Frame* f = pool->Acquire();
    std::fill(f->rgb.begin(), f->rgb.end(), Grey(t));
    for (auto& layer : f->layers) std::fill(layer.begin(), layer.end(), Grey(t));
    f->t = t;
    f->label = "t=" + std::to_string(t);
    encoder->Push(f);
  }
}

double MeanOf(const std::vector<uint8_t>& rgb) {
  double sum = 0;
  for (uint8_t v : rgb) sum += v;
  return sum / rgb.size();
}

TEST(EpisodeEncoder, EncodesEveryFrameIntoAnMp4AndWritesTheEpisodesFiles) {
  TempDir dir;
  const int steps = 5, frames = steps + 1;
  const EpisodeSinkOptions options = SinkOptions(dir.path(), steps);
  // two frames: the encoder must hand each back (it keeps only the latest) or this deadlocks
  FramePool pool(2, static_cast<size_t>(kWidth) * kHeight * 3, 0);
  int done_calls = 0;
  EpisodeResult result;
  {
    EpisodeEncoder encoder(options, 2, &pool, [&](int k, EpisodeResult r) {
      EXPECT_EQ(k, 2);
      ++done_calls;
      result = std::move(r);
    });
    PushFrames(&pool, &encoder, frames);
    EpisodeHindsight hindsight;
    hindsight.k = 4;
    encoder.SetHindsight(hindsight);
    encoder.Close(MakeEpisode(2, steps), 0.25, 0.5);
    encoder.Join();
    EXPECT_TRUE(encoder.finished());
  }
  EXPECT_LE(pool.allocated(), 2u);
  ASSERT_EQ(done_calls, 1);
  const ManifestEpisode& entry = result.entry;
  EXPECT_EQ(entry.index, 2);
  EXPECT_EQ(entry.video, "episode_002.mp4");
  EXPECT_EQ(entry.frames, frames);
  EXPECT_EQ(entry.videos.at("mp4").frames, frames);
  EXPECT_EQ(entry.steps, steps);
  EXPECT_EQ(entry.is_success, true);
  EXPECT_EQ(entry.complete, true);
  EXPECT_EQ(entry.sheet, "episode_002_sheet.png");
  EXPECT_EQ(entry.trajectory, "episode_002.json");
  ASSERT_TRUE(entry.hindsight);
  EXPECT_EQ(entry.hindsight->k, 4);  // SetHindsight's counts join the entry
  EXPECT_DOUBLE_EQ(result.timings.sim, 0.25);
  EXPECT_DOUBLE_EQ(result.timings.render, 0.5);
  EXPECT_TRUE(entry.layers.empty());
  EXPECT_TRUE(fs::exists(dir.path() / "episode_002_sheet.png"));

  // the trajectory names the run as the sink options do
  const nlohmann::json trajectory =
      nlohmann::json::parse(testing::ReadFile(dir.path() / "episode_002.json"));
  EXPECT_EQ(trajectory["env_id"], "FetchReachDense-v4");
  EXPECT_EQ(trajectory["seed"], 5);
  EXPECT_EQ(trajectory["policy"], "zero");
  ASSERT_EQ(trajectory["episodes"].size(), 1u);
  EXPECT_EQ(trajectory["episodes"][0]["index"], 2);

  // decoded back: as many frames as pushed, in order
  const fs::path mp4 = dir.path() / "episode_002.mp4";
  VideoReader reader(mp4.string());
  std::vector<uint8_t> rgb;
  int decoded = 0;
  while (reader.Next(&rgb)) {
    EXPECT_NEAR(MeanOf(rgb), Grey(decoded), 4.0) << "frame " << decoded;
    ++decoded;
  }
  EXPECT_EQ(decoded, frames);

  // and ffprobe agrees, and reads the tags that trace the clip back to its run
  const testing::CommandResult probe = RunCommand(
      "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
      "stream=nb_read_frames:format_tags=env_id,seed,episode -of json '" +
      mp4.string() + "'");
  ASSERT_EQ(probe.exit_code, 0) << probe.output;
  const nlohmann::json j = nlohmann::json::parse(probe.output);
  EXPECT_EQ(j["streams"][0]["nb_read_frames"], std::to_string(frames));
  EXPECT_EQ(j["format"]["tags"]["env_id"], "FetchReachDense-v4");
  EXPECT_EQ(j["format"]["tags"]["seed"], "5");
  EXPECT_EQ(j["format"]["tags"]["episode"], "2");
}

TEST(EpisodeEncoder, WritesOneVideoPerLayerAndFormatWithTheDepthScaleAndLegend) {
  TempDir dir;
  const int steps = 2, frames = steps + 1;
  EpisodeSinkOptions options = SinkOptions(dir.path(), steps);
  options.formats = {FindVideoFormat("mp4"), FindVideoFormat("gif")};
  options.layers = {Layer::kDepth, Layer::kSegmentation};
  options.cameras = {"head_camera_rgb"};
  FramePool pool(3, static_cast<size_t>(kWidth) * kHeight * 3, options.layers.size());
  ManifestEpisode entry;
  EpisodeEncoder encoder(options, 0, &pool, [&](int, EpisodeResult r) { entry = r.entry; });
  PushFrames(&pool, &encoder, frames);
  DepthScale scale;
  scale.width = kWidth;
  scale.height = kHeight;
  scale.near_mm = 500;
  scale.far_mm = 2300;
  encoder.SetLayerInfo({{"episode", 0}, {"objects", nlohmann::json::array()}}, {scale});
  encoder.Close(MakeEpisode(0, steps), 0, 0);
  encoder.Join();

  for (const char* file :
       {"episode_000.mp4", "episode_000.gif", "episode_000_depth.mp4", "episode_000_depth.gif",
        "episode_000_segmentation.mp4", "episode_000_segmentation.gif",
        "episode_000_segmentation_legend.json"}) {
    EXPECT_TRUE(fs::exists(dir.path() / file)) << file;
  }
  const EpisodeLayer& depth = entry.layers.at("depth");
  EXPECT_EQ(depth.video, "episode_000_depth.mp4");
  EXPECT_EQ(depth.videos.at("gif").file, "episode_000_depth.gif");
  EXPECT_EQ(depth.videos.at("mp4").frames, frames);
  ASSERT_EQ(depth.details["scales"].size(), 1u);
  EXPECT_EQ(depth.details["scales"][0]["camera"], "head_camera_rgb");
  EXPECT_DOUBLE_EQ(depth.details["scales"][0]["near_m"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(depth.details["scales"][0]["far_m"].get<double>(), 2.3);
  EXPECT_EQ(entry.layers.at("segmentation").legend, "episode_000_segmentation_legend.json");
  int w = 0, h = 0;
  EXPECT_EQ(ReadAllFrames((dir.path() / "episode_000_depth.mp4").string(), &w, &h).size(),
            static_cast<size_t>(frames));
}

TEST(EpisodeEncoder, AbortLeavesNoVideoAndReportsNothing) {
  TempDir dir;
  const EpisodeSinkOptions options = SinkOptions(dir.path(), 5);
  FramePool pool(2, static_cast<size_t>(kWidth) * kHeight * 3, 0);
  bool done = false;
  {
    EpisodeEncoder encoder(options, 1, &pool, [&](int, EpisodeResult) { done = true; });
    PushFrames(&pool, &encoder, 3);
    // destroyed without Close: as when the render thread fails mid-episode
  }
  EXPECT_FALSE(done);
  for (const auto& entry : fs::directory_iterator(dir.path())) {
    ADD_FAILURE() << "left behind: " << entry.path().filename();
  }
  // every frame came back to the pool
  Frame* a = pool.Acquire();
  Frame* b = pool.Acquire();
  EXPECT_NE(a, b);
  EXPECT_EQ(pool.allocated(), 2u);
}

TEST(EpisodeEncoder, ABadFolderFailsInTheConstructorBeforeAnyFrame) {
  TempDir dir;
  const fs::path file = dir.path() / "a_file";
  { std::ofstream(file.string()) << "x"; }
  const EpisodeSinkOptions options = SinkOptions(file / "sub", 5);
  FramePool pool(2, static_cast<size_t>(kWidth) * kHeight * 3, 0);
  EXPECT_THROW(EpisodeEncoder(options, 0, &pool, [](int, EpisodeResult) {}), RunError);
}

TEST(EpisodeFiles, NamesAndCodecs) {
  EXPECT_EQ(EpisodeFileStem(7), "episode_007");
  EXPECT_EQ(EpisodeFileStem(1234), "episode_1234");
  EXPECT_EQ(LayerVideoName(3, Layer::kDepth, *FindVideoFormat("webm")), "episode_003_depth.webm");
  EXPECT_EQ(LayerVideoName(0, Layer::kSegmentation, *FindVideoFormat("gif")),
            "episode_000_segmentation.gif");
  EXPECT_EQ(FormatCodec(*FindVideoFormat("mp4"), "h264_nvenc"), "h264_nvenc");
  EXPECT_EQ(FormatCodec(*FindVideoFormat("webm"), "libx264"), "libvpx-vp9");
  EXPECT_EQ(FormatCodec(*FindVideoFormat("gif"), "libx264"), "gif");
  EpisodeSinkOptions options = SinkOptions("out", 5);
  options.video.fps = 12;
  const VideoOptions video = EpisodeVideoOptions(options, 4, *FindVideoFormat("webm"));
  EXPECT_EQ(video.format, FindVideoFormat("webm"));
  EXPECT_EQ(video.fps, 12);
  ASSERT_FALSE(video.metadata.empty());
  EXPECT_EQ(video.metadata[0].first, "title");
  EXPECT_EQ(video.metadata[0].second, "FetchReachDense-v4 seed 5 episode 4 (zero)");
}

// ---- render/layers

TEST(Layers, NamesLabelsAndRecordsLayersBeyondRgb) {
  EXPECT_STREQ(LayerName(Layer::kRgb), "rgb");
  EXPECT_STREQ(LayerName(Layer::kDepth), "depth");
  EXPECT_STREQ(LayerName(Layer::kSegmentation), "segmentation");
  EXPECT_EQ(cli::ParseRecordLayers("rgb"), std::vector<Layer>{});
  EXPECT_EQ(cli::ParseRecordLayers("segmentation, rgb, depth"),
            (std::vector<Layer>{Layer::kSegmentation, Layer::kDepth}));
  EXPECT_EQ(LayersLabel({}), "rgb");
  EXPECT_EQ(LayersLabel({Layer::kSegmentation, Layer::kDepth}), "rgb,segmentation,depth");
}

TEST(Layers, ParseLayersNamesWhatIsWrong) {
  struct Case {
    const char* list;
    const char* message;
  };
  for (const Case& c : {Case{"rgb,,depth", "has an empty entry"},
                        Case{"rgb,dpeth", "unknown layer 'dpeth' (did you mean 'depth'?)"},
                        Case{"depth,depth", "names 'depth' twice"}}) {
    try {
      cli::ParseLayers(c.list);
      ADD_FAILURE() << c.list << " accepted";
    } catch (const UsageError& e) {
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos)
          << c.list << ": " << e.what();
    }
  }
}

// A frame of `width` x `height` millimetres, row 0 at the top, as RenderLayer's kDepth bytes.
std::vector<uint8_t> DepthFrame(const std::vector<uint16_t>& mm) {
  std::vector<uint8_t> bytes(mm.size() * 2);
  std::memcpy(bytes.data(), mm.data(), bytes.size());
  return bytes;
}

TEST(DepthScale, IsFixedFromTheViewsNearestAndFarthestDepthRoundedTo10Cm) {
  // a 4 x 4 frame, two views stacked: the top one (bottom-left origin: bottom 2) and the
  // bottom one (bottom 0), which sees nothing
  const std::vector<uint16_t> mm = {0,    1234, 2345, 1500,  //
                                    1300, 1300, 1300, 1300,  //
                                    0,    0,    0,    0,     //
                                    0,    0,    0,    0};
  const std::vector<mjrRect> tiles = {{0, 2, 4, 2}, {0, 0, 4, 2}};
  const std::vector<DepthScale> scales = ScalesFromFrame(DepthFrame(mm), 4, 4, tiles);
  ASSERT_EQ(scales.size(), 2u);
  EXPECT_EQ(scales[0].y, 0);
  EXPECT_EQ(scales[0].height, 2);
  EXPECT_EQ(scales[0].near_mm, 1200);
  EXPECT_EQ(scales[0].far_mm, 2400);
  EXPECT_EQ(scales[1].y, 2);
  EXPECT_EQ(scales[1].near_mm, 0);  // nothing in view: 0 .. 10 m
  EXPECT_EQ(scales[1].far_mm, 10000);
}

TEST(DepthScale, GreyIsWhiteNearDarkFarBlackForNoDepthAndOutsideEveryView) {
  // one row: near, far, beyond far, nearer than near, no depth, outside the view
  const std::vector<uint16_t> mm = {1000, 2000, 3000, 500, 0, 1500};
  DepthScale scale;
  scale.width = 5;
  scale.height = 1;
  scale.near_mm = 1000;
  scale.far_mm = 2000;
  std::vector<uint8_t> rgb(mm.size() * 3, 99);
  DepthToGrey(DepthFrame(mm), 6, {scale}, rgb.data());
  const std::vector<uint8_t> expected_grey = {255, 32, 32, 255, 0, 0};
  for (size_t i = 0; i < mm.size(); ++i) {
    EXPECT_EQ(rgb[3 * i], expected_grey[i]) << "pixel " << i;
    EXPECT_EQ(rgb[3 * i + 1], rgb[3 * i]);
    EXPECT_EQ(rgb[3 * i + 2], rgb[3 * i]);
  }
  // halfway: 255 - 223 / 2, rounded
  std::vector<uint8_t> mid(3);
  DepthToGrey(DepthFrame({1500}), 1, {DepthScale{0, 0, 1, 1, 1000, 2000}}, mid.data());
  EXPECT_EQ(mid[0], 144);
}

SegmentObject Object(int index, const std::string& body, std::vector<std::string> geoms,
                     long pixels) {
  SegmentObject o;
  o.index = index;
  o.color = {static_cast<uint8_t>(index), 0x80, 0xff};
  o.body = body;
  o.geoms = std::move(geoms);
  o.pixels = pixels;
  return o;
}

TEST(EpisodeLegend, SumsPixelsAndFramesAndUnitesGeomsOverTheEpisode) {
  EpisodeLegend legend;
  legend.Add({Object(5, "table0", {"table0:geom"}, 10)});
  legend.Add({Object(5, "table0", {"geom 3"}, 20), Object(9, "object0", {"object0"}, 4)});
  legend.Add({});
  EXPECT_EQ(legend.frames(), 3);
  const nlohmann::json j = legend.Json(6);
  EXPECT_EQ(j["episode"], 6);
  EXPECT_EQ(j["frames"], 3);
  EXPECT_EQ(j["background"], "#000000");
  ASSERT_EQ(j["objects"].size(), 2u);
  const nlohmann::json& table = j["objects"][0];  // by palette index
  EXPECT_EQ(table["body"], "table0");
  EXPECT_EQ(table["pixels"], 30);
  EXPECT_EQ(table["frames"], 2);
  EXPECT_EQ(table["geoms"], (nlohmann::json{"geom 3", "table0:geom"}));
  EXPECT_EQ(table["color"], "#0580ff");
  EXPECT_EQ(table["rgb"], (nlohmann::json{5, 128, 255}));
  EXPECT_TRUE(table["site"].is_null());
  EXPECT_EQ(j["objects"][1]["body"], "object0");
  EXPECT_EQ(j["objects"][1]["frames"], 1);
}

}  // namespace
}  // namespace fetchscope
