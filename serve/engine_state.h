// What serve's engine thread owns (serve/engine.h): private to serve/engine*.cc and live.cc.
#pragma once

#include <array>
#include <chrono>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "encode/jpeg.h"
#include "render/gl_context.h"
#include "render/renderer.h"
#include "run/pixel_recorder.h"
#include "serve/engine.h"
#include "src/fetch_env.h"
#include "src/hindsight.h"
#include "src/policy.h"
#include "src/trajectory.h"

namespace fetchscope::serve {

using Clock = std::chrono::steady_clock;

/// A served episode once replayed: every step's row and checkpoint, and the page's data.
struct LoadedEpisode {
  int source = 0;
  int index = 0;
  std::vector<TrajectoryStep> steps;          ///< as replayed (a recording: as recorded)
  std::vector<EnvCheckpoint> checkpoints;     ///< the env after each step
  std::vector<std::array<double, 3>> ghost;   ///< a dataset's own achieved goal per row
  std::optional<HindsightEpisode> hindsight;  ///< a recording's relabelling (the overlay)
  std::optional<uint64_t> reset_seed;         ///< the seed record --seed reproduces it with
  std::optional<PlacedReset> placed;          ///< a recording's reset placed by hand
  nlohmann::json look;                        ///< a recording's stored look (null: none)
  bool float32 = false;                       ///< its actions' dtype
  nlohmann::json data;                        ///< Engine::Episode's answer
};

/// A page's live episode: from a live env's reset, or continued from a served step.
struct LiveEpisode {
  int source = 0;                          ///< the source it started from
  int index = 0;                           ///< the episode's index (a live env's: 0)
  int prefix = 0;                          ///< its first steps that came from the served episode
  std::optional<uint64_t> reset_seed;      ///< the record --seed that reproduces its reset
  std::optional<PlacedReset> placed;       ///< its reset placed by hand (saved; record --from)
  nlohmann::json look;                     ///< the look it continues (saved); null: none
  bool float32 = false;                    ///< the dtype of every action it takes
  std::vector<TrajectoryStep> steps;       ///< t = 0 .. n
  std::vector<EnvCheckpoint> checkpoints;  ///< the env after each step
  std::unique_ptr<Policy> policy;          ///< the command line's, made when first asked
  int policy_from = 0;                     ///< the step the policy began at
};

/// One page's session.
struct Session {
  std::optional<LiveEpisode> live;
  Clock::time_point used = Clock::now();
  int saves = 0;
};

/// A renderer for one env, frame size and number of views.
struct RendererSlot {
  const FetchEnv* env = nullptr;
  int width = 0, height = 0;
  size_t views = 0;
  std::unique_ptr<Renderer> renderer;
  uint64_t used = 0;
};

/// Where a request's step is: the env to restore and what the frame shows there.
struct StepState {
  FetchEnv* env = nullptr;
  const EnvCheckpoint* checkpoint = nullptr;
  const TrajectoryStep* row = nullptr;
  std::vector<std::array<double, 3>> trail;  ///< achieved goals of the steps before
  const std::array<double, 3>* ghost = nullptr;
  const std::vector<HindsightGoal>* relabelled = nullptr;
  const nlohmann::json* look = nullptr;  ///< the episode's stored look, if any
  uint64_t seed = 0;                     ///< its source's seed (serve's --randomize draws)
  int episode = 0;                       ///< its index
};

/// The images an exec: policy sees on one env (--obs-camera): the plan and its renderer.
struct PolicyImages {
  PixelPlan plan;
  std::optional<PixelRecorder> recorder;
};

/// Everything the engine thread owns. Member order is lifetime order: the GL context outlives the
/// renderers; sessions (and their exec: children) go first.
struct Engine::State {
  State(const std::vector<Source>& sources, const EngineOptions& options);

  const std::vector<Source>& sources;
  const EngineOptions& options;
  std::unique_ptr<GlContext> gl;
  std::map<std::string, std::unique_ptr<FetchEnv>> envs;  // by env id and assets root
  std::vector<FetchEnv*> env_of_source;
  std::vector<bool> starts_resolved;  // per source: a dataset's ResolveStarts has run
  std::vector<RendererSlot> renderers;
  std::map<const FetchEnv*, std::unique_ptr<PolicyImages>> policy_images;  // made when first asked
  std::map<std::pair<int, int>, std::shared_ptr<LoadedEpisode>> episodes;  // (source, index)
  std::map<std::pair<int, int>, uint64_t> episode_used;
  std::map<int, nlohmann::json> listings;  // per source, once asked
  JpegEncoder jpeg;
  std::vector<uint8_t> rgb, layer;  // frame buffers, reused
  uint64_t tick = 0;
  std::map<std::string, Session> sessions;

  /// The session `id`, marked used now. RequestError(404) when there is none (expired).
  Session& Touch(const std::string& id);
  /// The episode, replayed (and kept) when first asked. RequestError 404 for no such source or
  /// episode, 409 when the replay differs from the recording.
  LoadedEpisode& Load(int source, int index);
  /// Where `at` is: a served step, or (kLiveSource) the session's live episode's.
  StepState Resolve(Session& session, const StepRef& at);
  /// A renderer for `env` of `views` views of width x height, with the command line's options
  /// (made, or the least recently used of two replaced).
  Renderer& RendererFor(FetchEnv& env, int width, int height, size_t views);
  /// The renderer for `view` on `state`'s env, its cameras and overlays set, `state` restored,
  /// and the frame info of that step: what RenderFrame and Pick draw.
  Renderer& Prepare(const ViewRequest& view, const StepState& state, FrameInfo* info,
                    std::string* camera_text, std::string* look_text = nullptr);
  /// The look `view` asks for on `state` (ViewRequest::look), set on `renderer`; its LookJson
  /// (compact) into `look_text` where given, "" for the plain look.
  void SetViewLook(const ViewRequest& view, const StepState& state, Renderer& renderer,
                   std::string* look_text);
  /// The look `view` asks for on `state` for the views `camera_keys`; nullopt: plain.
  std::optional<LookDraw> ViewLook(const ViewRequest& view, const StepState& state,
                                   const std::vector<std::string>& camera_keys) const;
  /// The images of --obs-camera drawn on `env` as it stands at `row` (the live episode's last
  /// step): what an exec: policy receives with its line.
  PixelRecorder& DrawPolicyImages(FetchEnv& env, const TrajectoryStep& row);
  /// A dataset episode's replay against its own rows, for the episode browser: {"diverges_at"
  /// (the first step beyond the tolerance, or null), "max_difference", "reset" (its rule)}.
  nlohmann::json DatasetDivergence(int source, int index);
  /// The live episode's data for the page, whole (rows and signals).
  nlohmann::json LiveData(const LiveEpisode& live) const;
  /// What describes the live episode without its rows: source, episode, steps, dtype, ...
  nlohmann::json LiveHead(const LiveEpisode& live) const;
};

/// The page's data of an episode's rows: {"steps", "rows", "signals", ...} (inspect/viewer.h).
nlohmann::json RowsData(const EnvSpec& spec, const std::vector<TrajectoryStep>& steps,
                        const std::optional<uint64_t>& hindsight_seed);

/// One row as the page's step inspector shows it: t, the observation, both goals, the action,
/// the reward, success and the contacts (where recorded), each as the trajectory JSON has it.
nlohmann::json RowJson(const TrajectoryStep& row);

/// The signals of the last of `steps` alone (EpisodeSignals of the last two, each list's last
/// value): what a live step's answer carries.
nlohmann::json LastStepSignals(const EnvSpec& spec, const std::vector<TrajectoryStep>& steps);

}  // namespace fetchscope::serve
