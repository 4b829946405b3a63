// fetchscope record: episodes -> a run folder of MP4 videos, contact sheets, trajectories and
// one manifest. Rendering and encoding overlap: the main thread steps and renders into a small
// ring of reused frame buffers while an encoder thread converts and encodes them.
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <mutex>
#include <set>
#include <thread>

#include "cli/common.h"
#include "cli/render_common.h"
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

std::atomic<int> g_signal{0};
void OnSignal(int sig) { g_signal.store(sig); }

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
};

class Progress {
 public:
  Progress(bool quiet, int episodes, int frames_per_episode)
      : quiet_(quiet), tty_(isatty(STDERR_FILENO)), episodes_(episodes), per_(frames_per_episode),
        start_(Clock::now()) {}
  void Frame(int episode) {
    ++frames_;
    if (quiet_ || !tty_) return;
    const double elapsed = Since(start_);
    if (elapsed - last_ < 0.1) return;
    last_ = elapsed;
    const double fps = frames_ / elapsed;
    const long total = static_cast<long>(episodes_) * per_;
    const double eta = fps > 0 ? (total - frames_) / fps : 0;
    std::fprintf(stderr, "\rrecord: episode %d/%d  frame %ld/%ld  %.1f frames/s  ETA %.0f s   ",
                 episode + 1, episodes_, frames_, total, fps, eta);
  }
  void Done(const std::string& summary) {
    if (quiet_) return;
    if (tty_) std::fprintf(stderr, "\r%*s\r", 78, "");
    std::fprintf(stderr, "%s\n", summary.c_str());
  }
  long frames() const { return frames_; }

 private:
  bool quiet_, tty_;
  int episodes_, per_;
  Clock::time_point start_;
  long frames_ = 0;
  double last_ = -1;
};

void RunRecord(const RecordOptions& o, const std::string& command_line) {
  const auto wall_start = Clock::now();
  const EnvSpec& spec = FindEnvSpec(o.env.env_id);
  const uint64_t seed = ParseSeed(o.env.seed);
  VideoOptions video;
  video.width = o.view.width;
  video.height = o.view.height;
  video.fps = o.fps;
  video.codec = o.codec;
  video.crf = o.crf;
  video.preset = o.preset;
  ValidateVideoOptions(video);
  PolicyContext context;
  context.seed = seed;
  context.steps_per_episode = o.steps;
  context.episodes = o.episodes;
  context.exec_timeout_s = o.exec_timeout;
  auto policy = MakePolicy(o.policy, spec, context);
  FetchEnv env(spec, ResolveAssets(o.env.assets));
  const RenderOptions render_options = MakeRenderOptions(o.view, env.model());

  std::error_code ec;
  fs::create_directories(o.out, ec);
  if (!fs::is_directory(o.out)) {
    throw RunError("cannot create output folder '" + o.out + "': " +
                   (ec ? ec.message() : std::string("a file is in the way")));
  }
  auto gl = CreateGlContext(o.view.backend, o.view.gpu);
  Renderer renderer(*gl, env.model(), render_options);

  g_signal.store(0);
  struct sigaction sa {};
  sa.sa_handler = OnSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);

  const size_t frame_bytes = static_cast<size_t>(o.view.width) * o.view.height * 3;
  FrameRing ring(4, frame_bytes);
  Timings timings;
  Progress progress(o.quiet, o.episodes, o.steps + 1);
  nlohmann::json episodes_json = nlohmann::json::array();
  std::string codec_used;
  int encoded_w = 0, encoded_h = 0;
  int successes = 0;

  for (int k = 0; k < o.episodes && g_signal.load() == 0; ++k) {
    const std::string name = EpisodeName(k);
    const std::string video_path = (fs::path(o.out) / (name + ".mp4")).string();
    VideoWriter writer(video_path, video);
    codec_used = writer.codec_name();
    encoded_w = writer.encoded_width();
    encoded_h = writer.encoded_height();
    const std::vector<int> sheet_index = SheetFrameIndices(o.steps + 1, o.sheet_every);
    const std::set<int> on_sheet(sheet_index.begin(), sheet_index.end());
    std::vector<SheetTile> tiles;
    std::exception_ptr encoder_error;

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

    renderer.ResetTrail();
    Frame* pending = nullptr;  // rendered, held back until we know whether it is the last
    auto sim_start = Clock::now();
    auto on_step = [&](const StepRecord& record, const StepResult*) {
      timings.sim += Since(sim_start);
      const auto t0 = Clock::now();
      Frame* f = ring.AcquireFree();
      const FrameInfo info = MakeFrameInfo(env, record);
      renderer.Render(env.data(), info, f->rgb.data());
      f->t = record.t;
      f->label = TileLabel(info);
      f->last = false;
      f->empty = false;
      timings.render += Since(t0);
      if (pending) ring.PushFilled(pending);
      pending = f;
      progress.Frame(k);
      sim_start = Clock::now();
      return g_signal.load() == 0;
    };
    EpisodeRecord episode;
    try {
      episode = RunEpisode(env, *policy, k, k == 0 ? std::optional<uint64_t>(seed) : std::nullopt,
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

    const auto t0 = Clock::now();
    writer.Finish();
    char title[256];
    std::snprintf(title, sizeof(title), "%s  seed %s  policy %s  episode %d%s", spec.id.c_str(),
                  o.env.seed.c_str(), o.policy.c_str(), k,
                  g_signal.load() ? "  (interrupted)" : "");
    const SheetImage sheet = MakeContactSheet(title, tiles);
    const std::string sheet_path = (fs::path(o.out) / (name + "_sheet.png")).string();
    WritePng(sheet_path, sheet.width, sheet.height, 3, 8, sheet.rgb.data());
    const std::string json_path = (fs::path(o.out) / (name + ".json")).string();
    WriteJson(json_path, TrajectoryJson(env, seed, o.policy, {&episode}));
    timings.write += Since(t0);
    const bool success = episode.steps.back().is_success;
    successes += success;
    episodes_json.push_back({{"index", k},
                             {"video", name + ".mp4"},
                             {"sheet", name + "_sheet.png"},
                             {"trajectory", name + ".json"},
                             {"frames", writer.frames_written()},
                             {"steps", static_cast<int>(episode.steps.size()) - 1},
                             {"return", JsonDouble(episode.episode_return)},
                             {"is_success", success}});
  }

  const int sig = g_signal.load();
  const double wall = Since(wall_start);
  const GlInfo& gi = gl->info();
  nlohmann::json manifest = {
      {"env_id", spec.id},
      {"seed", seed},
      {"policy", o.policy},
      {"episodes_requested", o.episodes},
      {"steps_per_episode", o.steps},
      {"episodes", episodes_json},
      {"assets", AssetsJson(env.assets())},
      {"model_file", env.model_path()},
      {"camera", o.view.camera},
      {"overlay", o.view.overlay},
      {"backend", {{"name", gi.backend}, {"device", gi.device}, {"gl_vendor", gi.vendor},
                   {"gl_renderer", gi.renderer}, {"gl_version", gi.version}}},
      {"video", {{"codec", codec_used}, {"crf", o.crf}, {"preset", o.preset.empty() ? kDefaultVideoPreset : o.preset},
                 {"fps", o.fps}, {"width", o.view.width}, {"height", o.view.height},
                 {"encoded_width", encoded_w}, {"encoded_height", encoded_h},
                 {"container", "mp4"}, {"pix_fmt", "yuv420p"}}},
      {"versions", VersionsJson()},
      {"timings_s", {{"wall", wall}, {"sim", timings.sim}, {"render", timings.render},
                     {"encode", timings.encode}, {"write", timings.write}}},
      {"frames", progress.frames()},
      {"interrupted", sig != 0},
      {"signal", sig == 0 ? nlohmann::json(nullptr) : nlohmann::json(sig == SIGINT ? "SIGINT" : "SIGTERM")},
      {"command_line", command_line}};
  WriteJson((fs::path(o.out) / "manifest.json").string(), manifest);
  char summary[512];
  std::snprintf(summary, sizeof(summary),
                "record: %zu episode(s), %ld frames in %.1f s (%.1f frames/s), success %d/%zu, "
                "%s via %s, %s -> %s%s",
                episodes_json.size(), progress.frames(), wall, progress.frames() / wall, successes,
                episodes_json.size(), gi.renderer.c_str(), gi.backend.c_str(), codec_used.c_str(),
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
  sub->callback([o]() { RunRecord(*o, CommandLine()); });
}

}  // namespace fetchscope::cli
