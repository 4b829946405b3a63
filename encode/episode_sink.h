// The episode video sink: one episode's files, written on their own thread while the episode is
// still being rendered. Frames arrive from the render thread (encode/frame_pool.h); the sink
// encodes them into one video per --format (and per extra layer), then writes the contact
// sheet, the trajectory JSON and the segmentation legend, and hands the episode's result
// (encode/episode_result.h) to a callback.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <exception>
#include <functional>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "base/cpu_clock.h"
#include "encode/contact_sheet.h"
#include "encode/episode_result.h"
#include "encode/frame_pool.h"
#include "encode/video_format.h"
#include "encode/video_writer.h"
#include "render/layers.h"
#include "render/renderer.h"
#include "src/episode.h"

namespace fetchscope {

/// What every episode sink of a run shares: where the files go, how they are encoded, and what
/// their titles, tags and trajectories name.
struct EpisodeSinkOptions {
  std::string out;        ///< the run folder
  std::string env_id;     ///< the env spec's id
  uint64_t seed = 0;      ///< the run's seed (tags, trajectory)
  std::string seed_text;  ///< the seed as given on the command line (sheet titles)
  std::string policy;     ///< the policy as given (titles, tags, trajectory)
  AssetSource assets;     ///< the trajectory's "assets"
  int steps = 50;         ///< steps per episode: steps + 1 frames (sheet tiles)
  int sheet_every = 0;    ///< every K-th frame on the sheet (SheetFrameIndices); -1: none
  std::vector<std::string> cameras;  ///< the camera of each view, in order (depth scales)
  VideoOptions video;                ///< size and codec decided; format and tags set per file
  /// video formats, rows of VideoFormats(), in --format order
  std::vector<const VideoFormat*> formats;
  std::vector<Layer> layers;  ///< layers beyond rgb, one video per format each
};

/// The stem of episode k's files: "episode_007".
std::string EpisodeFileStem(int k);

/// The file of episode k's `layer` video in `format`: "episode_000_depth.mp4".
std::string LayerVideoName(int k, Layer layer, const VideoFormat& format);

/// The codec a format's file is encoded with: the row's encoder, or the run's H.264 decision
/// `h264` for an H.264 row (mp4).
std::string FormatCodec(const VideoFormat& format, const std::string& h264);

/// The options of episode k's video in `format`: the encoder settings of `options` plus the tags
/// that trace a clip found alone back to its run (ffprobe -show_format lists them).
VideoOptions EpisodeVideoOptions(const EpisodeSinkOptions& options, int k,
                                 const VideoFormat& format);

/// The scale at which the run's GIF shows its frames, {GIF width, frame width}, when the run
/// writes a GIF narrower than its frames; nullopt otherwise. Such a GIF gets its own copy of each
/// frame (Frame::gif_rgb) whose HUD and tile labels are sized for the GIF's width.
std::optional<ShownScale> GifTextScale(const EpisodeSinkOptions& options);

/// Whether the frame of step `t` needs its GIF copy (Frame::gif_rgb): there is a scaled GIF and
/// it keeps that frame (GifKeepsFrame at the run's fps and GIF fps). The GIF takes gif_rgb for
/// every frame; those it drops are never read.
bool NeedsGifCopy(const EpisodeSinkOptions& options, int t);

/// The one line a run prints when its GIF leaves the HUD out (each `tile_width` x `tile_height`
/// view shows smaller in the GIF than the HUD needs, kHudMinTileWidth x kHudMinTileHeight);
/// empty when the GIF has the HUD or there is no scaled GIF.
std::string GifHudNote(const EpisodeSinkOptions& options, int tile_width, int tile_height);

/// Receives an episode's result once its files are written (on the sink's thread); the worker
/// that recorded it is left for the callback to fill in.
using EpisodeDone = std::function<void(int episode, EpisodeResult result)>;

/// One episode's encoding, on its own thread: the videos frame by frame as frames arrive, then
/// the contact sheet, the trajectory JSON and the episode's result, given to `done`. Each video is
/// encoded by one single-threaded encoder, so the bytes never depend on the machine.
class EpisodeEncoder {
 public:
  /// Opens episode k's videos in options.out (here, on the caller's thread, so a bad folder
  /// fails before any frame) and starts the thread. `options` and `pool` must outlive this.
  EpisodeEncoder(const EpisodeSinkOptions& options, int k, FramePool* pool, EpisodeDone done);
  /// Aborts (removing the partial videos) unless Close was called, and joins the thread.
  ~EpisodeEncoder();
  EpisodeEncoder(const EpisodeEncoder&) = delete;
  EpisodeEncoder& operator=(const EpisodeEncoder&) = delete;

  /// Hands a rendered frame over (render thread); the encoder returns it to the pool.
  void Push(Frame* f) { Enqueue(f, Command::kFrame); }
  /// No more frames: finish the files with `episode` as the trajectory; sim_s and render_s
  /// are the render thread's seconds, for the manifest; `render_cpu` its CPU time by stage
  /// (base/cpu_clock.h), to which this thread adds its own (timings_s.cpu_s).
  void Close(EpisodeRecord episode, double sim_s, double render_s, CpuStages render_cpu = {});
  /// The episode's hindsight counts, for its manifest entry; call before Close.
  void SetHindsight(EpisodeHindsight hindsight) { hindsight_ = std::move(hindsight); }
  /// The layers' extras: the segmentation legend JSON (written beside the videos) and the depth
  /// scale (in the manifest entry); call before Close.
  void SetLayerInfo(nlohmann::json legend, std::vector<DepthScale> depth);
  /// No more frames and no files: the partial video is removed.
  void Abort() { Enqueue(nullptr, Command::kAbort); }
  /// Waits for the thread; rethrows its failure.
  void Join();
  /// True once the thread is done (the files written, or abandoned).
  bool finished() const { return finished_.load(); }

 private:
  enum class Command { kFrame, kClose, kAbort };

  void Enqueue(Frame* f, Command c);
  void Body();
  void AddTile(const Frame& f);
  void Finalize();
  std::map<std::string, EpisodeLayer> FinishLayers();

  const EpisodeSinkOptions& options_;
  const int k_;
  FramePool& pool_;
  const EpisodeDone done_;
  const std::string name_;
  std::set<int> on_sheet_;
  std::vector<VideoWriter> writers_;        // one per options.formats entry, in that order
  std::vector<VideoWriter> layer_writers_;  // per options.layers entry, one per format
  std::vector<SheetTile> tiles_;            // scaled at capture (ScaleSheetTile)
  SheetScratch sheet_scratch_;              // ScaleSheetTile's working memory
  EpisodeRecord episode_;
  std::optional<EpisodeHindsight> hindsight_;
  nlohmann::json legend_;                 // the segmentation layer's
  std::vector<DepthScale> depth_scales_;  // the depth layer's, one per camera view
  double sim_s_ = 0, render_s_ = 0, encode_s_ = 0;
  CpuStages render_cpu_;  // the render thread's (from Close)
  CpuStages cpu_;         // this thread's (sheet tiles, then Finalize)
  std::exception_ptr error_;
  std::atomic<bool> finished_{false};
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::pair<Frame*, Command>> queue_;
  std::thread thread_;  // last: starts after every member above exists
};

}  // namespace fetchscope
