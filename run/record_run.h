// One worker of a record run (cli/record.cc): its own environment, policy, GL context, renderer,
// frame pool and episode video sinks (encode/episode_sink.h), driven by the episode scheduler
// (run/episode_scheduler.h). The render thread steps and renders into the pool's reused frame
// buffers while each episode is encoded by its own single-threaded encoder thread, up to
// RecordPlan::encoders episodes at once, so episode k comes out byte for byte the same whatever
// the number of workers or encoders.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "encode/episode_sink.h"
#include "encode/frame_pool.h"
#include "encode/video_format.h"
#include "encode/video_writer.h"
#include "render/gl_context.h"
#include "render/gpu_select.h"
#include "render/layers.h"
#include "render/renderer.h"
#include "render/view.h"
#include "run/episode_scheduler.h"
#include "run/manifest.h"
#include "run/pixel_recorder.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/episode_source.h"
#include "src/hindsight.h"
#include "src/policy_spec.h"

namespace fetchscope {

/// Everything the parent decided before the workers start; workers only read it.
struct RecordPlan {
  const EnvSpec* spec = nullptr;  ///< the environment
  uint64_t seed = 0;              ///< episode 0's reset seed
  std::string seed_text;          ///< the seed as given (sheet titles)
  AssetSource assets;             ///< resolved assets
  PolicySpec policy;              ///< --policy, parsed (record --from: zero, named)
  PolicyContext policy_context;   ///< what the policy is made with
  int steps = 50;                 ///< steps per episode
  ViewSetup view;                 ///< render options (cameras resolved), backend, GPU request
  std::string out;                ///< the run folder
  int sheet_every = 0;            ///< contact sheet: every K-th frame (0: about 12 tiles; -1: none)
  VideoOptions video;             ///< codec already decided; format and metadata set per file
  std::vector<const VideoFormat*> formats;  ///< --format: rows of VideoFormats(), as given
  GpuChoice gpu;                            ///< EGL devices, worker w on devices[w % size]
  int encoders = 1;                         ///< episodes a worker encodes at once
  /// record --from: the episodes to replay (not owned); null: the policy plays them
  const TrajectorySource* from = nullptr;
  bool hindsight = false;        ///< the hindsight overlay: run the episode first, then render it
  std::vector<Layer> layers;     ///< --layers beyond rgb (depth, segmentation), in the order given
  bool contact_signals = false;  ///< --signals contacts: each step's contacts in the trajectory
  /// --obs-camera: each step's images (and states) rendered and staged for the dataset
  PixelPlan pixels;
  int stop_after_success = -1;  ///< --stop-after-success K (-1: off)
  /// --randomize: each episode's look drawn from LookSeed(seed, k) (none: plain); nullopt: not
  /// given (record --from then draws each episode as it stored its look)
  std::optional<LookConfig> look;
  std::optional<uint64_t> look_seed;  ///< --look-seed: the looks' seed instead of `seed`
};

/// The episode sinks' options for `plan`.
EpisodeSinkOptions MakeEpisodeSinkOptions(const RecordPlan& plan);

/// Frames in a worker's pool: those being read back, 4 in flight between rendering and
/// encoding, one held by each encoder, and a whole episode (steps + 1 frames) for each further
/// encoder so that the render thread can run an episode ahead, those within the pool's memory
/// budget (BoundedFrameCount, `frame_bytes`: one frame with its layers).
size_t FramePoolSize(int encoders, int steps, size_t frame_bytes);

/// One worker of a record run. Each episode is played one of three ways: live from the policy;
/// replayed from a recording (record --from); or, for the hindsight overlay, run first without
/// rendering and then replayed with the relabelled goals known. Reports each episode's
/// manifest entry (with "worker" and "hindsight") through the channel once its files are
/// written.
class RecordRunner : public EpisodeRunner {
 public:
  /// Makes the environment and policy; `plan` must outlive the runner.
  RecordRunner(const RecordPlan& plan, int worker);
  /// Aborts the encoders still running, then frees the renderer while its GL context exists.
  ~RecordRunner() override;

  /// Makes the GL context, renderer and frame pool; returns the worker's manifest entry
  /// (backend, device, GL strings, msaa, readback): a ManifestWorker as JSON (StartedWorkers).
  nlohmann::json Start() override;
  /// Plays and renders episode k, handing its frames to a new encoder; returns once rendered
  /// (the encoding may go on), after waiting for the oldest encoder beyond plan.encoders.
  void Run(int k, WorkerChannel& channel) override;
  /// Waits for every encoder.
  void Finish(WorkerChannel& channel) override;

 private:
  EpisodeRecord PlayEpisode(int k, const StepCallback& on_step, WorkerChannel& channel);
  HindsightEpisode SampleEpisodeHindsight(int k, const std::vector<StepRecord>& steps);
  EpisodeHindsight HindsightCounts(const EpisodeRecord& episode);
  void AddRelabelled(int t, FrameInfo* info) const;
  // Episode k's look (run/episode_look.h), set on the renderer and the pixel recorder; the
  // thread CPU it took (the draw, the textures made and uploaded) is added to *cpu.
  std::optional<LookDraw> SetEpisodeLook(int k, double* cpu);
  void RenderLayers(const mjData* data, const FrameInfo& info, Frame* f, EpisodeLegend* legend,
                    std::vector<DepthScale>* depth_scales);

  const RecordPlan& plan_;
  const int worker_;
  const EpisodeSinkOptions sink_;
  const std::optional<ShownScale>
      gif_scale_;  // GifTextScale(sink_): a scaled-down GIF's own HUD size
  EpisodeSequence sequence_;
  std::unique_ptr<FetchEnv> replay_env_;       // hindsight: the env the replay renders
  std::unique_ptr<EpisodeReplayer> replayer_;  // --from, hindsight
  FetchEnv* render_env_ = nullptr;             // the env being replayed, while it is
  std::optional<HindsightEpisode> hindsight_;  // this episode's relabelling (hindsight overlay)
  std::vector<uint8_t> depth_;                 // the depth layer's millimetres, reused
  // Lifetime order: the GL context outlives the renderer; encoders go first (they hold frames).
  std::unique_ptr<GlContext> gl_;
  std::optional<Renderer> renderer_;
  std::optional<PixelRecorder> pixels_;  // --obs-camera's images, on gl_
  std::optional<FramePool> pool_;
  std::deque<std::unique_ptr<EpisodeEncoder>> encoders_;
};

/// Records `schedule.episodes` on `schedule.jobs` workers (LimitLlvmpipeThreads first), each
/// a RecordRunner of `plan`: the scheduler's result, with each episode's result as JSON
/// (RecordResults types them).
ScheduleResult RecordEpisodes(const RecordPlan& plan, const ScheduleOptions& schedule);

/// An episode's result as the worker channel carries it (WorkerChannel::Done), and back: the one
/// place where a record result is JSON. EpisodeResultFromJson throws ManifestError for what is
/// not a result.
nlohmann::json EpisodeResultToJson(const EpisodeResult& result);
EpisodeResult EpisodeResultFromJson(const nlohmann::json& json);

/// The results of a record schedule, typed (EpisodeResultFromJson), by episode.
std::map<int, EpisodeResult> RecordResults(const ScheduleResult& result);

/// What each worker of a record schedule reported when it started (RecordRunner::Start), typed;
/// a worker that reported nothing has its index alone.
std::vector<ManifestWorker> StartedWorkers(const ScheduleResult& result);

/// llvmpipe starts one rasteriser thread per core in every context; with several workers that
/// oversubscribes the cores, so with `jobs` > 1 each worker rasterises on its own thread instead
/// (LP_NUM_THREADS=0, unless the user set it). Hardware drivers ignore the variable.
void LimitLlvmpipeThreads(int jobs);

/// Episodes one worker encodes at once: the usable cores shared out over `jobs` workers, C/N
/// (each encoder is one thread, so that the bytes never depend on the thread count), at least 1.
/// An encoder only holds frames while it is behind the render thread, so memory grows with
/// encoders only where the encoders, not the renderer, are the bottleneck.
int EncodersPerWorker(int jobs);

/// Adds the run's CPU account to the manifest's `timings` (timings_s): "cpu_s", the thread CPU
/// seconds of each stage summed over episodes (`stages`, the entries' timings_s.cpu_s added up),
/// with "outside_gl" (every stage but gl) and "process" (the whole process and its waited-for
/// children: start-up, and threads no stage sees such as llvmpipe's rasterisers); and
/// "cpu_ms_per_frame", the same per recorded frame (`frames`).
void AddCpuAccount(const std::map<std::string, double>& stages, long frames,
                   ManifestTimings* timings);

}  // namespace fetchscope
