#include "run/record_run.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "base/cores.h"
#include "base/cpu_clock.h"
#include "render/layers.h"
#include "run/episode_look.h"
#include "src/policy.h"

namespace fetchscope {
namespace {

using Clock = std::chrono::steady_clock;

double Since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

}  // namespace

EpisodeSinkOptions MakeEpisodeSinkOptions(const RecordPlan& plan) {
  EpisodeSinkOptions sink;
  sink.out = plan.out;
  sink.env_id = plan.spec->id;
  sink.seed = plan.seed;
  sink.seed_text = plan.seed_text;
  sink.policy = plan.policy.text;
  sink.assets = plan.assets;
  sink.steps = plan.steps;
  sink.sheet_every = plan.sheet_every;
  for (const CameraSpec& camera : plan.view.render.cameras) sink.cameras.push_back(camera.name);
  sink.video = plan.video;
  sink.formats = plan.formats;
  sink.layers = plan.layers;
  return sink;
}

size_t FramePoolSize(int encoders, int steps, size_t frame_bytes) {
  const size_t floor = 4 + kReadbackDepth + encoders;
  return BoundedFrameCount(floor, floor + static_cast<size_t>(encoders - 1) * (steps + 1),
                           frame_bytes);
}

RecordRunner::RecordRunner(const RecordPlan& plan, int worker)
    : plan_(plan),
      worker_(worker),
      sink_(MakeEpisodeSinkOptions(plan)),
      gif_scale_(GifTextScale(sink_)),
      sequence_(std::make_unique<FetchEnv>(*plan.spec, plan.assets),
                // --from replays recorded actions: the policy that made them is not run
                MakePolicy(plan.from ? PolicySpec::Zero() : plan.policy, *plan.spec,
                           WithImages(plan.policy_context, &pixels_)),
                plan.seed, plan.steps) {
  if (plan.contact_signals) sequence_.env().EnableContactSignals();
  sequence_.SetStopAfterSuccess(plan.stop_after_success);
}

RecordRunner::~RecordRunner() {
  encoders_.clear();  // aborts and joins whatever is still running (a failure elsewhere)
  pixels_.reset();
  renderer_.reset();  // the renderer's MuJoCo context is freed with its GL context current
  gl_.reset();
}

nlohmann::json RecordRunner::Start() {
  gl_ = CreateViewContext(plan_.view.backend, plan_.gpu, worker_);
  renderer_.emplace(*gl_, sequence_.env().model(), plan_.view.render);
  if (plan_.pixels.enabled()) pixels_.emplace(plan_.pixels, gl_.get(), sequence_.env().model());
  const size_t frame_bytes = static_cast<size_t>(renderer_->width()) * renderer_->height() * 3;
  pool_.emplace(FramePoolSize(plan_.encoders, plan_.steps, frame_bytes * (1 + plan_.layers.size())),
                frame_bytes, plan_.layers.size(), gif_scale_.has_value());
  const GlInfo& gi = gl_->info();
  ManifestWorker info;
  info.worker = worker_;
  info.pid = static_cast<long>(getpid());
  info.backend = gi.backend;
  info.device = gi.device;
  info.device_selection = gl_->selection();
  info.gl_vendor = gi.vendor;
  info.gl_renderer = gi.renderer;
  info.gl_version = gi.version;
  info.msaa = renderer_->msaa_samples();
  info.msaa_reason = renderer_->msaa_reason();
  info.readback = renderer_->readback_reason();
  return ManifestWorkerToJson(info);  // the worker channel's JSON
}

namespace {

// An episode's CPU by stage: sim, and the renderer's own stages between `before` and `after`,
// the rest of the render thread's time (`render_cpu`) as render_other.
CpuStages EpisodeCpu(const CpuStages& before, const CpuStages& after, double sim_cpu,
                     double render_cpu, double look_cpu) {
  CpuStages cpu;
  cpu.sim = sim_cpu;
  cpu.look = look_cpu;
  cpu.scene = after.scene - before.scene;
  cpu.gl = after.gl - before.gl;
  cpu.hud = after.hud - before.hud;
  cpu.copy = after.copy - before.copy;
  cpu.render_other = std::max(0.0, render_cpu - (cpu.scene + cpu.gl + cpu.hud + cpu.copy));
  return cpu;
}

}  // namespace

// The --layers of the frame just submitted, drawn after its rgb readback was queued and read at
// once: segmentation into the frame (its objects into `legend`), depth as grey in the scale of
// the episode's first frame.
void RecordRunner::RenderLayers(const mjData* data, const FrameInfo& info, Frame* f,
                                EpisodeLegend* legend, std::vector<DepthScale>* depth_scales) {
  for (size_t i = 0; i < plan_.layers.size(); ++i) {
    const Layer layer = plan_.layers[i];
    if (layer == Layer::kSegmentation) {
      renderer_->RenderLayer(data, info, layer, &f->layers[i]);
      legend->Add(renderer_->segmentation_legend());
    } else {
      renderer_->RenderLayer(data, info, layer, &depth_);
      if (depth_scales->empty()) {
        *depth_scales =
            ScalesFromFrame(depth_, renderer_->width(), renderer_->height(), renderer_->tiles());
      }
      DepthToGrey(depth_, renderer_->width(), *depth_scales, f->layers[i].data());
    }
  }
}

void RecordRunner::Run(int k, WorkerChannel& channel) {
  // at most plan.encoders episodes encode at once: wait for the oldest beyond that
  while (!encoders_.empty() &&
         (encoders_.front()->finished() || static_cast<int>(encoders_.size()) >= plan_.encoders)) {
    encoders_.front()->Join();
    encoders_.pop_front();
  }
  const int worker = worker_;
  auto encoder = std::make_unique<EpisodeEncoder>(
      sink_, k, &*pool_, [&channel, worker](int episode, EpisodeResult result) {
        result.worker = worker;
        channel.Done(episode, EpisodeResultToJson(result));
      });
  renderer_->ResetTrail();
  EpisodeLegend legend;
  std::vector<DepthScale> depth_scales;
  double sim_s = 0, render_s = 0;
  // the same on the thread's CPU clock: sim, and the render thread's whole time per frame, of
  // which the renderer's own stages (scene, gl, hud, copy) are told apart by the renderer
  double sim_cpu = 0, render_cpu = 0;
  const CpuStages renderer_before = renderer_->cpu();
  // frames submitted to the renderer and not yet back, oldest first: with asynchronous
  // readback the GPU draws frame t+1 while frame t comes back
  std::deque<Frame*> in_flight;
  auto collect_oldest = [&] {
    renderer_->Collect();
    encoder->Push(in_flight.front());
    in_flight.pop_front();
    channel.Progress(1);
  };
  double look_cpu = 0;  // the look stage: the episode's look, before its first step
  const std::optional<LookDraw> look = SetEpisodeLook(k, &look_cpu);
  auto sim_start = Clock::now();
  CpuLap lap;
  auto on_step = [&](const StepRecord& record, const StepResult*) {
    const auto render_start = Clock::now();
    sim_s += std::chrono::duration<double>(render_start - sim_start).count();
    lap.Into(&sim_cpu);
    FetchEnv& env = render_env_ ? *render_env_ : sequence_.env();
    if (pixels_) pixels_->Step(env, record);
    Frame* f = pool_->Acquire();
    FrameInfo info = MakeFrameInfo(env, record);
    AddRelabelled(record.t, &info);
    if (plan_.from) info.ghost = RecordedAchieved(*plan_.from, k, record.t);  // a dataset's own
    f->t = record.t;
    f->label = SheetCaption(info);
    in_flight.push_back(f);
    // a scaled-down GIF gets its own copy of the frames it keeps, its HUD sized for its width
    renderer_->Submit(env.data(), info, f->rgb.data(),
                      NeedsGifCopy(sink_, record.t) ? f->gif_rgb.data() : nullptr,
                      gif_scale_.value_or(ShownScale{}));
    RenderLayers(env.data(), info, f, &legend, &depth_scales);
    while (renderer_->pending() >= renderer_->pipeline_depth()) collect_oldest();
    sim_start = Clock::now();
    render_s += std::chrono::duration<double>(sim_start - render_start).count();
    lap.Into(&render_cpu);
    return !channel.StopRequested();
  };
  EpisodeRecord episode;
  try {
    if (pixels_) pixels_->Begin(k);
    episode = PlayEpisode(k, on_step, channel);
    if (look) episode.look = LookJson(*look);
    if (pixels_) pixels_->End();
    const auto drain_start = Clock::now();
    lap.Into(&sim_cpu);  // the last step's
    while (!in_flight.empty()) collect_oldest();
    render_s += Since(drain_start);
    lap.Into(&render_cpu);
  } catch (...) {
    renderer_->DiscardPending();
    for (Frame* f : in_flight) pool_->Release(f);
    throw;  // aborts `encoder`
  }
  encoder->SetHindsight(HindsightCounts(episode));
  encoder->SetLayerInfo(legend.Json(k), std::move(depth_scales));
  encoder->Close(std::move(episode), sim_s, render_s,
                 EpisodeCpu(renderer_before, renderer_->cpu(), sim_cpu, render_cpu, look_cpu));
  encoders_.push_back(std::move(encoder));
}

std::optional<LookDraw> RecordRunner::SetEpisodeLook(int k, double* cpu) {
  CpuLap lap;
  const TrajectoryEpisode* recorded = nullptr;
  if (plan_.from) {
    const auto it = plan_.from->episodes.find(k);
    if (it != plan_.from->episodes.end()) recorded = &it->second;
  }
  std::vector<std::string> keys = renderer_->camera_keys();
  if (pixels_) {
    for (const std::string& key : pixels_->camera_keys()) keys.push_back(key);
  }
  const std::optional<LookDraw> look = EpisodeLook(plan_.look, plan_.look_seed.value_or(plan_.seed),
                                                   k, recorded, keys, sequence_.env().model());
  renderer_->SetLook(look ? &*look : nullptr);
  if (pixels_) pixels_->SetLook(look ? &*look : nullptr);
  lap.Into(cpu);
  return look;
}

void RecordRunner::Finish(WorkerChannel& channel) {
  (void)channel;
  while (!encoders_.empty()) {
    encoders_.front()->Join();
    encoders_.pop_front();
  }
}

// Plays episode k, calling on_step (which renders) at every step: live from the policy; or,
// for --from and the hindsight overlay, a replay of recorded actions (the recording's, or
// those of a first pass run here without rendering) with the hindsight goals sampled first.
EpisodeRecord RecordRunner::PlayEpisode(int k, const StepCallback& on_step,
                                        WorkerChannel& channel) {
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
    if (!plan_.from) {
      replay_env_ = std::make_unique<FetchEnv>(*plan_.spec, plan_.assets);
      if (plan_.contact_signals) replay_env_->EnableContactSignals();
    }
    replayer_ =
        std::make_unique<EpisodeReplayer>(plan_.from ? sequence_.env() : *replay_env_, plan_.seed);
  }
  // the replay renders from the env of sequence_ (--from) or replay_env_ (hindsight)
  render_env_ = plan_.from ? &sequence_.env() : replay_env_.get();
  EpisodeRecord episode = plan_.from ? replayer_->ReplaySource(*plan_.from, k, on_step)
                                     : replayer_->Replay(k, *script, script_complete, "", on_step);
  render_env_ = nullptr;
  return episode;
}

HindsightEpisode RecordRunner::SampleEpisodeHindsight(int k, const std::vector<StepRecord>& steps) {
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
EpisodeHindsight RecordRunner::HindsightCounts(const EpisodeRecord& episode) {
  const HindsightEpisode h =
      hindsight_ ? *hindsight_ : SampleEpisodeHindsight(episode.index, episode.steps);
  EpisodeHindsight counts;
  counts.relabelled_successes = h.relabelled_successes;
  counts.original_successes = h.original_successes;
  counts.k = kHindsightK;
  counts.transitions = static_cast<int>(episode.steps.size()) - 1;
  return counts;
}

// The hindsight overlay's goals for the frame after step t (the transition t-1 -> t).
void RecordRunner::AddRelabelled(int t, FrameInfo* info) const {
  if (!hindsight_ || t < 1 || t > static_cast<int>(hindsight_->transitions.size())) return;
  int successes = 0;
  for (const HindsightGoal& g : hindsight_->transitions[t - 1]) {
    info->relabelled.push_back({g.goal, g.success});
    successes += g.success;
  }
  info->relabelled_successes = successes;
}

ScheduleResult RecordEpisodes(const RecordPlan& plan, const ScheduleOptions& schedule) {
  LimitLlvmpipeThreads(schedule.jobs);
  return RunEpisodes(schedule,
                     [&plan](int worker) { return std::make_unique<RecordRunner>(plan, worker); });
}

void LimitLlvmpipeThreads(int jobs) {
  if (jobs > 1) setenv("LP_NUM_THREADS", "0", /*overwrite=*/0);
}

void AddCpuAccount(const std::map<std::string, double>& stages, long frames,
                   ManifestTimings* timings) {
  std::map<std::string, double> seconds;
  double outside = 0;
  for (const auto& [stage, s] : stages) {
    seconds[stage] = s;
    if (stage != "gl") outside += s;
  }
  seconds["outside_gl"] = outside;
  seconds["process"] = ProcessCpuSeconds();
  std::map<std::string, double> per_frame;
  for (const auto& [stage, s] : seconds) {
    per_frame[stage] = frames > 0 ? 1000 * s / static_cast<double>(frames) : 0.0;
  }
  timings->cpu_s = std::move(seconds);
  timings->cpu_ms_per_frame = std::move(per_frame);
}

// ---- the worker channel's JSON

nlohmann::json EpisodeResultToJson(const EpisodeResult& result) {
  const EpisodeTimings& t = result.timings;
  return {{"entry", ManifestEpisodeToJson(result.entry)},
          {"worker", result.worker},
          {"timings_s",
           {{"sim", t.sim},
            {"render", t.render},
            {"encode", t.encode},
            {"write", t.write},
            {"cpu_s", t.cpu_s}}}};
}

EpisodeResult EpisodeResultFromJson(const nlohmann::json& json) {
  EpisodeResult result;
  try {
    result.entry = ManifestEpisodeFromJson(json.at("entry"));
    result.worker = json.at("worker").get<int>();
    const nlohmann::json& t = json.at("timings_s");
    result.timings.sim = t.at("sim").get<double>();
    result.timings.render = t.at("render").get<double>();
    result.timings.encode = t.at("encode").get<double>();
    result.timings.write = t.at("write").get<double>();
    result.timings.cpu_s = t.at("cpu_s").get<std::map<std::string, double>>();
  } catch (const nlohmann::json::exception& e) {
    throw ManifestError(std::string("an episode result that is not one: ") + e.what());
  }
  return result;
}

std::map<int, EpisodeResult> RecordResults(const ScheduleResult& result) {
  std::map<int, EpisodeResult> results;
  for (const auto& [k, json] : result.results) results[k] = EpisodeResultFromJson(json);
  return results;
}

std::vector<ManifestWorker> StartedWorkers(const ScheduleResult& result) {
  std::vector<ManifestWorker> workers;
  for (size_t w = 0; w < result.workers.size(); ++w) {
    if (result.workers[w].is_null()) {
      workers.emplace_back().worker = static_cast<int>(w);
    } else {
      workers.push_back(ManifestWorkerFromJson(result.workers[w]));
    }
  }
  return workers;
}

int EncodersPerWorker(int jobs) {
  const int cores = UsableCores().usable;
  return std::max(1, cores / std::max(1, jobs));
}

}  // namespace fetchscope
