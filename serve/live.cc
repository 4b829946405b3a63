// serve's live episodes (serve/engine.h): started from a live env's reset or a served step,
// stepped by the page's keys or the command line's policy, stepped back, and saved as a replay
// trajectory with the record command that re-renders it.
#include <mujoco/mujoco.h>
#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numeric>

#include "base/atomic_file.h"
#include "base/errors.h"
#include "base/process.h"
#include "base/stop_signal.h"
#include "serve/engine_state.h"
#include "src/observation_layout.h"
#include "src/policy.h"

namespace fetchscope::serve {
namespace {

namespace fs = std::filesystem;

// A number as the CSV replay reads it back exactly: shortest round-trip text.
std::string RoundTrip(double v) {
  char text[40];
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(text, sizeof(text), "%.*g", digits, v);
    if (std::strtod(text, nullptr) == v) break;
  }
  return text;
}

TrajectoryStep RowAfterStep(const FetchEnv& env, const StepResult& r, const Action& action, int t) {
  TrajectoryStep row;
  row.t = t;
  row.obs = r.obs;
  row.action = action;
  row.reward = r.reward;
  row.is_success = r.is_success;
  row.past_time_limit = t > env.spec().max_episode_steps;
  row.contacts = env.Contacts();
  return row;
}

// The record command that re-renders a saved live episode: `replay` (its env, seed, replay and
// steps, or --from the saved trajectory), its assets (given when the command line gave --assets
// or they are not the bundled ones; --from reads them from the trajectory), and the view the page
// showed.
std::string RecordCommand(std::vector<std::string> replay, bool assets_given,
                          const AssetSource& assets, const ViewRequest& view, const fs::path& out) {
  std::vector<std::string> argv = {SelfCommand(), "record"};
  argv.insert(argv.end(), replay.begin(), replay.end());
  argv.insert(argv.end(), {"--signals", "contacts"});  // its trajectory has them
  if (replay[0] != "--from" && (assets_given || assets.kind != "bundled")) {
    argv.push_back("--assets");
    argv.push_back(assets.kind == "bundled" ? "bundled" : assets.root);
  }
  argv.insert(argv.end(), {"--camera", view.camera, "--overlay", view.overlay_text, "--width",
                           std::to_string(view.width), "--height", std::to_string(view.height),
                           "--out", out.string()});
  std::string command;
  for (const std::string& arg : argv) command += (command.empty() ? "" : " ") + ShellQuote(arg);
  return command;
}

// A reset placed by hand (StartRequest goal, object) on `env`, whose seeded reset gave `reset`:
// the goal given or drawn, the object (object tasks) at the x, y given, at the z given or the
// reset's, turned as the reset left it. A point off the table's top (x, y) or below it, or more
// than 0.6 m above it, is refused in one line naming it and the range accepted.
PlacedReset PlaceReset(const FetchEnv& env, const Observation& reset, const StartRequest& r) {
  const mjModel* m = env.model();
  const int body = mj_name2id(m, mjOBJ_BODY, "table0");
  if (body < 0 || m->body_geomnum[body] < 1) {
    throw RequestError(400, "this model has no table0 body to place things on");
  }
  const int table = m->body_geomadr[body];  // its box (the world body's child: world frame)
  double centre[3];
  for (int i = 0; i < 3; ++i) centre[i] = m->body_pos[3 * body + i] + m->geom_pos[3 * table + i];
  const double* half = m->geom_size + 3 * table;
  const double low[3] = {centre[0] - half[0], centre[1] - half[1], centre[2] + half[2]};
  const double high[3] = {centre[0] + half[0], centre[1] + half[1], centre[2] + half[2] + 0.6};
  const auto check = [&](const char* what, const std::vector<double>& v) {
    for (size_t i = 0; i < v.size(); ++i) {
      if (v[i] < low[i] || v[i] > high[i]) {
        char range[96];
        std::snprintf(range, sizeof(range), "%.3f..%.3f", low[i], high[i]);
        throw RequestError(400, std::string("parameter ") + what + ": " + "xyz"[i] + " = " +
                                    RoundTrip(v[i]) + " is off the table; accepted: " + range +
                                    (i == 2 ? " m (its top to 0.6 m above)" : " m (its top)"));
      }
    }
  };
  PlacedReset placed;
  placed.goal = r.goal.value_or(reset.desired_goal);
  check("goal", {placed.goal.begin(), placed.goal.end()});
  if (!r.object.empty()) {
    if (!env.spec().has_object) {
      throw RequestError(
          400, "parameter object: " + env.spec().id + " has no object; place its goal alone");
    }
    check("object", r.object);
  }
  if (env.spec().has_object) {
    const int position = FindObservationSlice(true, "object_pos")->first;
    const int euler = FindObservationSlice(true, "object_rot")->first;
    ObjectPose pose;
    for (int i = 0; i < 3; ++i) {
      pose.position[i] =
          i < static_cast<int>(r.object.size()) ? r.object[i] : reset.observation[position + i];
      pose.euler[i] = reset.observation[euler + i];
    }
    placed.object = pose;
  }
  return placed;
}

// The first session_NNN in `dir` with no .json, .csv or folder of that name.
std::string FreeSessionName(const fs::path& dir) {
  for (int n = 1; n < 100000; ++n) {
    char text[32];
    std::snprintf(text, sizeof(text), "session_%03d", n);
    if (!fs::exists(dir / (std::string(text) + ".json")) &&
        !fs::exists(dir / (std::string(text) + ".csv")) && !fs::exists(dir / text)) {
      return text;
    }
  }
  throw RequestError(500, "cannot save the session: " + dir.string() + " holds 99999 of them");
}

// A saved live episode's trajectory, as record writes the episode it re-renders: the same
// writer, env, seed, policy text and assets, so that the two files are the same bytes.
Trajectory SavedTrajectory(const EnvSpec& spec, const FetchEnv& env, const LiveEpisode& live,
                           const fs::path& json_path, const nlohmann::json& look) {
  Trajectory trajectory;
  trajectory.env_id = spec.id;
  trajectory.seed = live.reset_seed.value_or(0);
  trajectory.policy = "replay:" + json_path.string();
  trajectory.assets = env.assets();
  TrajectoryEpisode episode;
  episode.index = live.index;
  episode.steps = live.steps;
  episode.episode_return = 0;
  for (const TrajectoryStep& row : live.steps) {
    if (row.reward) episode.episode_return += *row.reward;
  }
  episode.placed = live.placed;
  episode.look = look;
  trajectory.episodes = {episode};
  return trajectory;
}

// The actions of steps 1.. as CSV rows that read back exactly.
std::string ActionsCsv(const std::vector<TrajectoryStep>& steps) {
  std::string csv;
  for (size_t t = 1; t < steps.size(); ++t) {
    const Action& a = *steps[t].action;
    for (int i = 0; i < 4; ++i) csv += (i ? "," : "") + RoundTrip(a.value[i]);
    csv += "\n";
  }
  return csv;
}

}  // namespace

nlohmann::json Engine::State::LiveHead(const LiveEpisode& live) const {
  const Source& src = sources[live.source];
  return {{"env_id", src.spec->id},
          {"steps", static_cast<int>(live.steps.size()) - 1},
          {"source", live.source},
          {"episode", live.index},
          {"prefix", live.prefix},
          {"placed", live.placed.has_value()},
          {"action_dtype", live.float32 ? "float32" : "float64"},
          {"can_save", live.reset_seed.has_value() && live.steps.size() > 1},
          {"policy", options.policy.text}};
}

nlohmann::json Engine::State::LiveData(const LiveEpisode& live) const {
  nlohmann::json data = RowsData(*sources[live.source].spec, live.steps, std::nullopt);
  data.update(LiveHead(live));
  return data;
}

nlohmann::json Engine::LiveState(const std::string& session) {
  return Run<nlohmann::json>([&](State& s) {
    Session& ses = s.Touch(session);
    if (!ses.live) throw RequestError(409, "this session has no live episode: start one first");
    return s.LiveData(*ses.live);
  });
}

nlohmann::json Engine::StartLive(const std::string& session, const StartRequest& r) {
  return Run<nlohmann::json>([&](State& s) {
    Session& ses = s.Touch(session);
    LiveEpisode live;
    if (r.env) {
      const int source = *r.env;
      if (source >= static_cast<int>(sources_.size()) ||
          sources_[source].kind != SourceKind::kLive) {
        throw RequestError(404, "no live env " + std::to_string(source) +
                                    ": start one with serve --env-id ID --seed S");
      }
      const Source& src = sources_[source];
      FetchEnv& env = *s.env_of_source[source];
      TrajectoryStep row;
      row.obs = env.Reset(src.seed);
      if (r.goal || !r.object.empty()) {  // the seed's reset, then the goal and object placed
        live.placed = PlaceReset(env, row.obs, r);
        row.obs = env.ResetTo(live.placed->goal, live.placed->object);
      }
      row.is_success = env.IsSuccess(row.obs.achieved_goal, row.obs.desired_goal);
      row.contacts = env.Contacts();
      live.source = source;
      live.reset_seed = src.seed;
      live.float32 = std::holds_alternative<policy_spec::Random>(options_.policy.value) ||
                     options_.policy.replay_dtype() == "float32";
      live.steps.push_back(row);
      live.checkpoints.push_back(env.Checkpoint());
    } else {
      const LoadedEpisode& e = s.Load(r.from.source, r.from.episode);
      if (r.from.step >= static_cast<int>(e.steps.size())) {
        throw RequestError(404, "step " + std::to_string(r.from.step) +
                                    " is past the episode's end: it has " +
                                    std::to_string(e.steps.size() - 1) + " steps");
      }
      live.source = r.from.source;
      live.index = r.from.episode;
      live.prefix = r.from.step;
      live.reset_seed = e.reset_seed;
      live.placed = e.placed;
      live.look = e.look;
      live.float32 = e.float32;
      live.steps.assign(e.steps.begin(), e.steps.begin() + r.from.step + 1);
      live.checkpoints.assign(e.checkpoints.begin(), e.checkpoints.begin() + r.from.step + 1);
    }
    ses.live = std::move(live);
    return s.LiveData(*ses.live);
  });
}

nlohmann::json Engine::StepLive(const std::string& session, const StepRequest& r) {
  return Run<nlohmann::json>([&](State& s) {
    Session& ses = s.Touch(session);
    if (!ses.live) throw RequestError(409, "this session has no live episode: start one first");
    LiveEpisode& live = *ses.live;
    const int t = static_cast<int>(live.steps.size());
    if (t > options_.max_live_steps) {
      throw RequestError(409, "the live episode has " + std::to_string(t - 1) +
                                  " steps, the most it may take (" +
                                  std::to_string(options_.max_live_steps) + ")");
    }
    FetchEnv& env = *s.env_of_source[live.source];
    env.Restore(live.checkpoints.back());
    Action action;
    if (r.action) {
      action.value = *r.action;
    } else {
      action = PolicyAction(s, live, env);
    }
    if (live.float32) {
      for (double& v : action.value) v = static_cast<float>(v);
    }
    action.is_float32 = live.float32;
    const StepResult result = env.Step(action);
    live.steps.push_back(RowAfterStep(env, result, action, t));
    live.checkpoints.push_back(env.Checkpoint());
    nlohmann::json out = s.LiveHead(live);
    out["step"] = {{"row", RowJson(live.steps.back())},
                   {"signals", LastStepSignals(env.spec(), live.steps)}};
    return out;
  });
}

PixelRecorder& Engine::State::DrawPolicyImages(FetchEnv& env, const TrajectoryStep& row) {
  std::unique_ptr<PolicyImages>& images = policy_images[&env];
  gl->MakeCurrent();
  if (!images) {
    images = std::make_unique<PolicyImages>();
    images->plan.setup = options.policy_images;
    images->plan.layout = MakePixelLayout(options.policy_images, env.model());
    images->recorder.emplace(images->plan, gl.get(), env.model());
  }
  images->recorder->Step(env, row);
  return *images->recorder;
}

Action Engine::PolicyAction(State& s, LiveEpisode& live, FetchEnv& env) {
  const int t = static_cast<int>(live.steps.size()) - 1;  // the step it acts at
  try {
    PixelRecorder* images = nullptr;
    if (options_.policy_images.enabled()) images = &s.DrawPolicyImages(env, live.steps.back());
    if (!live.policy) {
      PolicyContext context;
      context.seed = live.reset_seed.value_or(sources_[live.source].seed);
      context.steps_per_episode = std::max(env.spec().max_episode_steps, t + 2);
      context.episodes = live.index + 1;
      context.stop_requested = [] { return StopSignal() != 0; };
      if (images) context.images = [images](int) { return images->wire(); };
      live.policy = MakePolicy(options_.policy, env.spec(), context);
      live.policy->BeginEpisode(live.index, live.steps.back().obs);
      live.policy_from = t;
    }
    return live.policy->Act(live.steps.back().obs, t);
  } catch (const std::exception& e) {
    live.policy.reset();  // a child that failed is started afresh next time
    throw RequestError(502,
                       std::string("the policy ") + options_.policy.text + " failed: " + e.what());
  }
}

nlohmann::json Engine::BackLive(const std::string& session) {
  return Run<nlohmann::json>([&](State& s) {
    Session& ses = s.Touch(session);
    if (!ses.live) throw RequestError(409, "this session has no live episode: start one first");
    LiveEpisode& live = *ses.live;
    if (live.steps.size() <= 1) throw RequestError(409, "the live episode is at its reset");
    live.steps.pop_back();
    live.checkpoints.pop_back();
    live.policy.reset();  // it acts from where the episode now stands, when asked again
    if (static_cast<int>(live.steps.size()) - 1 < live.prefix) live.prefix = live.steps.size() - 1;
    return s.LiveHead(live);
  });
}

nlohmann::json Engine::SaveLive(const std::string& session, const ViewRequest& view) {
  return Run<nlohmann::json>([&](State& s) {
    Session& ses = s.Touch(session);
    if (!ses.live || ses.live->steps.size() <= 1) {
      throw RequestError(409, "nothing to save: the live episode has taken no step");
    }
    const LiveEpisode& live = *ses.live;
    const Source& src = sources_[live.source];
    const FetchEnv& env = *s.env_of_source[live.source];
    // the camera goes into the record command: one this env cannot draw is refused here, as a
    // frame request of it is, not saved into a command that would fail
    std::vector<std::string> keys;
    try {
      for (const CameraSpec& c : ParseCameraList(view.camera, env.model())) {
        keys.push_back(CameraText(c));
      }
    } catch (const UsageError& e) {
      throw RequestError(400, std::string("parameter camera: ") + e.what());
    }
    // the look the page shows (look=...), saved with the episode so that the command redraws it
    const std::optional<LookDraw> look =
        s.ViewLook(view, s.Resolve(ses, {kLiveSource, 0, 0}), keys);
    std::error_code ec;
    fs::create_directories(options_.save_dir, ec);
    const fs::path dir = fs::absolute(options_.save_dir);
    const std::string name = FreeSessionName(dir);
    const fs::path json_path = dir / (name + ".json");
    const fs::path csv_path = dir / (name + ".csv");
    const Trajectory trajectory =
        SavedTrajectory(*src.spec, env, live, json_path, look ? LookJson(*look) : nlohmann::json());
    try {
      WriteFileAtomically(json_path.string(), TrajectoryText(trajectory));
      WriteFileAtomically(csv_path.string(), ActionsCsv(live.steps));
    } catch (const RunError& e) {
      throw RequestError(500, std::string("cannot save the session: ") + e.what());
    }
    ++ses.saves;
    nlohmann::json out = s.LiveData(live);
    out["files"] = {json_path.string(), csv_path.string()};
    if (!live.reset_seed) {
      out["command"] = nullptr;
      out["why_no_command"] =
          "this dataset episode has no seed (it was reset from its first observation or a "
          "continued generator), so record cannot reset to it; the files hold its actions";
      return out;
    }
    const fs::path record_out = dir / name;
    // a placed reset and a look are in the trajectory alone: record replays it --from there (no
    // seed resets to it); otherwise the seed's reset and the replay of the saved actions
    const std::vector<std::string> replay =
        live.placed || look
            ? std::vector<std::string>{"--from", json_path.string()}
            : std::vector<std::string>{
                  "--env-id", src.spec->id,      "--seed",  std::to_string(*live.reset_seed),
                  "--policy", trajectory.policy, "--steps", std::to_string(live.steps.size() - 1)};
    out["command"] =
        RecordCommand(replay, !options_.assets_flag.empty(), env.assets(), view, record_out);
    out["record_out"] = (dir / name).string();
    char episode_file[32];
    std::snprintf(episode_file, sizeof(episode_file), "episode_%03d.json", live.index);
    out["episode_file"] = (dir / name / episode_file).string();
    return out;
  });
}

}  // namespace fetchscope::serve
