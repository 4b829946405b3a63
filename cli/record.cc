// fetchscope record: episodes -> a run folder of videos, contact sheets, trajectories and
// one manifest. The episodes run on the episode scheduler (cli/episode_scheduler.h): --jobs N
// worker processes, each with its own env, policy, GL context, renderer and encoders; the
// parent decides the GPUs and the encoder once (cli/node_probe.h), owns progress and signals,
// and writes the manifest. In a worker, rendering and encoding overlap: the render thread
// steps and renders into a pool of reused frame buffers, and each episode is encoded by its
// own single-threaded encoder thread, up to a few episodes at once (the encoder budget).
// --shard I/N records every N-th episode so that machines split a batch. Either way episode k
// comes out exactly as in a sequential run, byte for byte.
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <thread>

#include "base/errors.h"
#include "base/json_util.h"
#include "base/suggest.h"
#include "cli/command.h"
#include "cli/common.h"
#include "cli/jobs_options.h"
#include "cli/record_from.h"
#include "cli/render_common.h"
#include "encode/contact_sheet.h"
#include "encode/png_io.h"
#include "encode/video_writer.h"
#include "inspect/report.h"
#include "render/renderer.h"
#include "run/episode_scheduler.h"
#include "run/node_probe.h"
#include "run/progress.h"
#include "run/run_folder.h"
#include "run/shard.h"
#include "src/hindsight.h"

namespace fetchscope::cli {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

struct RecordOptions {
  EnvOptions env;
  ViewOptions view;
  int episodes = 1;
  int steps = 50;
  std::string policy = "random";
  double exec_timeout = 10.0;
  int fps = 25;
  std::string codec = "auto";
  int crf = 23;
  std::string preset;
  std::string formats = "mp4";  // --format: comma list of mp4, webm, gif
  int gif_fps = 10;
  int gif_width = 320;
  int sheet_every = 0;
  std::string out = "out";
  bool quiet = false;
  int jobs = 1;  // workers; 0 = one per core
  std::string worker_mode = "process";
  std::string shard;            // "I/N"; empty: from the environment, else the whole run
  int shard_count = 0;          // with JOB_COMPLETION_INDEX; 0 = not given
  bool overwrite = false;       // replace the run already in --out
  bool resume = false;          // continue the run already in --out
  std::string replay_dtype;     // --replay-dtype: "", float32, float64
  bool episodes_given = false;  // --episodes was on the command line
  bool no_report = false;       // no index.html (cli/report.h)
  std::string from;             // record --from: a run folder or trajectory JSON
  std::string layers = "rgb";   // --layers: rgb plus depth, segmentation
};

// Everything the parent decided before the workers start; workers only read it.
struct RecordPlan {
  const RecordOptions* o = nullptr;
  const EnvSpec* spec = nullptr;
  uint64_t seed = 0;
  AssetSource assets;
  PolicyContext policy_context;
  VideoOptions video;                // codec already decided; format and metadata set per file
  std::vector<std::string> formats;  // --format, in the order given
  GpuChoice gpu;                     // EGL devices, worker w on devices[w % size]
  int encoders = 1;                  // episodes a worker encodes at once
  const TrajectorySource* from = nullptr;  // record --from: the episodes to replay
  bool hindsight = false;     // the hindsight overlay: run the episode first, then render it
  std::vector<Layer> layers;  // --layers beyond rgb (depth, segmentation), in the order given
};

// One rendered frame travelling from the render thread to an episode's encoder thread.
struct Frame {
  std::vector<uint8_t> rgb;
  std::vector<std::vector<uint8_t>> layers;  // RecordPlan::layers as rgb, in that order
  int t = 0;
  std::string label;
};

// A bounded pool of frame buffers shared by a worker's render thread and its encoder threads:
// no per-frame allocation, and a render thread that runs ahead waits for a free one.
class FramePool {
 public:
  /// At most `count` frames of `bytes` each (and `layers` layer images of as many), made when
  /// first needed: a run whose render thread never gets ahead of its encoders never holds more
  /// than the few it cycles through.
  FramePool(size_t count, size_t bytes, size_t layers)
      : count_(count), bytes_(bytes), layers_(layers) {}
  Frame* Acquire() {
    std::unique_lock<std::mutex> lock(mutex_);
    if (free_.empty() && pool_.size() < count_) {
      pool_.push_back(std::make_unique<Frame>());
      pool_.back()->rgb.resize(bytes_);
      pool_.back()->layers.assign(layers_, std::vector<uint8_t>(bytes_));
      return pool_.back().get();
    }
    cv_.wait(lock, [&] { return !free_.empty(); });
    Frame* f = free_.front();
    free_.pop_front();
    return f;
  }
  void Release(Frame* f) {
    if (!f) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      free_.push_back(f);
    }
    cv_.notify_one();
  }

 private:
  const size_t count_;
  const size_t bytes_;
  const size_t layers_;
  std::vector<std::unique_ptr<Frame>> pool_;
  std::deque<Frame*> free_;
  std::mutex mutex_;
  std::condition_variable cv_;
};

std::string TileLabel(const FrameInfo& info) {
  char line1[96], line2[96];
  if (info.step == 0) {
    std::snprintf(line1, sizeof(line1), "t=0 reset");
  } else {
    std::snprintf(line1, sizeof(line1), "t=%d r=%.3g", info.step, info.reward);
  }
  std::snprintf(line2, sizeof(line2), "d=%.3f %s", info.distance, info.success ? "SUCCESS" : "");
  return std::string(line1) + "\n" + line2;
}

std::string EpisodeName(int k) {
  char name[32];
  std::snprintf(name, sizeof(name), "episode_%03d", k);
  return name;
}

// A layer's name as --layers, the file names and the manifest write it.
const char* LayerName(Layer layer) {
  switch (layer) {
    case Layer::kRgb:
      return "rgb";
    case Layer::kDepth:
      return "depth";
    case Layer::kSegmentation:
      return "segmentation";
  }
  return "?";
}

// --layers beyond rgb, in the order given: rgb is always recorded (the episode video, sheet and
// report need it).
std::vector<Layer> ParseRecordLayers(const std::string& list) {
  std::vector<Layer> extra;
  for (Layer layer : ParseLayers(list)) {
    if (layer != Layer::kRgb) extra.push_back(layer);
  }
  return extra;
}

// The --layers list the manifest and --resume compare: "rgb" and the extra layers in order.
std::string LayersLabel(const std::vector<Layer>& layers) {
  std::string label = "rgb";
  for (Layer layer : layers) label += std::string(",") + LayerName(layer);
  return label;
}

// The depth video's grey scale for one camera's view in one episode, fixed from the episode's
// reset frame so that a shade means the same distance all episode long: `near_mm` (the nearest
// depth in the view, rounded down to 10 cm) is white, `far_mm` (the farthest, rounded up) dark
// grey 32; nearer is clamped to white, farther to 32, and no depth (sky, nothing hit) is black.
struct DepthScale {
  int x = 0, y = 0, width = 0, height = 0;  // the view in the frame, pixels, row 0 at the top
  int near_mm = 0;
  int far_mm = 0;
};

// One scale per view of the frame (`tiles`: the renderer's, bottom-left origin), from `depth`
// (RenderLayer's millimetres of a `frame_width` x `frame_height` frame).
std::vector<DepthScale> ScalesFromFrame(const std::vector<uint8_t>& depth, int frame_width,
                                        int frame_height, const std::vector<mjrRect>& tiles) {
  const uint16_t* mm = reinterpret_cast<const uint16_t*>(depth.data());
  std::vector<DepthScale> scales;
  for (const mjrRect& tile : tiles) {
    DepthScale scale;
    scale.x = tile.left;
    scale.y = frame_height - tile.bottom - tile.height;
    scale.width = tile.width;
    scale.height = tile.height;
    int lo = 65535, hi = 0;
    for (int r = scale.y; r < scale.y + scale.height; ++r) {
      for (int c = scale.x; c < scale.x + scale.width; ++c) {
        const int v = mm[static_cast<size_t>(r) * frame_width + c];
        if (v == 0) continue;
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
    }
    if (hi == 0) {  // nothing in view at reset: 0..10 m
      lo = 0;
      hi = 10000;
    }
    scale.near_mm = lo / 100 * 100;
    scale.far_mm = std::max((hi + 99) / 100 * 100, scale.near_mm + 100);
    scales.push_back(scale);
  }
  return scales;
}

// Depth in millimetres (RenderLayer's uint16) -> grey rgb, each view with its scale; pixels in
// no view (the empty cells of a grid) stay black.
void DepthToGrey(const std::vector<uint8_t>& depth, int frame_width,
                 const std::vector<DepthScale>& scales, uint8_t* rgb) {
  const uint16_t* mm = reinterpret_cast<const uint16_t*>(depth.data());
  std::fill(rgb, rgb + depth.size() / 2 * 3, 0);
  for (const DepthScale& s : scales) {
    const double span = s.far_mm - s.near_mm;
    for (int r = s.y; r < s.y + s.height; ++r) {
      for (int c = s.x; c < s.x + s.width; ++c) {
        const size_t i = static_cast<size_t>(r) * frame_width + c;
        if (mm[i] == 0) continue;
        const double f = std::clamp((mm[i] - s.near_mm) / span, 0.0, 1.0);
        const auto grey = static_cast<uint8_t>(std::lround(255.0 - 223.0 * f));
        rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = grey;
      }
    }
  }
}

// One episode's segmentation legend: every object seen in any of its frames, with the pixels
// of all frames summed, the frames it appears in, and the geoms seen.
class EpisodeLegend {
 public:
  void Add(const std::vector<SegmentObject>& frame) {
    ++frames_;
    for (const SegmentObject& o : frame) {
      Entry& e = objects_[o.index];
      e.object.index = o.index;
      e.object.color = o.color;
      e.object.body = o.body;
      e.object.site = o.site;
      e.object.pixels += o.pixels;
      e.geoms.insert(o.geoms.begin(), o.geoms.end());
      ++e.frames;
    }
  }
  /// The legend JSON; the colour of each object is the same in every episode, camera and run.
  nlohmann::json Json(int episode) const {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& [index, e] : objects_) {
      SegmentObject object = e.object;
      object.geoms.assign(e.geoms.begin(), e.geoms.end());
      nlohmann::json entry = SegmentObjectJson(object);
      entry["frames"] = e.frames;
      list.push_back(std::move(entry));
    }
    return {{"episode", episode},
            {"frames", frames_},
            {"background", "#000000"},
            {"note",
             "one colour per body (all its geoms) or site, the same in every frame; "
             "pixels and frames summed over the episode's video. Lossy video shifts "
             "colours slightly: match a pixel to the nearest colour here"},
            {"objects", list}};
  }

 private:
  struct Entry {
    SegmentObject object;
    std::set<std::string> geoms;
    int frames = 0;
  };
  std::map<int, Entry> objects_;  // by palette index
  int frames_ = 0;
};

// The file of episode k's `layer` video in `format`: episode_000_depth.mp4.
std::string LayerVideoName(int k, Layer layer, const std::string& format) {
  return EpisodeName(k) + "_" + LayerName(layer) + "." + VideoFormatExtension(format);
}

// The codec each format's file is encoded with: mp4 with the run's H.264 decision.
std::string FormatCodec(const std::string& format, const std::string& h264) {
  if (format == "mp4") return h264;
  if (format == "webm") return "libvpx-vp9";
  return format;  // gif
}

// The options of episode k's video in `format`: the plan's encoder settings plus the tags that
// trace a clip found alone back to its run (ffprobe -show_format lists them).
VideoOptions EpisodeVideoOptions(const RecordPlan& plan, int k, const std::string& format) {
  VideoOptions video = plan.video;
  video.format = format;
  video.metadata = {{"title", plan.spec->id + " seed " + std::to_string(plan.seed) + " episode " +
                                  std::to_string(k) + " (" + plan.o->policy + ")"},
                    {"env_id", plan.spec->id},
                    {"seed", std::to_string(plan.seed)},
                    {"policy", plan.o->policy},
                    {"episode", std::to_string(k)},
                    {"fetchscope_version", FETCHSCOPE_VERSION}};
  return video;
}

// One episode's encoding, on its own thread: the video frame by frame as frames arrive, then
// the contact sheet, the trajectory JSON and the manifest entry, reported to the scheduler.
class EpisodeEncoder {
 public:
  EpisodeEncoder(const RecordPlan& plan, int k, int worker, FramePool* pool, WorkerChannel* channel)
      : plan_(plan),
        k_(k),
        worker_(worker),
        pool_(*pool),
        channel_(*channel),
        name_(EpisodeName(k)) {
    const std::vector<int> indices = SheetFrameIndices(plan.o->steps + 1, plan.o->sheet_every);
    on_sheet_.insert(indices.begin(), indices.end());
    // the writers open here, on the render thread, so a bad folder fails before any frame
    for (const std::string& format : plan.formats) {
      writers_.emplace_back(
          (fs::path(plan.o->out) / (name_ + "." + VideoFormatExtension(format))).string(),
          EpisodeVideoOptions(plan, k, format));
    }
    for (Layer layer : plan.layers) {
      for (const std::string& format : plan.formats) {
        VideoOptions options = EpisodeVideoOptions(plan, k, format);
        options.metadata.emplace_back("layer", LayerName(layer));
        layer_writers_.emplace_back(
            (fs::path(plan.o->out) / LayerVideoName(k, layer, format)).string(), options);
      }
    }
    thread_ = std::thread([this] { Body(); });
  }
  ~EpisodeEncoder() {
    if (thread_.joinable()) {
      Abort();
      thread_.join();
    }
  }

  /// Hands a rendered frame over (render thread); the encoder returns it to the pool.
  void Push(Frame* f) { Enqueue(f, Command::kFrame); }
  /// No more frames: finish the files with `episode` as the trajectory; sim_s and render_s
  /// are the render thread's seconds, for the manifest.
  void Close(EpisodeRecord episode, double sim_s, double render_s) {
    episode_ = std::move(episode);
    sim_s_ = sim_s;
    render_s_ = render_s;
    Enqueue(nullptr, Command::kClose);
  }
  /// Members added to the manifest entry (e.g. "hindsight"); call before Close.
  void SetExtra(nlohmann::json extra) { extra_ = std::move(extra); }
  /// The layers' extras: the segmentation legend JSON (written beside the videos) and the depth
  /// scale (in the manifest entry); call before Close.
  void SetLayerInfo(nlohmann::json legend, std::vector<DepthScale> depth) {
    legend_ = std::move(legend);
    depth_scales_ = std::move(depth);
  }
  /// No more frames and no files: the partial video is removed.
  void Abort() { Enqueue(nullptr, Command::kAbort); }
  /// Waits for the thread; rethrows its failure.
  void Join() {
    if (thread_.joinable()) thread_.join();
    if (error_) std::rethrow_exception(error_);
  }
  bool finished() const { return finished_.load(); }

 private:
  enum class Command { kFrame, kClose, kAbort };

  void Enqueue(Frame* f, Command c) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      queue_.push_back({f, c});
    }
    cv_.notify_one();
  }

  void Body() {
    Frame* held = nullptr;  // the latest frame, kept until the next: the sheet's last tile
    while (true) {
      std::pair<Frame*, Command> item;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        cv_.wait(lock, [&] { return !queue_.empty(); });
        item = queue_.front();
        queue_.pop_front();
      }
      if (item.second == Command::kFrame) {
        Frame* f = item.first;
        if (!error_) {
          try {
            const auto t0 = Clock::now();
            for (VideoWriter& writer : writers_) writer.AddFrame(f->rgb.data());
            const size_t formats = plan_.formats.size();
            for (size_t i = 0; i < layer_writers_.size(); ++i) {
              layer_writers_[i].AddFrame(f->layers[i / formats].data());
            }
            encode_s_ += Since(t0);
            if (on_sheet_.count(f->t)) AddTile(*f);
          } catch (...) {
            error_ = std::current_exception();
          }
        }
        pool_.Release(held);  // keeps draining after a failure: the render thread never stalls
        held = f;
        continue;
      }
      if (item.second == Command::kClose && !error_) {
        try {
          if (held && !on_sheet_.count(held->t)) AddTile(*held);
          pool_.Release(held);
          held = nullptr;
          Finalize();
        } catch (...) {
          error_ = std::current_exception();
        }
      }
      pool_.Release(held);
      if (error_ || item.second == Command::kAbort) {  // removes the partial videos
        writers_.clear();
        layer_writers_.clear();
      }
      finished_.store(true);
      return;
    }
  }

  void AddTile(const Frame& f) {
    tiles_.push_back({f.rgb, plan_.video.width, plan_.video.height, f.label});
  }

  void Finalize() {
    const RecordOptions& o = *plan_.o;
    const auto t0 = Clock::now();
    for (VideoWriter& writer : writers_) writer.Finish();
    for (VideoWriter& writer : layer_writers_) writer.Finish();
    const int steps = static_cast<int>(episode_.steps.size()) - 1;
    const bool complete = episode_.complete;  // false: ended early by SIGINT/SIGTERM
    char title[256];
    std::snprintf(title, sizeof(title), "%s  seed %s  policy %s  episode %d%s",
                  plan_.spec->id.c_str(), o.env.seed.c_str(), o.policy.c_str(), k_,
                  complete ? "" : "  (interrupted)");
    const SheetImage sheet = MakeContactSheet(title, tiles_);
    WritePng((fs::path(o.out) / (name_ + "_sheet.png")).string(), sheet.width, sheet.height, 3, 8,
             sheet.rgb.data());
    // the trajectory's env fields come from the spec and assets, as TrajectoryJson writes them
    nlohmann::json trajectory = {{"env_id", plan_.spec->id},
                                 {"seed", plan_.seed},
                                 {"policy", o.policy},
                                 {"assets", AssetsJson(plan_.assets)},
                                 {"episodes", nlohmann::json::array({EpisodeJson(episode_)})}};
    WriteJson((fs::path(o.out) / (name_ + ".json")).string(), trajectory);
    const nlohmann::json layers = FinishLayers();
    const double write_s = Since(t0);
    const bool success = episode_.steps.back().is_success;
    nlohmann::json videos = nlohmann::json::object();  // format -> file and frames in it
    for (size_t i = 0; i < writers_.size(); ++i) {
      videos[plan_.formats[i]] = {{"file", fs::path(writers_[i].path()).filename().string()},
                                  {"frames", writers_[i].frames_encoded()}};
    }
    const VideoWriter& first = writers_.front();
    nlohmann::json entry = {
        {"index", k_},
        {"video", fs::path(first.path()).filename().string()},
        {"videos", videos},
        {"sheet", name_ + "_sheet.png"},
        {"trajectory", name_ + ".json"},
        {"frames", first.frames_written()},
        {"steps", steps},
        {"complete", complete},
        {"return", JsonDouble(episode_.episode_return)},
        {"is_success", success},
        {"worker", worker_},
        {"codec", first.codec_name()},
        {"encoded_width", first.encoded_width()},
        {"encoded_height", first.encoded_height()},
        {"timings_s",
         {{"sim", sim_s_}, {"render", render_s_}, {"encode", encode_s_}, {"write", write_s}}}};
    if (!layers.empty()) entry["layers"] = layers;
    if (extra_.is_object()) entry.update(extra_);
    channel_.Done(k_, entry);
  }

  // The manifest entry's "layers" (empty without --layers): per layer its videos as "videos"
  // lists them, the first format's file as "video", the depth scale or the segmentation legend
  // (written here).
  nlohmann::json FinishLayers() {
    nlohmann::json layers = nlohmann::json::object();
    const size_t formats = plan_.formats.size();
    for (size_t l = 0; l < plan_.layers.size(); ++l) {
      const Layer layer = plan_.layers[l];
      nlohmann::json videos = nlohmann::json::object();
      for (size_t f = 0; f < formats; ++f) {
        const VideoWriter& writer = layer_writers_[l * formats + f];
        videos[plan_.formats[f]] = {{"file", fs::path(writer.path()).filename().string()},
                                    {"frames", writer.frames_encoded()}};
      }
      nlohmann::json entry = {{"video", videos[plan_.formats.front()]["file"]}, {"videos", videos}};
      if (layer == Layer::kDepth) {
        nlohmann::json scales = nlohmann::json::array();
        const std::vector<std::string> cameras = SplitCommaList(plan_.o->view.camera);
        for (size_t i = 0; i < depth_scales_.size(); ++i) {
          scales.push_back({{"camera", i < cameras.size() ? cameras[i] : std::string()},
                            {"near_m", depth_scales_[i].near_mm / 1000.0},
                            {"far_m", depth_scales_[i].far_mm / 1000.0}});
        }
        entry["scales"] = std::move(scales);
        entry["mapping"] =
            "per camera view: grey 255 (white) at near_m and nearer .. 32 at far_m and farther, "
            "0 (black) = no depth";
      }
      if (layer == Layer::kSegmentation) {
        const std::string legend = name_ + "_segmentation_legend.json";
        WriteJson((fs::path(plan_.o->out) / legend).string(), legend_);
        entry["legend"] = legend;
      }
      layers[LayerName(layer)] = std::move(entry);
    }
    return layers;
  }

  const RecordPlan& plan_;
  const int k_;
  const int worker_;
  FramePool& pool_;
  WorkerChannel& channel_;
  const std::string name_;
  std::set<int> on_sheet_;
  std::vector<VideoWriter> writers_;        // one per plan.formats entry, in that order
  std::vector<VideoWriter> layer_writers_;  // per plan.layers entry, one per format
  std::vector<SheetTile> tiles_;
  EpisodeRecord episode_;
  nlohmann::json extra_;
  nlohmann::json legend_;                 // the segmentation layer's
  std::vector<DepthScale> depth_scales_;  // the depth layer's, one per camera view
  double sim_s_ = 0, render_s_ = 0, encode_s_ = 0;
  std::exception_ptr error_;
  std::atomic<bool> finished_{false};
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::pair<Frame*, Command>> queue_;
  std::thread thread_;  // last: starts after every member above exists
};

// One worker of a record run: its own environment, policy, GL context, renderer, frame pool
// and encoders.
class RecordRunner : public EpisodeRunner {
 public:
  RecordRunner(const RecordPlan& plan, int worker)
      : plan_(plan),
        worker_(worker),
        sequence_(std::make_unique<FetchEnv>(*plan.spec, plan.assets),
                  // --from replays recorded actions: the policy that made them is not run
                  MakePolicy(plan.from ? "zero" : plan.o->policy, *plan.spec, plan.policy_context),
                  plan.seed, plan.o->steps) {}

  ~RecordRunner() override {
    encoders_.clear();  // aborts and joins whatever is still running (a failure elsewhere)
    renderer_.reset();  // the renderer's MuJoCo context is freed with its GL context current
    gl_.reset();
  }

  nlohmann::json Start() override {
    gl_ = CreateViewContext(plan_.o->view, plan_.gpu, worker_);
    renderer_.emplace(*gl_, sequence_.env().model(),
                      MakeRenderOptions(plan_.o->view, sequence_.env().model()));
    const size_t frame_bytes = static_cast<size_t>(renderer_->width()) * renderer_->height() * 3;
    // the frames being read back, 4 in flight between rendering and encoding, one held by each
    // encoder, and a whole episode for each further encoder so that the render thread can run
    // an episode ahead
    const size_t frames =
        4 + kReadbackDepth + plan_.encoders + (plan_.encoders - 1) * (plan_.o->steps + 1);
    pool_.emplace(frames, frame_bytes, plan_.layers.size());
    const GlInfo& gi = gl_->info();
    return {{"worker", worker_},
            {"pid", static_cast<long>(getpid())},
            {"backend", gi.backend},
            {"device", gi.device},
            {"device_selection", gl_->selection()},
            {"gl_vendor", gi.vendor},
            {"gl_renderer", gi.renderer},
            {"gl_version", gi.version},
            {"msaa", renderer_->msaa_samples()},
            {"msaa_reason", renderer_->msaa_reason()},
            {"readback", renderer_->readback_reason()}};
  }

  void Run(int k, WorkerChannel& channel) override {
    // at most plan.encoders episodes encode at once: wait for the oldest beyond that
    while (!encoders_.empty() && (encoders_.front()->finished() ||
                                  static_cast<int>(encoders_.size()) >= plan_.encoders)) {
      encoders_.front()->Join();
      encoders_.pop_front();
    }
    auto encoder = std::make_unique<EpisodeEncoder>(plan_, k, worker_, &*pool_, &channel);
    renderer_->ResetTrail();
    EpisodeLegend legend;
    std::vector<DepthScale> depth_scales;
    double sim_s = 0, render_s = 0;
    // frames submitted to the renderer and not yet back, oldest first: with asynchronous
    // readback the GPU draws frame t+1 while frame t comes back
    std::deque<Frame*> in_flight;
    auto collect_oldest = [&] {
      renderer_->Collect();
      encoder->Push(in_flight.front());
      in_flight.pop_front();
      channel.Progress(1);
    };
    auto sim_start = Clock::now();
    auto on_step = [&](const StepRecord& record, const StepResult*) {
      const auto render_start = Clock::now();
      sim_s += std::chrono::duration<double>(render_start - sim_start).count();
      Frame* f = pool_->Acquire();
      FetchEnv& env = render_env_ ? *render_env_ : sequence_.env();
      FrameInfo info = MakeFrameInfo(env, record);
      AddRelabelled(record.t, &info);
      f->t = record.t;
      f->label = TileLabel(info);
      in_flight.push_back(f);
      renderer_->Submit(env.data(), info, f->rgb.data());
      // the layers are drawn after the rgb frame's readback has been queued, and read at once
      for (size_t i = 0; i < plan_.layers.size(); ++i) {
        const Layer layer = plan_.layers[i];
        if (layer == Layer::kSegmentation) {
          renderer_->RenderLayer(env.data(), info, layer, &f->layers[i]);
          legend.Add(renderer_->segmentation_legend());
        } else {
          renderer_->RenderLayer(env.data(), info, layer, &depth_);
          if (depth_scales.empty()) {
            depth_scales = ScalesFromFrame(depth_, renderer_->width(), renderer_->height(),
                                           renderer_->tiles());
          }
          DepthToGrey(depth_, renderer_->width(), depth_scales, f->layers[i].data());
        }
      }
      while (renderer_->pending() >= renderer_->pipeline_depth()) collect_oldest();
      sim_start = Clock::now();
      render_s += std::chrono::duration<double>(sim_start - render_start).count();
      return !channel.StopRequested();
    };
    EpisodeRecord episode;
    try {
      episode = PlayEpisode(k, on_step, channel);
      const auto drain_start = Clock::now();
      while (!in_flight.empty()) collect_oldest();
      render_s += Since(drain_start);
    } catch (...) {
      renderer_->DiscardPending();
      for (Frame* f : in_flight) pool_->Release(f);
      throw;  // aborts `encoder`
    }
    encoder->SetExtra({{"hindsight", HindsightCounts(episode)}});
    encoder->SetLayerInfo(legend.Json(k), std::move(depth_scales));
    encoder->Close(std::move(episode), sim_s, render_s);
    encoders_.push_back(std::move(encoder));
  }

  void Finish(WorkerChannel& channel) override {
    (void)channel;
    while (!encoders_.empty()) {
      encoders_.front()->Join();
      encoders_.pop_front();
    }
  }

 private:
  // Plays episode k, calling on_step (which renders) at every step: live from the policy; or,
  // for --from and the hindsight overlay, a replay of recorded actions (the recording's, or
  // those of a first pass run here without rendering) with the hindsight goals sampled first.
  EpisodeRecord PlayEpisode(int k, const StepCallback& on_step, WorkerChannel& channel) {
    hindsight_.reset();
    if (!plan_.from && !plan_.hindsight) return sequence_.Play(k, on_step);
    EpisodeRecord first_pass;
    const std::vector<StepRecord>* script = nullptr;
    bool script_complete = true;
    if (plan_.from) {
      script = &plan_.from->episodes.at(k).steps;
      script_complete = plan_.from->episodes.at(k).complete;
    } else {
      first_pass = sequence_.Play(
          k, [&](const StepRecord&, const StepResult*) { return !channel.StopRequested(); });
      script = &first_pass.steps;
      script_complete = first_pass.complete;
    }
    if (plan_.hindsight) hindsight_ = SampleEpisodeHindsight(k, *script);
    if (!replayer_) {
      if (!plan_.from) replay_env_ = std::make_unique<FetchEnv>(*plan_.spec, plan_.assets);
      replayer_.emplace(plan_.from ? sequence_.env() : *replay_env_, plan_.seed);
    }
    // the replay renders from the env of sequence_ (--from) or replay_env_ (hindsight)
    render_env_ = plan_.from ? &sequence_.env() : replay_env_.get();
    const std::string check = plan_.from ? plan_.from->episodes.at(k).file : std::string();
    EpisodeRecord episode = replayer_->Replay(k, *script, script_complete, check, on_step);
    render_env_ = nullptr;
    return episode;
  }

  HindsightEpisode SampleEpisodeHindsight(int k, const std::vector<StepRecord>& steps) {
    std::vector<std::array<double, 3>> achieved;
    for (const StepRecord& s : steps) achieved.push_back(s.obs.achieved_goal);
    const FetchEnv& env = sequence_.env();
    return SampleHindsight(
        achieved, steps.front().obs.desired_goal, HindsightSeed(plan_.seed, k), kHindsightK,
        [&env](const auto& a, const auto& g) { return env.ComputeReward(a, g); },
        [&env](const auto& a, const auto& g) { return env.IsSuccess(a, g); });
  }

  // The manifest entry's "hindsight": relabelled successes (of k per transition) against the
  // episode's own successful transitions.
  nlohmann::json HindsightCounts(const EpisodeRecord& episode) {
    const HindsightEpisode h =
        hindsight_ ? *hindsight_ : SampleEpisodeHindsight(episode.index, episode.steps);
    const int transitions = static_cast<int>(episode.steps.size()) - 1;
    return {{"relabelled_successes", h.relabelled_successes},
            {"original_successes", h.original_successes},
            {"k", kHindsightK},
            {"transitions", transitions}};
  }

  // The hindsight overlay's goals for the frame after step t (the transition t-1 -> t).
  void AddRelabelled(int t, FrameInfo* info) const {
    if (!hindsight_ || t < 1 || t > static_cast<int>(hindsight_->transitions.size())) return;
    int successes = 0;
    for (const HindsightGoal& g : hindsight_->transitions[t - 1]) {
      info->relabelled.push_back({g.goal, g.success});
      successes += g.success;
    }
    info->relabelled_successes = successes;
  }

  const RecordPlan& plan_;
  const int worker_;
  EpisodeSequence sequence_;
  std::unique_ptr<FetchEnv> replay_env_;  // hindsight: the env the replay renders
  std::optional<EpisodeReplayer> replayer_;
  FetchEnv* render_env_ = nullptr;             // the env being replayed, while it is
  std::optional<HindsightEpisode> hindsight_;  // this episode's relabelling (hindsight overlay)
  std::vector<uint8_t> depth_;                 // the depth layer's millimetres, reused
  // Lifetime order: the GL context outlives the renderer; encoders go first (they hold frames).
  std::unique_ptr<GlContext> gl_;
  std::optional<Renderer> renderer_;
  std::optional<FramePool> pool_;
  std::deque<std::unique_ptr<EpisodeEncoder>> encoders_;
};

// llvmpipe starts one rasteriser thread per core in every context; with several workers that
// oversubscribes the cores, so each worker rasterises on its own thread instead (unless the
// user chose). Hardware drivers ignore the variable.
void LimitLlvmpipeThreads(int jobs) {
  if (jobs > 1) setenv("LP_NUM_THREADS", "0", /*overwrite=*/0);
}

// Episodes one worker encodes at once: the usable cores shared out over the workers, C/N
// (each encoder is one thread, so that the bytes never depend on the thread count), at least 1.
// An encoder only holds frames while it is behind the render thread, so memory grows with
// encoders only where the encoders, not the renderer, are the bottleneck.
int EncodersPerWorker(int jobs) {
  const int cores = UsableCores().usable;
  return std::max(1, cores / std::max(1, jobs));
}

// ", 1 incomplete (as recorded)" for the summary line when episodes are incomplete.
std::string IncompleteNote(const std::vector<int>& incomplete, bool interrupted) {
  if (incomplete.empty()) return "";
  return ", " + std::to_string(incomplete.size()) + " incomplete" +
         (interrupted ? "" : " (as recorded)");
}

// record --from: the recorded episodes' indices, ascending.
std::vector<int> FromEpisodes(const TrajectorySource& from) {
  std::vector<int> out;
  for (const auto& [k, episode] : from.episodes) out.push_back(k);
  return out;
}

int RunRecord(const RecordOptions& o, const std::string& command_line,
              const TrajectorySource* from = nullptr);

// record --from: the trajectory sets env, seed, policy, steps and episodes; then as record.
int RunRecordFrom(RecordOptions o, const CLI::App& sub, const std::string& command_line) {
  CheckFromFlags(sub, o.from);
  const TrajectorySource source = LoadTrajectorySource(o.from);
  ApplyFromSource(source, sub, &o.env.env_id, &o.env.seed, &o.policy, &o.steps, &o.episodes,
                  &o.env.assets);
  return RunRecord(o, command_line, &source);
}

// Starting an exec: child is the only full check of it, and the workers do that; every other
// policy is built once here so that a bad one fails before anything is written.
void ValidatePolicy(const std::string& policy, const EnvSpec& spec, const PolicyContext& context) {
  if (policy.rfind("exec:", 0) == 0 && policy.size() > 5) return;
  MakePolicy(policy, spec, context);
}

// What makes two record runs the same run, by option: what a resumed run must repeat for its
// episodes to come out byte for byte as the run it continues (--jobs, --gpu and --backend
// are free: outputs do not depend on them on one machine).
nlohmann::json RecordParameters(const RecordOptions& o, const RecordPlan& plan,
                                const Shard& shard) {
  nlohmann::json parameters = {{"--env-id", plan.spec->id},
                               {"--seed", plan.seed},
                               {"--policy", o.policy},
                               {"--replay-dtype", o.replay_dtype},
                               {"--episodes", o.episodes},
                               {"--steps", o.steps},
                               {"--sheet-every", o.sheet_every},
                               {"--assets", plan.assets.sha256},
                               {"--camera", o.view.camera},
                               {"--overlay", o.view.overlay},
                               {"--width", o.view.width},
                               {"--height", o.view.height},
                               {"--msaa", o.view.msaa},
                               {"--codec", plan.video.codec},
                               {"--crf", o.crf},
                               {"--preset", o.preset.empty() ? kDefaultVideoPreset : o.preset},
                               {"--fps", o.fps},
                               {"--shard", ShardLabel(shard)}};
  // newer options join only when they change the files, so that runs recorded before they
  // existed stay resumable
  if (plan.formats != std::vector<std::string>{"mp4"}) {
    parameters["--format"] = plan.formats;
    if (std::find(plan.formats.begin(), plan.formats.end(), "gif") != plan.formats.end()) {
      parameters["--gif-fps"] = o.gif_fps;
      parameters["--gif-width"] = o.gif_width;
    }
  }
  if (!plan.layers.empty()) parameters["--layers"] = LayersLabel(plan.layers);
  return parameters;
}

RunFolderRequest MakeRunFolderRequest(const RecordOptions& o, const Shard& shard,
                                      const std::vector<int>& episodes,
                                      const nlohmann::json& parameters) {
  RunFolderRequest request;
  request.out = o.out;
  request.mode = ParseReuseMode(o.overwrite, o.resume);
  request.manifest_name = ShardManifestName(shard);
  request.sharded = shard.sharded();
  request.owns = [shard](int k) { return shard.Owns(k); };
  request.episodes = episodes;
  request.parameters = parameters;
  return request;
}

// --resume: the manifest entries of this run and the complete ones kept from the run it
// continues, in episode order.
nlohmann::json WithKeptEpisodes(nlohmann::json entries, const std::vector<nlohmann::json>& kept) {
  for (const nlohmann::json& e : kept) entries.push_back(e);
  std::sort(entries.begin(), entries.end(), [](const nlohmann::json& a, const nlohmann::json& b) {
    return a.at("index").get<int>() < b.at("index").get<int>();
  });
  return entries;
}

// The episodes this run records: those of its shard among 0 .. --episodes-1 or, replaying a
// trajectory JSON, the file's episodes, each under its own index (and so with its own reset);
// --episodes then becomes one past the last index.
std::vector<int> RecordEpisodeList(RecordOptions* o, const Shard& shard, const RecordPlan& plan) {
  const std::optional<std::vector<int>> indices = ReplayedEpisodes(
      o->policy, o->episodes_given ? o->episodes : 0, plan.spec->id, plan.seed, o->quiet);
  if (!indices) return ShardEpisodes(shard, o->episodes);
  o->episodes = indices->back() + 1;
  std::vector<int> mine;
  for (int k : *indices) {
    if (shard.Owns(k)) mine.push_back(k);
  }
  return mine;
}

int RunRecord(const RecordOptions& options, const std::string& command_line,
              const TrajectorySource* from) {
  const auto wall_start = Clock::now();
  RecordOptions o = options;  // a trajectory replay sets the episodes
  RecordPlan plan;
  plan.o = &o;
  plan.from = from;
  plan.hindsight = ParseOverlays(o.view.overlay).hindsight;
  plan.spec = &FindEnvSpec(o.env.env_id);
  plan.seed = ParseSeed(o.env.seed);
  const Shard shard = ResolveShard(o.shard, o.shard_count);
  const WorkerMode mode = ParseWorkerMode(o.worker_mode);
  plan.video.fps = o.fps;
  plan.video.codec = o.codec;
  plan.video.crf = o.crf;
  plan.video.preset = o.preset;
  plan.video.gif_fps = o.gif_fps;
  plan.video.gif_width = o.gif_width;
  plan.formats = ParseVideoFormats(o.formats);
  plan.layers = ParseRecordLayers(o.layers);
  ValidateVideoOptions(plan.video);
  const std::vector<int> episodes = from ? FromEpisodes(*from) : RecordEpisodeList(&o, shard, plan);
  const int jobs = ResolveJobs(o.jobs, static_cast<int>(episodes.size()));
  plan.encoders = EncodersPerWorker(jobs);

  plan.policy_context.seed = plan.seed;
  plan.policy_context.steps_per_episode = o.steps;
  plan.policy_context.episodes = o.episodes;
  plan.policy_context.exec_timeout_s = o.exec_timeout;
  plan.policy_context.stop_requested = [] { return StopSignal() != 0; };
  plan.policy_context.replay_dtype = o.replay_dtype;
  plan.policy_context.episode_indices = episodes;
  if (!from) ValidatePolicy(o.policy, *plan.spec, plan.policy_context);
  Font::Default();  // the sheets' font: missing or unreadable, the run stops before any file
  plan.assets = ResolveAssets(o.env.assets);
  std::string model_path;
  {
    FetchEnv env(*plan.spec, plan.assets);  // bad assets and bad cameras fail here
    const FrameDims frame = FrameSize(MakeRenderOptions(o.view, env.model()));
    plan.video.width = frame.width;  // --width/--height size each camera's tile
    plan.video.height = frame.height;
    model_path = env.model_path();
    if (from) VerifyRecording(env, *from);  // an edited recording stops here, before any file
  }
  ValidateVideoOptions(plan.video);

  // The GPUs and the encoder, decided once (driver work in a child process); without mp4 no
  // H.264 is encoded, and nothing is probed for it.
  const bool h264 =
      std::find(plan.formats.begin(), plan.formats.end(), "mp4") != plan.formats.end();
  const NodeProbe node = ProbeNode(o.view, h264 ? &plan.video : nullptr);
  plan.gpu = node.gpu;
  if (h264) plan.video.codec = node.codec.codec;
  if (!node.warnings.empty() && !o.quiet) {
    std::fprintf(stderr, "fetchscope: warning: %s\n", node.warnings.c_str());
  }

  // never two runs in one folder; a failure below leaves nothing this run made. From here a
  // SIGINT/SIGTERM is an interruption (the scheduler takes over the handlers when it starts).
  InstallStopSignals();
  const nlohmann::json parameters = RecordParameters(o, plan, shard);
  RunFolder folder(MakeRunFolderRequest(o, shard, episodes, parameters));
  if (!folder.notice().empty() && !o.quiet) {
    std::fprintf(stderr, "fetchscope: note: %s\n", folder.notice().c_str());
  }
  const int early_signal = StopSignal();  // before the scheduler: record nothing

  ProgressReporter progress("record", static_cast<int>(folder.todo().size()), o.steps + 1, o.quiet);
  int successes = 0;
  ScheduleOptions schedule;
  schedule.episodes = folder.todo();
  schedule.jobs = jobs;
  schedule.mode = mode;
  schedule.on_progress = [&](int n) { progress.Frames(n); };
  schedule.on_done = [&](int, const nlohmann::json& entry) {
    progress.EpisodeDone();
    successes += entry.at("is_success").get<bool>();
  };
  LimitLlvmpipeThreads(jobs);
  ScheduleResult result;
  if (early_signal) {
    result.signal = early_signal;
    result.jobs = jobs;
    result.missing = folder.todo();
  } else {
    result = RunEpisodes(
        schedule, [&plan](int worker) { return std::make_unique<RecordRunner>(plan, worker); });
  }
  const bool any_complete =
      std::any_of(result.results.begin(), result.results.end(),
                  [](const auto& r) { return r.second.value("complete", false); });
  if (result.signal && !any_complete && folder.replacing()) {
    // interrupted before --overwrite recorded a whole episode: the earlier run stays as it was
    if (!o.quiet) {
      std::fprintf(stderr,
                   "record: interrupted before any episode was complete; the earlier "
                   "run in %s is kept as it was\n",
                   o.out.c_str());
    }
    return 128 + result.signal;  // `folder` removes this run's files, puts the earlier run back
  }

  const double wall = Since(wall_start);
  nlohmann::json episodes_json = nlohmann::json::array();
  std::map<std::string, double> timings = {{"sim", 0}, {"render", 0}, {"encode", 0}, {"write", 0}};
  std::map<int, std::vector<int>> by_worker;  // the episodes each worker recorded
  for (const auto& [k, entry] : result.results) {
    nlohmann::json e = entry;
    for (auto& [phase, seconds] : timings) seconds += e["timings_s"][phase].get<double>();
    by_worker[e.at("worker").get<int>()].push_back(k);
    // what differs with --jobs stays out of the episode entries (they are identical)
    e.erase("worker");
    e.erase("timings_s");
    e.erase("codec");
    e.erase("encoded_width");
    e.erase("encoded_height");
    episodes_json.push_back(std::move(e));
  }
  episodes_json = WithKeptEpisodes(std::move(episodes_json), folder.kept());
  // The first worker that started speaks for the GL setup (all run the same backend).
  nlohmann::json first_worker;
  for (const nlohmann::json& w : result.workers) {
    if (!w.is_null()) {
      first_worker = w;
      break;
    }
  }
  if (result.results.empty() && result.signal == 0 && !result.failures.empty()) {
    // nothing was recorded: no manifest, and `folder` removes what this run made
    const WorkerFailure& first = result.failures.front();
    if (first.usage) throw UsageError(first.message);
    throw RunError(DescribeFailures(result));
  }
  nlohmann::json workers_json = nlohmann::json::array();
  for (size_t w = 0; w < result.workers.size(); ++w) {
    nlohmann::json entry =
        result.workers[w].is_null() ? nlohmann::json{{"worker", w}} : result.workers[w];
    entry["episodes"] = by_worker[static_cast<int>(w)];
    workers_json.push_back(std::move(entry));
  }
  nlohmann::json failures_json = nlohmann::json::array();
  for (const WorkerFailure& f : result.failures) {
    failures_json.push_back(
        {{"worker", f.worker}, {"episodes", f.episodes}, {"message", f.message}});
  }
  const nlohmann::json shard_json = {
      {"index", shard.index},
      {"count", shard.count},
      {"source", shard.source.empty() ? nlohmann::json(nullptr) : nlohmann::json(shard.source)},
      {"episodes", episodes}};
  const int sig = result.signal;
  // the encoder of each format's files, and all of them in --format order as one line
  nlohmann::json codecs = nlohmann::json::object();
  std::string codec_used;
  for (const std::string& format : plan.formats) {
    codecs[format] = FormatCodec(format, plan.video.codec);
    codec_used += (codec_used.empty() ? "" : ", ") + codecs[format].get<std::string>();
  }
  const std::string codec_reason =
      h264 ? node.codec.reason
           : "--format " + o.formats + ": no H.264 encoded, so --codec does not apply";
  // episodes cut short: by this run's signal, or already in the recording --from replays
  std::vector<int> incomplete;
  for (const nlohmann::json& e : episodes_json) {
    if (!e.value("complete", true)) incomplete.push_back(e.at("index").get<int>());
  }
  nlohmann::json manifest = {
      {"env_id", plan.spec->id},
      {"seed", plan.seed},
      {"policy", o.policy},
      {"from", from ? nlohmann::json(from->path) : nlohmann::json(nullptr)},
      {"episodes_requested", o.episodes},
      {"steps_per_episode", o.steps},
      {"sheet_every", o.sheet_every},
      {"episodes", episodes_json},
      {"missing", result.missing},
      {"failures", failures_json},
      {"shard", shard_json},
      {"jobs", result.jobs},
      {"worker_mode", o.worker_mode},
      {"workers", workers_json},
      {"gpu",
       {{"request", o.view.gpu}, {"choice", plan.gpu.reason}, {"devices", plan.gpu.devices}}},
      {"assets", AssetsJson(plan.assets)},
      {"model_file", model_path},
      {"camera", o.view.camera},
      {"overlay", o.view.overlay},
      {"msaa", first_worker.value("msaa", 0)},
      {"msaa_reason", first_worker.value("msaa_reason", "")},
      {"backend",
       {{"name", first_worker.value("backend", "")},
        {"device", first_worker.value("device", "")},
        {"gl_vendor", first_worker.value("gl_vendor", "")},
        {"gl_renderer", first_worker.value("gl_renderer", "")},
        {"gl_version", first_worker.value("gl_version", "")}}},
      {"layers", SplitCommaList(LayersLabel(plan.layers))},
      {"video",
       {{"codec", codec_used},
        {"codecs", codecs},
        {"codec_reason", codec_reason},
        {"crf", o.crf},
        {"preset", o.preset.empty() ? kDefaultVideoPreset : o.preset},
        {"fps", o.fps},
        {"width", plan.video.width},
        {"height", plan.video.height},
        {"encoded_width", (plan.video.width + 1) & ~1},
        {"encoded_height", (plan.video.height + 1) & ~1},
        {"encoder_threads", plan.video.threads},
        {"encoders_per_worker", plan.encoders},
        {"container", plan.formats.front()},
        {"formats", plan.formats},
        {"gif", {{"fps", std::min(o.gif_fps, o.fps)}, {"width", o.gif_width}}},
        {"pix_fmt", "yuv420p"}}},
      {"versions", VersionsJson()},
      {"timings_s",
       {{"wall", wall},
        {"sim", timings["sim"]},
        {"render", timings["render"]},
        {"encode", timings["encode"]},
        {"write", timings["write"]}}},
      {"frames", progress.frames()},
      {"interrupted", sig != 0},
      {"incomplete_episodes", incomplete},
      {"signal",
       sig == 0 ? nlohmann::json(nullptr) : nlohmann::json(sig == SIGINT ? "SIGINT" : "SIGTERM")},
      {"command_line", command_line},
      {"parameters", parameters},
      {"resumed", o.resume && !folder.kept().empty()}};
  const fs::path manifest_path = fs::path(o.out) / ShardManifestName(shard);
  WriteJson(manifest_path.string(), manifest);
  folder.Commit();
  const size_t recorded = result.results.size();
  char summary[768];
  std::snprintf(
      summary, sizeof(summary),
      "record: %zu episode(s), %ld frames in %.1f s (%.1f frames/s, %.2f episodes/s, %d "
      "job(s)%s%s), success %d/%zu%s, %s via %s, %s -> %s%s",
      recorded, progress.frames(), wall, progress.frames() / wall, recorded / wall, result.jobs,
      shard.sharded() ? ", shard " : "", shard.sharded() ? ShardLabel(shard).c_str() : "",
      successes, recorded, IncompleteNote(incomplete, sig != 0).c_str(),
      first_worker.value("gl_renderer", "?").c_str(), first_worker.value("backend", "?").c_str(),
      codec_used.c_str(), o.out.c_str(), sig ? " (interrupted)" : "");
  progress.Done(summary);
  // a shard's episodes are only part of the run: merge-manifests writes the run's report
  if (!o.no_report && !shard.sharded()) WriteRunReportOrWarn(manifest_path, o.quiet);
  if (sig) return 128 + sig;
  if (!result.failures.empty()) {
    throw RunError(DescribeFailures(result) + "; the manifest lists the missing episodes (" +
                   std::to_string(result.missing.size()) + "): --resume records them");
  }
  return 0;
}

}  // namespace

Command AddRecord(CLI::App& app) {
  auto o = std::make_shared<RecordOptions>();
  CLI::App* sub = app.add_subcommand(
      "record",
      "Record episodes: episode_NNN.mp4 (.webm, .gif: --format), episode_NNN_sheet.png, "
      "episode_NNN.json, manifest.json");
  AddEnvOptions(sub, &o->env);
  AddViewOptions(sub, &o->view);
  sub->add_option("--episodes", o->episodes, "Number of episodes")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  sub->add_option("--steps", o->steps, "Steps per episode (TimeLimit is 50)")
      ->capture_default_str()
      ->check(CLI::Range(1, 50));
  sub->add_option("--policy", o->policy, kPolicyHelp)->capture_default_str();
  sub->add_option("--exec-timeout", o->exec_timeout, "Seconds an exec: policy may take per answer")
      ->capture_default_str()
      ->check(CLI::Range(0.001, 86400.0));
  sub->add_option("--replay-dtype", o->replay_dtype, kReplayDtypeHelp);
  sub->add_option("--fps", o->fps, "Video frame rate (25 = the control rate: real time)")
      ->capture_default_str();
  sub->add_option("--codec", o->codec,
                  "auto (h264_nvenc where the GPU has NVENC, else libx264; decided once per run), "
                  "libx264 or h264_nvenc")
      ->capture_default_str();
  sub->add_option("--crf", o->crf, "H.264 quality, 0 (lossless) .. 51 (worst)")
      ->capture_default_str();
  sub->add_option("--preset", o->preset,
                  std::string("Encoder preset (default ") + kDefaultVideoPreset + ")");
  sub->add_option("--format", o->formats,
                  "Video formats, a comma list: mp4 (H.264), webm (VP9, plays in every browser and "
                  "wandb), gif (one palette per clip, scaled by --gif-fps/--gif-width); one file "
                  "per episode and format")
      ->capture_default_str();
  sub->add_option("--gif-fps", o->gif_fps, "GIF frame rate, 1..50 (at most --fps)")
      ->capture_default_str();
  sub->add_option(
         "--gif-width", o->gif_width,
         "GIF width in pixels, 16..4096 (never wider than the frames; height keeps the aspect)")
      ->capture_default_str();
  sub->add_option("--layers", o->layers,
                  "Comma list of rgb (always recorded), depth, segmentation: each extra layer is "
                  "one more video per episode and --format, episode_NNN_depth.mp4 (grey: white "
                  "near .. dark far, black = no depth; the scale is fixed per episode from its "
                  "reset frame and given in the manifest), episode_NNN_segmentation.mp4 (a fixed "
                  "colour per body or site, as render --layers) with "
                  "episode_NNN_segmentation_legend.json naming each colour's body and geoms. "
                  "Layers show no overlays; contact sheets stay rgb")
      ->capture_default_str();
  sub->add_option(
         "--sheet-every", o->sheet_every,
         "Contact sheet: every K-th frame (0: about 12 tiles); the last frame is always included")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000));
  sub->add_option("--out", o->out, "Output folder")->capture_default_str();
  sub->add_flag("-q,--quiet", o->quiet, "No progress or summary on stderr");
  sub->add_flag("--overwrite", o->overwrite,
                "Replace the record run already in --out (its manifest, report and episode "
                "files; other files stay). The earlier run is kept aside until the new one has "
                "its manifest, and put back if it fails or is interrupted before an episode is "
                "complete. Without --overwrite or --resume such a folder is refused");
  sub->add_flag("--resume", o->resume,
                "Continue the interrupted record run in --out: keep its complete episodes and "
                "record the others, byte-identical to an uninterrupted run; the options must "
                "be those of that run. With nothing to resume (no such folder, or no manifest "
                "in it) the whole run is recorded, with a note saying so");
  AddJobsOptions(sub, &o->jobs, &o->worker_mode);
  sub->add_option("--shard", o->shard,
                  "Record only shard I of N (0 <= I < N): episodes k with k mod N = I. Without it: "
                  "JOB_COMPLETION_INDEX (with --shard-count) or SLURM_ARRAY_TASK_ID/COUNT if set");
  sub->add_option("--shard-count", o->shard_count,
                  "Number of shards when the index comes from JOB_COMPLETION_INDEX (a Kubernetes "
                  "Indexed Job's completions)");
  sub->add_flag("--no-report", o->no_report,
                "Do not write the run's HTML report (index.html; see `fetchscope report`)");
  AddFromOption(sub, &o->from);
  return {sub, [o, sub] {
            o->episodes_given = sub->count("--episodes") > 0;
            if (!o->from.empty()) return RunRecordFrom(*o, *sub, CommandLine());
            return RunRecord(*o, CommandLine());
          }};
}

}  // namespace fetchscope::cli
