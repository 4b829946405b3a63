// fetchscope record: episodes -> a run folder of MP4 videos, contact sheets, trajectories and
// one manifest. Rendering and encoding overlap: each worker steps and renders into a small ring
// of reused frame buffers while an encoder thread converts and encodes them. --jobs N runs N
// workers, each with its own env, policy, GL context and renderer; --shard I/N records every
// N-th episode so that machines split a batch. Either way episode k comes out exactly as in a
// sequential run: a worker replays the resets and policy draws of the episodes it skips.
#include <signal.h>
#include <unistd.h>

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

#include "cli/common.h"
#include "cli/render_common.h"
#include "cli/shard.h"
#include "render/contact_sheet.h"
#include "render/png_io.h"
#include "render/renderer.h"
#include "render/video_writer.h"
#include "src/errors.h"
#include "src/json_util.h"

namespace fetchscope::cli {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;


double Since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

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
  int sheet_every = 0;
  std::string out = "out";
  bool quiet = false;
  int jobs = 1;                 // workers; 0 = one per core
  std::string shard;            // "I/N"; empty: from the environment, else the whole run
  int shard_count = 0;          // with JOB_COMPLETION_INDEX; 0 = not given
};

// One rendered frame travelling from the render thread to the encoder thread.
struct Frame {
  std::vector<uint8_t> rgb;
  int t = 0;
  std::string label;
  bool last = false;
  bool empty = false;  // an end marker that carries no picture (episode failed before its first frame)
};

// A fixed pool of frame buffers passed between two threads: no per-frame allocation.
class FrameRing {
 public:
  FrameRing(size_t count, size_t bytes) {
    for (size_t i = 0; i < count; ++i) {
      pool_.push_back(std::make_unique<Frame>());
      pool_.back()->rgb.resize(bytes);
      free_.push_back(pool_.back().get());
    }
  }
  Frame* AcquireFree() { return Take(free_); }
  void PushFilled(Frame* f) { Give(filled_, f); }
  Frame* AcquireFilled() { return Take(filled_); }
  void Release(Frame* f) { Give(free_, f); }

 private:
  Frame* Take(std::deque<Frame*>& q) {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [&] { return !q.empty(); });
    Frame* f = q.front();
    q.pop_front();
    return f;
  }
  void Give(std::deque<Frame*>& q, Frame* f) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      q.push_back(f);
    }
    cv_.notify_all();
  }
  std::vector<std::unique_ptr<Frame>> pool_;
  std::deque<Frame*> free_, filled_;
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

struct Timings {
  double sim = 0, render = 0, encode = 0, write = 0;
  Timings& operator+=(const Timings& t) {
    sim += t.sim;
    render += t.render;
    encode += t.encode;
    write += t.write;
    return *this;
  }
};

// The progress line on stderr, fed by every worker.
class Progress {
 public:
  Progress(bool quiet, int episodes, int frames_per_episode)
      : quiet_(quiet), tty_(isatty(STDERR_FILENO)), episodes_(episodes), per_(frames_per_episode),
        start_(Clock::now()) {}
  void Frame() {
    std::lock_guard<std::mutex> lock(mutex_);
    ++frames_;
    Draw();
  }
  void EpisodeDone() {
    std::lock_guard<std::mutex> lock(mutex_);
    ++done_;
  }
  void Done(const std::string& summary) {
    if (quiet_) return;
    if (tty_) std::fprintf(stderr, "\r%*s\r", 78, "");
    std::fprintf(stderr, "%s\n", summary.c_str());
  }
  long frames() {
    std::lock_guard<std::mutex> lock(mutex_);
    return frames_;
  }

 private:
  void Draw() {
    if (quiet_ || !tty_) return;
    const double elapsed = Since(start_);
    if (elapsed - last_ < 0.1) return;
    last_ = elapsed;
    const double fps = frames_ / elapsed;
    const long total = static_cast<long>(episodes_) * per_;
    const double eta = fps > 0 ? (total - frames_) / fps : 0;
    std::fprintf(stderr, "\rrecord: %d/%d episodes  frame %ld/%ld  %.1f frames/s  ETA %.0f s   ",
                 done_, episodes_, frames_, total, fps, eta);
  }

  std::mutex mutex_;
  bool quiet_, tty_;
  int episodes_, per_;
  Clock::time_point start_;
  long frames_ = 0;
  int done_ = 0;
  double last_ = -1;
};

// What the workers share: the run's settings, the queue of episodes, and the results.
struct RunState {
  const RecordOptions* o = nullptr;
  const EnvSpec* spec = nullptr;
  uint64_t seed = 0;
  VideoOptions video;
  std::vector<int> episodes;           // this shard's, ascending
  std::atomic<size_t> next{0};         // index into `episodes` of the next unclaimed one
  std::atomic<bool> failed{false};     // a worker threw: the others abandon their episode
  Progress* progress = nullptr;

  std::mutex mutex;                    // guards everything below
  std::map<int, nlohmann::json> done;  // manifest entries by episode index
  Timings timings;                     // summed over workers
  int successes = 0;
  std::string codec_used;
  int encoded_w = 0, encoded_h = 0;
  std::optional<GlInfo> gl_info;       // the first worker's
  int msaa = 0;                        // the first worker's renderer: samples used
  std::string msaa_reason;             // and why ("auto: software renderer llvmpipe")
  std::exception_ptr error;            // the first worker's failure

  bool Stop() const { return StopSignal() != 0 || failed.load(); }
};

// MuJoCo 2.2 binds its GL functions at the first mjr_makeContext of the process; contexts and
// renderers are made one at a time so no two threads race through that.
std::mutex g_setup_mutex;

// One worker: its own environment, policy, GL context, renderer and frame ring. Workers claim
// episodes in ascending order and bring their generators forward over the episodes others
// play, so episode k comes out exactly as in a sequential run.
class Worker {
 public:
  Worker(RunState* run, std::unique_ptr<FetchEnv> env, std::unique_ptr<Policy> policy,
         RenderOptions render_options)
      : run_(*run), env_(std::move(env)), policy_(std::move(policy)),
        render_options_(std::move(render_options)) {}

  // The thread body: never throws; a failure is stored in the run state.
  void Run() {
    try {
      {
        std::lock_guard<std::mutex> lock(g_setup_mutex);
        gl_ = CreateGlContext(run_.o->view.backend, run_.o->view.gpu);
        renderer_.emplace(*gl_, env_->model(), render_options_);
      }
      {
        std::lock_guard<std::mutex> lock(run_.mutex);
        if (!run_.gl_info) {
          run_.gl_info = gl_->info();
          run_.msaa = renderer_->msaa_samples();
          run_.msaa_reason = renderer_->msaa_reason();
        }
      }
      const size_t frame_bytes = static_cast<size_t>(run_.o->view.width) * run_.o->view.height * 3;
      ring_.emplace(4, frame_bytes);
      while (!run_.Stop()) {
        const size_t slot = run_.next.fetch_add(1);
        if (slot >= run_.episodes.size()) break;
        Record(run_.episodes[slot]);
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(run_.mutex);
      if (!run_.error) run_.error = std::current_exception();
      run_.failed.store(true);
    }
    // the renderer's MuJoCo context is freed with this worker's GL context current
    renderer_.reset();
    gl_.reset();
  }

 private:
  // Brings the env's generator and the policy's state to the start of episode k, as the
  // episodes before it would have left them (a reset draws only from the env's generator).
  void CatchUp(int k) {
    for (; next_episode_ < k; ++next_episode_) {
      env_->Reset(next_episode_ == 0 ? std::optional<uint64_t>(run_.seed) : std::nullopt);
      policy_->SkipEpisode(run_.o->steps);
    }
    next_episode_ = k + 1;
  }

  void Record(int k) {
    const RecordOptions& o = *run_.o;
    CatchUp(k);
    Timings timings;
    const std::string name = EpisodeName(k);
    const std::string video_path = (fs::path(o.out) / (name + ".mp4")).string();
    VideoWriter writer(video_path, run_.video);
    const std::vector<int> sheet_index = SheetFrameIndices(o.steps + 1, o.sheet_every);
    const std::set<int> on_sheet(sheet_index.begin(), sheet_index.end());
    std::vector<SheetTile> tiles;
    std::exception_ptr encoder_error;
    FrameRing& ring = *ring_;

    // encoder thread: frames in order, until the one marked last
    std::thread encoder([&] {
      bool failed = false;
      while (true) {
        Frame* f = ring.AcquireFilled();
        const bool last = f->last;
        if (!failed && !f->empty) {
          try {
            const auto t0 = Clock::now();
            writer.AddFrame(f->rgb.data());
            timings.encode += Since(t0);
            if (on_sheet.count(f->t) || last) {
              tiles.push_back({f->rgb, o.view.width, o.view.height, f->label});
            }
          } catch (...) {
            encoder_error = std::current_exception();
            failed = true;
          }
        }
        ring.Release(f);
        if (last) break;
      }
    });

    renderer_->ResetTrail();
    Frame* pending = nullptr;  // rendered, held back until we know whether it is the last
    auto sim_start = Clock::now();
    auto on_step = [&](const StepRecord& record, const StepResult*) {
      timings.sim += Since(sim_start);
      const auto t0 = Clock::now();
      Frame* f = ring.AcquireFree();
      const FrameInfo info = MakeFrameInfo(*env_, record);
      renderer_->Render(env_->data(), info, f->rgb.data());
      f->t = record.t;
      f->label = TileLabel(info);
      f->last = false;
      f->empty = false;
      timings.render += Since(t0);
      if (pending) ring.PushFilled(pending);
      pending = f;
      run_.progress->Frame();
      sim_start = Clock::now();
      return !run_.Stop();
    };
    EpisodeRecord episode;
    try {
      episode = RunEpisode(*env_, *policy_, k, k == 0 ? std::optional<uint64_t>(run_.seed) : std::nullopt,
                           o.steps, on_step);
    } catch (...) {
      if (!pending) {
        pending = ring.AcquireFree();
        pending->empty = true;
      }
      pending->last = true;
      ring.PushFilled(pending);
      encoder.join();
      throw;  // the writer's destructor removes the partial video
    }
    pending->last = true;
    ring.PushFilled(pending);
    encoder.join();
    if (encoder_error) std::rethrow_exception(encoder_error);
    // another worker failed: drop this episode (the writer removes its partial video); a
    // signal instead finishes it, so that what was recorded plays
    if (run_.failed.load() && StopSignal() == 0) return;

    const auto t0 = Clock::now();
    writer.Finish();
    char title[256];
    std::snprintf(title, sizeof(title), "%s  seed %s  policy %s  episode %d%s", run_.spec->id.c_str(),
                  o.env.seed.c_str(), o.policy.c_str(), k,
                  static_cast<int>(episode.steps.size()) - 1 < o.steps ? "  (interrupted)" : "");
    const SheetImage sheet = MakeContactSheet(title, tiles);
    const std::string sheet_path = (fs::path(o.out) / (name + "_sheet.png")).string();
    WritePng(sheet_path, sheet.width, sheet.height, 3, 8, sheet.rgb.data());
    const std::string json_path = (fs::path(o.out) / (name + ".json")).string();
    WriteJson(json_path, TrajectoryJson(*env_, run_.seed, o.policy, {&episode}));
    timings.write += Since(t0);
    const bool success = episode.steps.back().is_success;
    nlohmann::json entry = {{"index", k},
                            {"video", name + ".mp4"},
                            {"sheet", name + "_sheet.png"},
                            {"trajectory", name + ".json"},
                            {"frames", writer.frames_written()},
                            {"steps", static_cast<int>(episode.steps.size()) - 1},
                            {"return", JsonDouble(episode.episode_return)},
                            {"is_success", success}};
    run_.progress->EpisodeDone();
    std::lock_guard<std::mutex> lock(run_.mutex);
    run_.done[k] = std::move(entry);
    run_.timings += timings;
    run_.successes += success;
    run_.codec_used = writer.codec_name();
    run_.encoded_w = writer.encoded_width();
    run_.encoded_h = writer.encoded_height();
  }

  RunState& run_;
  std::unique_ptr<FetchEnv> env_;
  std::unique_ptr<Policy> policy_;
  RenderOptions render_options_;
  int next_episode_ = 0;  // the episode the env's generator and the policy stand at
  // Lifetime order: the GL context outlives the renderer (reset explicitly in Run).
  std::unique_ptr<GlContext> gl_;
  std::optional<Renderer> renderer_;
  std::optional<FrameRing> ring_;
};

// llvmpipe starts one rasteriser thread per core in every context; with several workers that
// oversubscribes the cores, so each worker rasterises on its own thread instead (unless the
// user chose). Hardware drivers ignore the variable.
void LimitLlvmpipeThreads(int jobs) {
  if (jobs > 1) setenv("LP_NUM_THREADS", "0", /*overwrite=*/0);
}

void RunRecord(const RecordOptions& o, const std::string& command_line) {
  const auto wall_start = Clock::now();
  const EnvSpec& spec = FindEnvSpec(o.env.env_id);
  const uint64_t seed = ParseSeed(o.env.seed);
  const Shard shard = ResolveShard(o.shard, o.shard_count);
  RunState run;
  run.o = &o;
  run.spec = &spec;
  run.seed = seed;
  run.video.width = o.view.width;
  run.video.height = o.view.height;
  run.video.fps = o.fps;
  run.video.codec = o.codec;
  run.video.crf = o.crf;
  run.video.preset = o.preset;
  ValidateVideoOptions(run.video);
  run.episodes = ShardEpisodes(shard, o.episodes);
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const int jobs = std::max(1, std::min(o.jobs == 0 ? cores : o.jobs, static_cast<int>(run.episodes.size())));

  PolicyContext context;
  context.seed = seed;
  context.steps_per_episode = o.steps;
  context.episodes = o.episodes;
  context.exec_timeout_s = o.exec_timeout;
  // Every worker gets its own model (the renderer writes the model's offscreen size), env and
  // policy (an exec: policy starts one child per worker). Built here, one after another, so
  // bad options fail before anything is written.
  std::vector<std::unique_ptr<Worker>> workers;
  const AssetSource assets = ResolveAssets(o.env.assets);
  std::string model_path;
  nlohmann::json assets_json;
  for (int w = 0; w < jobs; ++w) {
    auto policy = MakePolicy(o.policy, spec, context);
    auto env = std::make_unique<FetchEnv>(spec, assets);
    RenderOptions render_options = MakeRenderOptions(o.view, env->model());
    if (w == 0) {
      model_path = env->model_path();
      assets_json = AssetsJson(env->assets());
    }
    workers.push_back(std::make_unique<Worker>(&run, std::move(env), std::move(policy),
                                               std::move(render_options)));
  }

  std::error_code ec;
  fs::create_directories(o.out, ec);
  if (!fs::is_directory(o.out)) {
    throw RunError("cannot create output folder '" + o.out + "': " +
                   (ec ? ec.message() : std::string("a file is in the way")));
  }

  InstallStopSignals();

  Progress progress(o.quiet, static_cast<int>(run.episodes.size()), o.steps + 1);
  run.progress = &progress;
  LimitLlvmpipeThreads(jobs);
  std::vector<std::thread> threads;
  for (int w = 1; w < jobs; ++w) threads.emplace_back([&workers, w] { workers[w]->Run(); });
  workers[0]->Run();  // worker 0 on this thread
  for (std::thread& t : threads) t.join();
  workers.clear();  // GL contexts, renderers and exec children go now
  if (run.error) std::rethrow_exception(run.error);

  const int sig = StopSignal();
  const double wall = Since(wall_start);
  const GlInfo gi = run.gl_info.value_or(GlInfo{});
  nlohmann::json episodes_json = nlohmann::json::array();
  for (auto& [k, entry] : run.done) episodes_json.push_back(std::move(entry));
  nlohmann::json shard_json = {{"index", shard.index},
                               {"count", shard.count},
                               {"source", shard.source.empty() ? nlohmann::json(nullptr) : nlohmann::json(shard.source)},
                               {"episodes", run.episodes}};
  const Timings& timings = run.timings;
  nlohmann::json manifest = {
      {"env_id", spec.id},
      {"seed", seed},
      {"policy", o.policy},
      {"episodes_requested", o.episodes},
      {"steps_per_episode", o.steps},
      {"sheet_every", o.sheet_every},
      {"episodes", episodes_json},
      {"shard", shard_json},
      {"jobs", jobs},
      {"assets", assets_json},
      {"model_file", model_path},
      {"camera", o.view.camera},
      {"overlay", o.view.overlay},
      {"msaa", run.msaa},
      {"msaa_reason", run.msaa_reason},
      {"backend", {{"name", gi.backend}, {"device", gi.device}, {"gl_vendor", gi.vendor},
                   {"gl_renderer", gi.renderer}, {"gl_version", gi.version}}},
      {"video", {{"codec", run.codec_used}, {"crf", o.crf}, {"preset", o.preset.empty() ? kDefaultVideoPreset : o.preset},
                 {"fps", o.fps}, {"width", o.view.width}, {"height", o.view.height},
                 {"encoded_width", run.encoded_w}, {"encoded_height", run.encoded_h},
                 {"container", "mp4"}, {"pix_fmt", "yuv420p"}}},
      {"versions", VersionsJson()},
      {"timings_s", {{"wall", wall}, {"sim", timings.sim}, {"render", timings.render},
                     {"encode", timings.encode}, {"write", timings.write}}},
      {"frames", progress.frames()},
      {"interrupted", sig != 0},
      {"signal", sig == 0 ? nlohmann::json(nullptr) : nlohmann::json(sig == SIGINT ? "SIGINT" : "SIGTERM")},
      {"command_line", command_line}};
  WriteJson((fs::path(o.out) / ShardManifestName(shard)).string(), manifest);
  const size_t recorded = episodes_json.size();
  char summary[640];
  std::snprintf(summary, sizeof(summary),
                "record: %zu episode(s), %ld frames in %.1f s (%.1f frames/s, %.2f episodes/s, %d "
                "job(s)%s%s), success %d/%zu, %s via %s, %s -> %s%s",
                recorded, progress.frames(), wall, progress.frames() / wall, recorded / wall, jobs,
                shard.sharded() ? ", shard " : "", shard.sharded() ? ShardLabel(shard).c_str() : "",
                run.successes, recorded, gi.renderer.c_str(), gi.backend.c_str(), run.codec_used.c_str(),
                o.out.c_str(), sig ? " (interrupted)" : "");
  progress.Done(summary);
  if (sig) ExitStatus() = 128 + sig;
}

}  // namespace

void RegisterRecord(CLI::App& app) {
  auto o = std::make_shared<RecordOptions>();
  CLI::App* sub = app.add_subcommand(
      "record", "Record episodes: episode_NNN.mp4, episode_NNN_sheet.png, episode_NNN.json, manifest.json");
  AddEnvOptions(sub, &o->env);
  AddViewOptions(sub, &o->view);
  sub->add_option("--episodes", o->episodes, "Number of episodes")->capture_default_str()->check(CLI::Range(1, 1000000));
  sub->add_option("--steps", o->steps, "Steps per episode (TimeLimit is 50)")->capture_default_str()->check(CLI::Range(1, 50));
  sub->add_option("--policy", o->policy, kPolicyHelp)->capture_default_str();
  sub->add_option("--exec-timeout", o->exec_timeout, "Seconds an exec: policy may take per answer")
      ->capture_default_str()->check(CLI::Range(0.001, 86400.0));
  sub->add_option("--fps", o->fps, "Video frame rate (25 = the control rate: real time)")->capture_default_str();
  sub->add_option("--codec", o->codec, "auto (h264_nvenc if it opens, else libx264), libx264 or h264_nvenc")->capture_default_str();
  sub->add_option("--crf", o->crf, "H.264 quality, 0 (lossless) .. 51 (worst)")->capture_default_str();
  sub->add_option("--preset", o->preset, std::string("Encoder preset (default ") + kDefaultVideoPreset + ")");
  sub->add_option("--sheet-every", o->sheet_every, "Contact sheet: every K-th frame (0: about 12 tiles); the last frame is always included")
      ->capture_default_str()->check(CLI::Range(0, 1000));
  sub->add_option("--out", o->out, "Output folder")->capture_default_str();
  sub->add_flag("-q,--quiet", o->quiet, "No progress or summary on stderr");
  sub->add_option("-j,--jobs", o->jobs,
                  "Episodes recorded in parallel, each worker with its own GL context (0: one per "
                  "core); outputs are identical to --jobs 1")
      ->capture_default_str()->check(CLI::Range(0, 256));
  sub->add_option("--shard", o->shard,
                  "Record only shard I of N (0 <= I < N): episodes k with k mod N = I. Without it: "
                  "JOB_COMPLETION_INDEX (with --shard-count) or SLURM_ARRAY_TASK_ID/COUNT if set");
  sub->add_option("--shard-count", o->shard_count,
                  "Number of shards when the index comes from JOB_COMPLETION_INDEX (a Kubernetes "
                  "Indexed Job's completions)");
  sub->callback([o]() { RunRecord(*o, CommandLine()); });
}

}  // namespace fetchscope::cli
