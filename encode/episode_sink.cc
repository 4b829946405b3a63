#include "encode/episode_sink.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "base/atomic_file.h"
#include "base/json_util.h"
#include "encode/png_io.h"
#include "encode/video_format.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

// JSON as every output writes it: atomically, with a trailing newline.

}  // namespace

std::string EpisodeFileStem(int k) {
  char name[32];
  std::snprintf(name, sizeof(name), "episode_%03d", k);
  return name;
}

std::string LayerVideoName(int k, Layer layer, const VideoFormat& format) {
  return EpisodeFileStem(k) + "_" + LayerName(layer) + "." + std::string(format.extension);
}

std::string FormatCodec(const VideoFormat& format, const std::string& h264) {
  return format.codec == kH264 ? h264 : std::string(format.codec);
}

VideoOptions EpisodeVideoOptions(const EpisodeSinkOptions& options, int k,
                                 const VideoFormat& format) {
  VideoOptions video = options.video;
  video.format = &format;
  video.metadata = {{"title", options.env_id + " seed " + std::to_string(options.seed) +
                                  " episode " + std::to_string(k) + " (" + options.policy + ")"},
                    {"env_id", options.env_id},
                    {"seed", std::to_string(options.seed)},
                    {"policy", options.policy},
                    {"episode", std::to_string(k)},
                    {"fetchscope_version", FETCHSCOPE_VERSION}};
  return video;
}

std::optional<ShownScale> GifTextScale(const EpisodeSinkOptions& options) {
  if (!HasPaletteFormat(options.formats) || options.video.gif_width >= options.video.width)
    return std::nullopt;
  return ShownScale{options.video.gif_width, options.video.width};
}

bool NeedsGifCopy(const EpisodeSinkOptions& options, int t) {
  const VideoOptions& v = options.video;
  return GifTextScale(options) && GifKeepsFrame(t, v.fps, std::min(v.gif_fps, v.fps));
}

std::string GifHudNote(const EpisodeSinkOptions& options, int tile_width, int tile_height) {
  const std::optional<ShownScale> scale = GifTextScale(options);
  // no note where the frames have no HUD either, or where the GIF keeps it
  if (!scale || HudTextPixels(tile_width, tile_height) == 0 ||
      HudTextPixels(tile_width, tile_height, *scale) > 0) {
    return "";
  }
  const long shown_w = static_cast<long>(tile_width) * scale->shown / scale->drawn;
  const long shown_h = static_cast<long>(tile_height) * scale->shown / scale->drawn;
  return "the GIF (" + std::to_string(scale->shown) + " px wide) shows each view at " +
         std::to_string(shown_w) + "x" + std::to_string(shown_h) + ", smaller than the " +
         std::to_string(kHudMinTileWidth) + "x" + std::to_string(kHudMinTileHeight) +
         " the HUD needs to be read: the GIF has no HUD (raise --gif-width to keep it)";
}

EpisodeEncoder::EpisodeEncoder(const EpisodeSinkOptions& options, int k, FramePool* pool,
                               EpisodeDone done)
    : options_(options), k_(k), pool_(*pool), done_(std::move(done)), name_(EpisodeFileStem(k)) {
  if (options.sheet_every >= 0) {  // -1: --no-sheets
    const std::vector<int> indices = SheetFrameIndices(options.steps + 1, options.sheet_every);
    on_sheet_.insert(indices.begin(), indices.end());
  }
  // the writers open here, on the render thread, so a bad folder fails before any frame
  for (const VideoFormat* format : options.formats) {
    writers_.emplace_back(
        (fs::path(options.out) / (name_ + "." + std::string(format->extension))).string(),
        EpisodeVideoOptions(options, k, *format));
  }
  for (Layer layer : options.layers) {
    for (const VideoFormat* format : options.formats) {
      VideoOptions video = EpisodeVideoOptions(options, k, *format);
      video.metadata.emplace_back("layer", LayerName(layer));
      layer_writers_.emplace_back(
          (fs::path(options.out) / LayerVideoName(k, layer, *format)).string(), video);
    }
  }
  thread_ = std::thread([this] { Body(); });
}

EpisodeEncoder::~EpisodeEncoder() {
  if (thread_.joinable()) {
    Abort();
    thread_.join();
  }
}

void EpisodeEncoder::Close(EpisodeRecord episode, double sim_s, double render_s,
                           CpuStages render_cpu) {
  episode_ = std::move(episode);
  sim_s_ = sim_s;
  render_s_ = render_s;
  render_cpu_ = render_cpu;
  Enqueue(nullptr, Command::kClose);
}

void EpisodeEncoder::SetLayerInfo(nlohmann::json legend, std::vector<DepthScale> depth) {
  legend_ = std::move(legend);
  depth_scales_ = std::move(depth);
}

void EpisodeEncoder::Join() {
  if (thread_.joinable()) thread_.join();
  if (error_) std::rethrow_exception(error_);
}

void EpisodeEncoder::Enqueue(Frame* f, Command c) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queue_.push_back({f, c});
  }
  cv_.notify_one();
}

void EpisodeEncoder::Body() {
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
          for (size_t i = 0; i < writers_.size(); ++i) {
            // a scaled-down GIF takes the copy whose text is sized for it
            const bool gif_copy =
                options_.formats[i]->pixels == VideoPixels::kPal8 && !f->gif_rgb.empty();
            writers_[i].AddFrame(gif_copy ? f->gif_rgb.data() : f->rgb.data());
          }
          const size_t formats = options_.formats.size();
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
        if (held && options_.sheet_every >= 0 && !on_sheet_.count(held->t)) AddTile(*held);
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

void EpisodeEncoder::AddTile(const Frame& f) {
  CpuLap lap;
  // scaled now: the sheet keeps 240-pixel tiles, not whole frames (byte for byte the same sheet)
  tiles_.push_back(ScaleSheetTile(f.rgb.data(), options_.video.width, options_.video.height,
                                  f.label, kSheetTileWidth, &sheet_scratch_));
  lap.Into(&cpu_.sheet);
}

void EpisodeEncoder::Finalize() {
  const EpisodeSinkOptions& o = options_;
  const auto t0 = Clock::now();
  for (VideoWriter& writer : writers_) writer.Finish();
  for (VideoWriter& writer : layer_writers_) writer.Finish();
  const int steps = static_cast<int>(episode_.steps.size()) - 1;
  const bool complete = episode_.complete;  // false: ended early by SIGINT/SIGTERM
  char title[256];
  std::snprintf(title, sizeof(title), "%s  seed %s  policy %s  episode %d%s", o.env_id.c_str(),
                o.seed_text.c_str(), o.policy.c_str(), k_, complete ? "" : "  (interrupted)");
  CpuLap lap;
  if (o.sheet_every >= 0) {
    const SheetImage sheet = MakeContactSheet(title, tiles_);
    WritePng((fs::path(o.out) / (name_ + "_sheet.png")).string(), sheet.width, sheet.height, 3, 8,
             sheet.rgb.data(), /*fast=*/true);
  }
  lap.Into(&cpu_.sheet);
  // the episode's trajectory file, through the one trajectory writer
  Trajectory trajectory;
  trajectory.env_id = o.env_id;
  trajectory.seed = o.seed;
  trajectory.policy = o.policy;
  trajectory.assets = o.assets;
  trajectory.episodes = {episode_};
  WriteFileAtomically((fs::path(o.out) / (name_ + ".json")).string(), TrajectoryText(trajectory));
  lap.Into(&cpu_.trajectory);
  std::map<std::string, EpisodeLayer> layers = FinishLayers();
  const double write_s = Since(t0);
  // this thread's stages: the writers' conversion and encoding, the rest of its time "other"
  for (const auto* list : {&writers_, &layer_writers_}) {
    for (const VideoWriter& w : *list) {
      cpu_.convert += w.convert_cpu_s();
      cpu_.encode += w.encode_cpu_s();
    }
  }
  cpu_.encode_other =
      ThreadCpuSeconds() - (cpu_.convert + cpu_.encode + cpu_.sheet + cpu_.trajectory);
  CpuStages cpu = render_cpu_;
  cpu += cpu_;
  EpisodeResult result;
  for (const auto& [stage, seconds] : cpu.Items()) result.timings.cpu_s[stage] = seconds;
  result.timings.sim = sim_s_;
  result.timings.render = render_s_;
  result.timings.encode = encode_s_;
  result.timings.write = write_s;
  ManifestEpisode& entry = result.entry;
  entry.index = k_;
  for (size_t i = 0; i < writers_.size(); ++i) {  // format -> file and frames in it
    entry.videos[std::string(o.formats[i]->name)] = {
        fs::path(writers_[i].path()).filename().string(), writers_[i].frames_encoded()};
  }
  const VideoWriter& first = writers_.front();
  entry.video = fs::path(first.path()).filename().string();
  if (o.sheet_every >= 0) entry.sheet = name_ + "_sheet.png";
  entry.trajectory = name_ + ".json";
  entry.frames = first.frames_written();
  entry.steps = steps;
  entry.complete = complete;
  entry.episode_return = episode_.episode_return;
  entry.is_success = episode_.steps.back().is_success;
  entry.layers = std::move(layers);
  entry.hindsight = hindsight_;
  if (!episode_.look.is_null()) entry.extra["look"] = episode_.look;  // --randomize's draw
  done_(k_, std::move(result));
}

// The entry's layers (none without layers): per layer its videos by format, the first format's
// file as `video`, the depth scale or the segmentation legend (written here).
std::map<std::string, EpisodeLayer> EpisodeEncoder::FinishLayers() {
  std::map<std::string, EpisodeLayer> layers;
  const size_t formats = options_.formats.size();
  for (size_t l = 0; l < options_.layers.size(); ++l) {
    const Layer layer = options_.layers[l];
    EpisodeLayer entry;
    for (size_t f = 0; f < formats; ++f) {
      const VideoWriter& writer = layer_writers_[l * formats + f];
      entry.videos[std::string(options_.formats[f]->name)] = {
          fs::path(writer.path()).filename().string(), writer.frames_encoded()};
    }
    entry.video = entry.videos[std::string(options_.formats.front()->name)].file;
    if (layer == Layer::kDepth) {
      nlohmann::json scales = nlohmann::json::array();
      const std::vector<std::string>& cameras = options_.cameras;
      for (size_t i = 0; i < depth_scales_.size(); ++i) {
        scales.push_back({{"camera", i < cameras.size() ? cameras[i] : std::string()},
                          {"near_m", depth_scales_[i].near_mm / 1000.0},
                          {"far_m", depth_scales_[i].far_mm / 1000.0}});
      }
      entry.details["scales"] = std::move(scales);
      entry.details["mapping"] =
          "per camera view: grey 255 (white) at near_m and nearer .. 32 at far_m and farther, "
          "0 (black) = no depth";
    }
    if (layer == Layer::kSegmentation) {
      const std::string legend = name_ + "_segmentation_legend.json";
      WriteJson((fs::path(options_.out) / legend).string(), legend_);
      entry.legend = legend;
    }
    layers[LayerName(layer)] = std::move(entry);
  }
  return layers;
}

}  // namespace fetchscope
