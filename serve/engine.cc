#include "serve/engine.h"

#include <algorithm>
#include <cmath>

#include "base/errors.h"
#include "base/json_util.h"
#include "encode/png_io.h"
#include "inspect/viewer.h"
#include "render/camera.h"
#include "render/frame_limits.h"
#include "render/layers.h"
#include "render/obs_view.h"
#include "run/record_command.h"
#include "serve/engine_state.h"
#include "serve/token.h"
#include "src/episode_source.h"

namespace fetchscope::serve {
namespace {

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

std::string EnvKey(const Source& s) { return s.spec->id + "|" + s.assets.root; }

// A free camera looking along a model camera (from where it stands at the env's current state),
// so that the page can orbit from a preset: lookat where its axis meets the table's height (or
// 1.5 m ahead where it looks up or level).
nlohmann::json PresetOf(const mjModel* m, const mjData* d, int cam) {
  const double* pos = d->cam_xpos + 3 * cam;
  const double* mat = d->cam_xmat + 9 * cam;
  const double f[3] = {-mat[2], -mat[5], -mat[8]};  // a MuJoCo camera looks along its -z
  const double table_z = 0.4;
  double distance = f[2] < -0.05 ? (table_z - pos[2]) / f[2] : 1.5;
  distance = std::clamp(distance, 0.3, 5.0);
  CameraSpec spec{CameraSpec::kFree, "", DefaultFreeCamera()};
  for (int k = 0; k < 3; ++k) spec.free.lookat[k] = pos[k] + distance * f[k];
  spec.free.distance = distance;
  spec.free.azimuth = std::atan2(f[1], f[0]) * 180 / M_PI;
  spec.free.elevation = std::asin(std::clamp(f[2], -1.0, 1.0)) * 180 / M_PI;
  return {{"name", mj_id2name(m, mjOBJ_CAMERA, cam)}, {"free", CameraText(spec)}};
}

}  // namespace

// ---- the engine thread

Engine::State::State(const std::vector<Source>& sources_in, const EngineOptions& options_in)
    : sources(sources_in), options(options_in) {
  gl = CreateViewContext(options.view.backend, ResolveGpuChoice(options.view));
  for (const Source& s : sources) {
    std::unique_ptr<FetchEnv>& env = envs[EnvKey(s)];
    if (!env) {
      env = std::make_unique<FetchEnv>(*s.spec, s.assets);
      env->EnableCheckpoints();
      env->EnableContactSignals();  // the plots show the fingers' forces; never changes a step
      env->Reset(s.seed);
    }
    env_of_source.push_back(env.get());
  }
  starts_resolved.assign(sources.size(), false);
}

template <class T>
T Engine::Run(std::function<T(State&)> task) {
  auto promise = std::make_shared<std::promise<T>>();
  std::future<T> result = promise->get_future();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_) throw RequestError(503, "the server is stopping");
    if (static_cast<int>(queue_.size()) >= options_.max_queued) {
      throw RequestError(503, "busy: " + std::to_string(queue_.size()) +
                                  " requests already wait for the renderer (the most --max-queued "
                                  "allows); a page keeps one in flight, so close a page or retry");
    }
    queue_.push_back([this, promise, task](bool run) {
      try {
        if (!run) throw RequestError(503, "the server is stopping");
        promise->set_value(task(*state_));
      } catch (...) {
        promise->set_exception(std::current_exception());
      }
    });
  }
  wake_.notify_one();
  return result.get();
}

Engine::Engine(std::vector<Source> sources, EngineOptions options)
    : sources_(std::move(sources)), options_(std::move(options)) {
  std::promise<void> started;
  std::future<void> ready = started.get_future();
  thread_ = std::thread([this, &started] {
    try {
      state_ = std::make_unique<State>(sources_, options_);
      cameras_json_ = nlohmann::json::array();
      for (size_t i = 0; i < sources_.size(); ++i) {
        const FetchEnv& env = *state_->env_of_source[i];
        nlohmann::json cams = nlohmann::json::array();
        for (int c = 0; c < env.model()->ncam; ++c) {
          cams.push_back(PresetOf(env.model(), env.data(), c));
        }
        cameras_json_.push_back(std::move(cams));
      }
      Warm(*state_);
      const GlInfo& i = state_->gl->info();
      gl_json_ = {{"backend", i.backend},
                  {"vendor", i.vendor},
                  {"renderer", i.renderer},
                  {"version", i.version},
                  {"device", i.device}};
      started.set_value();
    } catch (...) {
      state_.reset();
      started.set_exception(std::current_exception());
      return;
    }
    Loop();
  });
  try {
    ready.get();
  } catch (...) {
    thread_.join();
    throw;
  }
}

Engine::~Engine() {
  Stop();
  if (thread_.joinable()) thread_.join();
}

void Engine::Stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
}

void Engine::Loop() {
  while (true) {
    std::function<void(bool)> task;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
      if (stopping_) break;
      task = std::move(queue_.front());
      queue_.pop_front();
    }
    task(true);
  }
  std::deque<std::function<void(bool)>> refused;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    refused.swap(queue_);
  }
  for (auto& task : refused) task(false);
  state_.reset();  // sessions (exec: children), renderers, then the GL context
}

void Engine::Warm(State& s) {
  // the page's first view, drawn once before the first page asks: the renderer (GL buffers,
  // textures) is made and llvmpipe compiles its shaders now, not while the user waits
  FetchEnv& env = *s.env_of_source.front();
  try {
    const std::vector<CameraSpec> cameras = ParseCameraList(options_.camera_text, env.model());
    Renderer& renderer =
        s.RendererFor(env, options_.view.render.width, options_.view.render.height, cameras.size());
    renderer.SetView(cameras, options_.view.render.overlays);
    s.rgb.resize(static_cast<size_t>(renderer.width()) * renderer.height() * 3);
    TrajectoryStep reset;
    reset.obs = env.Observe();
    renderer.Render(env.data(), MakeFrameInfo(env, reset), s.rgb.data());
  } catch (const std::exception&) {
    // a view the first env cannot draw is refused when a page asks for it
  }
}

int Engine::queued() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int>(queue_.size());
}

// ---- sessions

std::string Engine::NewSession() {
  return Run<std::string>([this](State& s) {
    ExpireIdle(s);
    if (static_cast<int>(s.sessions.size()) >= options_.max_sessions) {
      throw RequestError(429, std::to_string(s.sessions.size()) +
                                  " sessions are open, the most --max-sessions allows; close a "
                                  "page, or wait until one has been idle for " +
                                  std::to_string(static_cast<int>(options_.idle_timeout_s)) + " s");
    }
    std::string id = NewToken();  // 192 random bits: another page cannot guess it
    s.sessions[id];
    return id;
  });
}

nlohmann::json Engine::CloseSession(const std::string& session) {
  return Run<nlohmann::json>([&](State& s) {
    s.Touch(session);  // 404 for a session that is not there
    s.sessions.erase(session);
    return nlohmann::json{{"closed", true}};
  });
}

int Engine::ExpireIdleSessions() {
  return Run<int>([this](State& s) {
    ExpireIdle(s);
    return static_cast<int>(s.sessions.size());
  });
}

void Engine::ExpireIdle(State& s) const {
  const auto limit = std::chrono::duration<double>(options_.idle_timeout_s);
  for (auto it = s.sessions.begin(); it != s.sessions.end();) {
    it = Clock::now() - it->second.used > limit ? s.sessions.erase(it) : std::next(it);
  }
}

Session& Engine::State::Touch(const std::string& id) {
  const auto it = sessions.find(id);
  if (it == sessions.end()) {
    throw RequestError(404,
                       "no session '" + id.substr(0, 64) +
                           "': it was never opened or has been idle too long; reload the page");
  }
  it->second.used = Clock::now();
  return it->second;
}

// ---- served episodes

namespace {

// Replays a dataset's episode `index` into `e` (its steps through `keep`, its reset seed, the
// dataset's own achieved goals as the ghost): the replay's JSON, its reset rule and divergence.
nlohmann::json ReplayDatasetEpisode(FetchEnv& env, const Source& src, int index,
                                    const StepCallback& keep, LoadedEpisode* e) {
  EpisodeReplayer replayer(env, 0);
  replayer.ReplaySource(*src.rows, index, keep);
  std::vector<Observation> replayed;
  for (const TrajectoryStep& row : e->steps) replayed.push_back(row.obs);
  const EpisodeStart& start = src.rows->starts.at(index);
  e->reset_seed = start.seed;
  for (const TrajectoryStep& row : src.rows->episodes.at(index).steps) {
    e->ghost.push_back(row.obs.achieved_goal);
  }
  return {{"reset", start.Rule()},
          {"divergence", DivergenceJson(CompareReplay(*src.rows, index, replayed))}};
}

}  // namespace

nlohmann::json Engine::State::DatasetDivergence(int source, int index) {
  const Source& src = sources[source];
  FetchEnv& env = *env_of_source[source];
  if (!starts_resolved[source]) {
    ResolveStarts(env, src.rows.get());
    starts_resolved[source] = true;
  }
  LoadedEpisode replayed;
  const auto keep = [&](const StepRecord& row, const StepResult*) {
    replayed.steps.push_back(row);
    return true;
  };
  const nlohmann::json replay = ReplayDatasetEpisode(env, src, index, keep, &replayed);
  const nlohmann::json& d = replay["divergence"];
  return {{"diverges_at", d["first_step"]},
          {"max_difference", d["max_difference"]},
          {"reset", replay["reset"]}};
}

LoadedEpisode& Engine::State::Load(int source, int index) {
  if (source < 0 || source >= static_cast<int>(sources.size())) {
    throw RequestError(404, "no source " + std::to_string(source) + "; the server has " +
                                std::to_string(sources.size()));
  }
  const Source& src = sources[source];
  if (!FindEpisode(src, index)) {
    throw RequestError(404, "source " + std::to_string(source) + " (" + src.given +
                                ") has no episode " + std::to_string(index));
  }
  const std::pair<int, int> key{source, index};
  episode_used[key] = ++tick;
  if (const auto it = episodes.find(key); it != episodes.end()) return *it->second;

  auto e = std::make_shared<LoadedEpisode>();
  e->source = source;
  e->index = index;
  FetchEnv& env = *env_of_source[source];
  const auto keep = [&](const StepRecord& row, const StepResult*) {
    e->steps.push_back(row);
    e->checkpoints.push_back(env.Checkpoint());
    return true;
  };
  nlohmann::json replay;
  try {
    if (src.kind == SourceKind::kDataset) {
      if (!starts_resolved[source]) {
        ResolveStarts(env, src.rows.get());
        starts_resolved[source] = true;
      }
      replay = ReplayDatasetEpisode(env, src, index, keep, e.get());
    } else {
      const TrajectoryEpisode recorded = EpisodeRows(src, index);
      EpisodeReplayer replayer(env, src.seed);
      replayer.ReplayEpisode(index, recorded, recorded.file.empty() ? src.given : recorded.file,
                             keep);
      e->reset_seed = src.seed;
      e->placed = recorded.placed;
      e->look = recorded.look;
      replay = {{"reset", recorded.placed ? "placed"
                          : index == 0    ? "seed"
                                          : "continued generator"},
                {"exact", true}};
      std::vector<std::array<double, 3>> achieved;
      for (const TrajectoryStep& row : e->steps) achieved.push_back(row.obs.achieved_goal);
      e->hindsight = SampleHindsight(
          achieved, e->steps.front().obs.desired_goal, HindsightSeed(src.seed, index), kHindsightK,
          [&env](const auto& a, const auto& g) { return env.ComputeReward(a, g); },
          [&env](const auto& a, const auto& g) { return env.IsSuccess(a, g); });
    }
  } catch (const ReplayMismatch& m) {
    throw RequestError(409, m.what());
  } catch (const RunError& m) {
    throw RequestError(500, m.what());
  }
  e->float32 = e->steps.size() > 1 && e->steps[1].action && e->steps[1].action->is_float32;
  const bool hindsight = src.kind == SourceKind::kRecording;
  e->data =
      RowsData(*src.spec, e->steps,
               hindsight ? std::optional<uint64_t>(HindsightSeed(src.seed, index)) : std::nullopt);
  e->data["source"] = source;
  e->data["episode"] = index;
  e->data["replay"] = replay;
  if (replay.contains("divergence")) {
    e->data["signals"]["replay_error"] = replay["divergence"]["position_error_mm"];
  }
  e->data["action_dtype"] = e->float32 ? "float32" : "float64";
  // keep options.episode_cache episodes: the least recently used goes
  episodes[key] = e;
  while (static_cast<int>(episodes.size()) > options.episode_cache) {
    auto oldest = episodes.begin();
    for (auto it = episodes.begin(); it != episodes.end(); ++it) {
      if (episode_used[it->first] < episode_used[oldest->first]) oldest = it;
    }
    episode_used.erase(oldest->first);
    episodes.erase(oldest);
  }
  return *e;
}

nlohmann::json Engine::Episode(const std::string& session, const StepRef& at) {
  return Run<nlohmann::json>([&](State& s) {
    s.Touch(session);
    return s.Load(at.source, at.episode).data;
  });
}

StepState Engine::State::Resolve(Session& session, const StepRef& at) {
  StepState state;
  const std::vector<TrajectoryStep>* steps = nullptr;
  const std::vector<EnvCheckpoint>* checkpoints = nullptr;
  if (at.source == kLiveSource) {
    if (!session.live) {
      throw RequestError(404, "this session has no live episode: start one first");
    }
    const LiveEpisode& live = *session.live;
    state.env = env_of_source[live.source];
    state.look = &live.look;
    state.seed = sources[live.source].seed;
    state.episode = live.index;
    steps = &live.steps;
    checkpoints = &live.checkpoints;
  } else {
    const LoadedEpisode& e = Load(at.source, at.episode);
    state.env = env_of_source[at.source];
    state.look = &e.look;
    state.seed = sources[at.source].seed;
    state.episode = at.episode;
    steps = &e.steps;
    checkpoints = &e.checkpoints;
    if (at.step < static_cast<int>(e.ghost.size())) state.ghost = &e.ghost[at.step];
    if (e.hindsight && at.step >= 1 &&
        at.step <= static_cast<int>(e.hindsight->transitions.size())) {
      state.relabelled = &e.hindsight->transitions[at.step - 1];
    }
  }
  if (at.step >= static_cast<int>(steps->size())) {
    throw RequestError(404, "step " + std::to_string(at.step) +
                                " is past the episode's end: it has " +
                                std::to_string(steps->size() - 1) + " steps");
  }
  state.row = &(*steps)[at.step];
  state.checkpoint = &(*checkpoints)[at.step];
  for (int t = 0; t < at.step; ++t) state.trail.push_back((*steps)[t].obs.achieved_goal);
  return state;
}

// ---- frames

Renderer& Engine::State::RendererFor(FetchEnv& env, int width, int height, size_t views) {
  for (RendererSlot& slot : renderers) {
    if (slot.env == &env && slot.width == width && slot.height == height && slot.views == views) {
      slot.used = ++tick;
      return *slot.renderer;
    }
  }
  constexpr size_t kKept = 2;  // a renderer holds a frame's GL buffers: keep the two last sizes
  if (renderers.size() >= kKept) {
    auto oldest = std::min_element(renderers.begin(), renderers.end(),
                                   [](const auto& a, const auto& b) { return a.used < b.used; });
    gl->MakeCurrent();
    renderers.erase(oldest);
  }
  RenderOptions o = options.view.render;
  o.width = width;
  o.height = height;
  o.cameras.assign(views, CameraSpec{CameraSpec::kDefault, "default", DefaultFreeCamera()});
  const FrameDims frame = FrameSize(o);
  if (static_cast<int64_t>(frame.width) * frame.height > kMaxFramePixels) {
    throw RequestError(413, "a frame of " + std::to_string(views) + " views of " +
                                std::to_string(width) + "x" + std::to_string(height) + " is " +
                                std::to_string(frame.width) + "x" + std::to_string(frame.height) +
                                ", over render's limit of " + std::to_string(kMaxFramePixels) +
                                " pixels");
  }
  RendererSlot slot;
  slot.env = &env;
  slot.width = width;
  slot.height = height;
  slot.views = views;
  slot.used = ++tick;
  try {
    slot.renderer = std::make_unique<Renderer>(*gl, env.model(), o);
  } catch (const UsageError& e) {
    throw RequestError(413, e.what());
  }
  renderers.push_back(std::move(slot));
  return *renderers.back().renderer;
}

std::optional<LookDraw> Engine::State::ViewLook(const ViewRequest& view, const StepState& state,
                                                const std::vector<std::string>& keys) const {
  const bool stored = state.look && state.look->is_object();
  if (view.look == "plain" || (view.look == "recorded" && !stored)) return std::nullopt;
  const mjModel* model = state.env->model();
  std::optional<LookDraw> own;  // the stored look; a run folder's that is not one: 409, one line
  if (stored) {
    try {
      own = ParseLookJson(*state.look, "the episode's look");
    } catch (const UsageError& e) {
      throw RequestError(409, e.what());
    }
  }
  if (view.look.empty() || view.look == "recorded") {
    if (own) return own;
    if (!options.look || !options.look->any()) return std::nullopt;
    return DrawLook(*options.look, LookSeed(options.look_seed.value_or(state.seed), state.episode),
                    keys, model);
  }
  // another draw: of serve's --randomize kinds, else the stored look's kinds, else all four
  LookConfig config = options.look.value_or(LookConfig{});
  if (!config.any() && own) {
    config.colors = own->colors;
    config.textures = own->textures;
    config.lighting = own->lighting;
    config.camera = own->camera;
  }
  if (!config.any()) config.colors = config.textures = config.lighting = config.camera = true;
  return DrawLook(config, LookSeed(std::stoull(view.look), state.episode), keys, model);
}

void Engine::State::SetViewLook(const ViewRequest& view, const StepState& state, Renderer& renderer,
                                std::string* look_text) {
  const std::optional<LookDraw> look = ViewLook(view, state, renderer.camera_keys());
  renderer.SetLook(look ? &*look : nullptr);
  if (look_text) *look_text = look ? LookJson(*look).dump() : "";
}

Renderer& Engine::State::Prepare(const ViewRequest& view, const StepState& state, FrameInfo* info,
                                 std::string* camera_text, std::string* look_text) {
  FetchEnv& env = *state.env;
  std::vector<CameraSpec> cameras;
  try {
    cameras = ParseCameraList(view.camera, env.model());
  } catch (const UsageError& e) {
    throw RequestError(400, std::string("parameter camera: ") + e.what());
  }
  Renderer& renderer = RendererFor(env, view.width, view.height, cameras.size());
  renderer.SetView(cameras, view.overlays);
  SetViewLook(view, state, renderer, look_text);
  renderer.SetTrail(state.trail);
  env.Restore(*state.checkpoint);
  *info = MakeFrameInfo(env, *state.row);
  if (state.ghost) info->ghost = *state.ghost;
  if (state.relabelled) {
    int successes = 0;
    for (const HindsightGoal& g : *state.relabelled) {
      info->relabelled.push_back({g.goal, g.success});
      successes += g.success;
    }
    info->relabelled_successes = successes;
  }
  camera_text->clear();
  for (const CameraSpec& c : cameras) {
    *camera_text += (camera_text->empty() ? "" : ",") + CameraText(c);
  }
  return renderer;
}

Frame Engine::RenderFrame(const std::string& session, const ViewRequest& r) {
  return Run<Frame>([&](State& s) {
    Session& ses = s.Touch(session);
    const StepState state = s.Resolve(ses, r.at);
    Frame frame;
    const auto start = Clock::now();
    FrameInfo info;
    Renderer& renderer = s.Prepare(r, state, &info, &frame.camera, &frame.look);
    const int w = renderer.width(), h = renderer.height();
    s.rgb.resize(static_cast<size_t>(w) * h * 3);
    const mjData* data = state.env->data();
    if (r.layer == Layer::kRgb) {
      renderer.Render(data, info, s.rgb.data());
    } else if (r.layer == Layer::kDepth) {
      renderer.RenderLayer(data, info, Layer::kDepth, &s.layer);
      DepthToGrey(s.layer, w, ScalesFromFrame(s.layer, w, h, renderer.tiles()), s.rgb.data());
    } else {
      renderer.RenderLayer(data, info, Layer::kSegmentation, &s.rgb);
    }
    frame.render_ms = MsSince(start);
    const auto encode_start = Clock::now();
    if (r.format == ImageFormat::kPng) {
      frame.bytes = EncodePng(w, h, 3, 8, s.rgb.data(), /*fast=*/true);
      frame.content_type = "image/png";
    } else {
      frame.bytes = s.jpeg.Encode(s.rgb.data(), w, h, r.quality);
      frame.content_type = "image/jpeg";
    }
    frame.encode_ms = MsSince(encode_start);
    return frame;
  });
}

nlohmann::json Engine::PageData() const {
  nlohmann::json sources = SourcesJson(sources_);
  for (size_t i = 0; i < sources.size(); ++i) sources[i]["cameras"] = cameras_json_[i];
  return {{"sources", sources},
          {"view",
           {{"camera", options_.camera_text},
            {"overlay", options_.overlay_text},
            {"width", options_.view.render.width},
            {"height", options_.view.render.height}}},
          {"policy", options_.policy.text},
          {"gl", gl_json_},
          {"limits",
           {{"max_sessions", options_.max_sessions},
            {"max_queued", options_.max_queued},
            {"idle_timeout_s", options_.idle_timeout_s},
            {"max_live_steps", options_.max_live_steps}}}};
}

}  // namespace fetchscope::serve
