// serve's engine: one thread that owns the GL context, the environments, the renderers, the
// replayed episodes and the pages' sessions, and runs every request that simulates or renders,
// one at a time, in the order they came. Requests queue for it (at most max_queued waiting: a
// page keeps one frame request in flight and sends the latest view when it returns, so a full
// queue means too many pages, answered 503). Every frame comes from the renderer record uses, on
// the exact state the environment held at that step (EnvCheckpoint), so a frame at a recorded
// camera and size is the frame render gives for that state.
#pragma once

#include <chrono>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "render/look.h"
#include "render/obs_view.h"
#include "render/view.h"
#include "serve/api.h"
#include "serve/request.h"
#include "serve/sources.h"
#include "src/policy_spec.h"

namespace fetchscope {
class FetchEnv;
}

namespace fetchscope::serve {

struct LiveEpisode;

/// How the engine runs: the command line's view, policy and limits.
struct EngineOptions {
  ViewSetup view;  ///< backend, GPU, msaa, HUD, readback; the page's first view
  std::string camera_text = "default";   ///< --camera as given: the page's first camera
  std::string overlay_text = "default";  ///< --overlay as given: the page's first overlays
  PolicySpec policy;                     ///< what "step the policy" plays (--policy)
  /// --obs-camera with an exec: policy: the images each of its lines carries (none: no images)
  ObsSetup policy_images;
  std::filesystem::path save_dir = "serve-sessions";  ///< where a saved session goes
  std::string assets_flag;      ///< the --assets a saved session's record command needs ("" none)
  int max_sessions = 8;         ///< pages with a session at once
  int max_queued = 16;          ///< requests waiting for the engine at once
  double idle_timeout_s = 600;  ///< a session unused this long is freed
  int episode_cache = 8;        ///< replayed episodes kept (their checkpoints and data)
  int max_live_steps = 10000;   ///< steps a live episode may take
  /// --randomize: the look of every episode without a stored one, and the kinds a page's
  /// redraw (look=N) draws; nullopt: not given
  std::optional<LookConfig> look;
  std::optional<uint64_t> look_seed;  ///< --look-seed: serve's draws from it, not the source's seed
};

class Engine : public Api {
 public:
  /// Starts the engine's thread, which makes the GL context (view.backend, view.gpu) and an
  /// environment per distinct env of `sources`. Throws what that throws (no GL: RunError).
  Engine(std::vector<Source> sources, EngineOptions options);
  /// Stops the thread: what is queued is refused (503), exec: children are ended.
  ~Engine();
  /// Refuses every request from now on (503), the queued ones at once; the one running finishes.
  /// The thread ends without waiting for it (the destructor joins it). For a prompt shutdown.
  void Stop();
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;

  const std::vector<Source>& sources() const { return sources_; }
  const EngineOptions& options() const { return options_; }
  /// GL vendor, renderer and backend, for the page and bench.
  nlohmann::json GlJson() const { return gl_json_; }

  /// What the page shows before any request: the sources, the view options, each env's cameras
  /// (names, and a free camera looking along each, for orbiting from it), the policy, the limits.
  nlohmann::json PageData() const override;

  /// A new session for a page (at most max_sessions; idle ones are freed first). Its id.
  std::string NewSession() override;
  /// Frees `session` (its live episode and exec: child): {"closed": true}. 404 for none.
  nlohmann::json CloseSession(const std::string& session) override;
  /// The live episode whole: {"steps", "rows", "signals", ...} as StartLive answers.
  nlohmann::json LiveState(const std::string& session) override;
  /// The frame of `request`'s view at its step (the session's live episode for source "live").
  Frame RenderFrame(const std::string& session, const ViewRequest& request) override;
  /// What is at a pixel of a view: {"body", "geom", "site", "color"} or {"body": null}.
  nlohmann::json Pick(const std::string& session, const PickRequest& request) override;
  /// A served episode's data for the viewer: steps, signals (inspect/viewer.h's EpisodeSignals),
  /// its replay (exact, or a dataset's divergence) and the dtype of its actions.
  nlohmann::json Episode(const std::string& session, const StepRef& episode) override;
  /// Every episode's browser columns, worked out once per source (a run folder's files are read
  /// then, after the page's first frame) and kept.
  nlohmann::json Listing(const std::string& session, int source) override;
  /// The session's live episode: started from a live env's reset or a served step, stepped by an
  /// action or the policy, one step back, saved (a replay trajectory and the record command that
  /// re-renders it). Start (and Save) return the live episode's data ({"steps", "rows",
  /// "signals", ...}; Save adds {"files", "command"}); a step returns the new step alone
  /// ({"steps", "step": {"row", "signals"}, ...}, the same size at step 2,000 as at step 10),
  /// a step back the new count ({"steps", ...}): the page keeps the rest.
  nlohmann::json StartLive(const std::string& session, const StartRequest& request) override;
  nlohmann::json StepLive(const std::string& session, const StepRequest& request) override;
  nlohmann::json BackLive(const std::string& session) override;
  nlohmann::json SaveLive(const std::string& session, const ViewRequest& view) override;
  /// Frees sessions idle for longer than idle_timeout_s; how many are open.
  int ExpireIdleSessions();

  /// Requests that wait for the engine now (for tests and bench).
  int queued() const;

 private:
  struct State;  // everything the engine thread owns
  // Runs `task` on the engine's thread and returns its result (or rethrows what it threw);
  // RequestError(503) when max_queued requests already wait, or when stopping.
  template <class T>
  T Run(std::function<T(State&)> task);
  void Loop();
  // Draws the first view once, at start (the renderer made, llvmpipe's shaders compiled).
  void Warm(State& state);
  // Frees the sessions idle for longer than idle_timeout_s (on the engine thread).
  void ExpireIdle(State& state) const;
  // The command line's policy's action at the live episode's last step (env restored there),
  // made when first asked; with --obs-camera its images are drawn first. RequestError(502)
  // when the policy fails.
  Action PolicyAction(State& state, LiveEpisode& live, FetchEnv& env);

  std::vector<Source> sources_;
  EngineOptions options_;
  nlohmann::json gl_json_;
  nlohmann::json cameras_json_;  // per source: its env's cameras (made on the engine thread)
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void(bool)>> queue_;  // each runs (true) or is refused (false)
  bool stopping_ = false;
  std::unique_ptr<State> state_;
  std::thread thread_;
};

}  // namespace fetchscope::serve
