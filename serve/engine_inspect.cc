// serve's engine (serve/engine.h), what the page inspects: an episode's rows as the step
// inspector and the plots read them (whole, or a live step's alone), the episode browser's
// columns of every episode of a source, and what is under the pointer (the body, the world point
// of the depth layer, the body's position).
#include <algorithm>
#include <cmath>

#include "base/errors.h"
#include "base/json_util.h"
#include "inspect/viewer.h"
#include "render/obs_view.h"
#include "serve/engine.h"
#include "serve/engine_state.h"

namespace fetchscope::serve {

nlohmann::json RowJson(const TrajectoryStep& s) {
  nlohmann::json row = {
      {"t", s.t},
      {"is_success", s.is_success},
      {"observation", JsonVector(s.obs.observation.data(), s.obs.observation.size())},
      {"achieved_goal", JsonVector(s.obs.achieved_goal.data(), 3)},
      {"desired_goal", JsonVector(s.obs.desired_goal.data(), 3)},
      {"action", s.action ? JsonVector(s.action->value.data(), 4) : nullptr},
      {"reward", s.reward ? JsonDouble(*s.reward) : nullptr}};
  if (s.contacts) {
    row["contacts"] = {{"left_finger_force", JsonDouble(s.contacts->left_finger_force)},
                       {"right_finger_force", JsonDouble(s.contacts->right_finger_force)},
                       {"grasped", s.contacts->grasped()},
                       {"object_on_table", s.contacts->object_on_table}};
  }
  return row;
}

namespace {

// Each per-step list of `signals` (EpisodeSignals of two steps) replaced by its last value.
nlohmann::json LastValues(const nlohmann::json& v) {
  if (v.is_object()) {
    nlohmann::json out = nlohmann::json::object();
    for (const auto& [key, x] : v.items()) out[key] = key == "colors" ? x : LastValues(x);
    return out;
  }
  if (!v.is_array() || v.empty()) return v;
  if (v.front().is_array()) {
    nlohmann::json out = nlohmann::json::array();
    for (const nlohmann::json& list : v) out.push_back(LastValues(list));
    return out;
  }
  return v.back();
}

}  // namespace

nlohmann::json LastStepSignals(const EnvSpec& spec, const std::vector<TrajectoryStep>& steps) {
  const size_t n = steps.size();
  const std::vector<TrajectoryStep> last(steps.begin() + (n > 1 ? n - 2 : 0), steps.end());
  nlohmann::json signals = LastValues(EpisodeSignals(spec, last));
  signals.erase("frames");
  return signals;
}

nlohmann::json RowsData(const EnvSpec& spec, const std::vector<TrajectoryStep>& steps,
                        const std::optional<uint64_t>& hindsight_seed) {
  nlohmann::json rows = nlohmann::json::array();
  for (const TrajectoryStep& s : steps) rows.push_back(RowJson(s));
  return {{"env_id", spec.id},
          {"steps", static_cast<int>(steps.size()) - 1},
          {"rows", std::move(rows)},
          {"signals", EpisodeSignals(spec, steps, hindsight_seed)}};
}

nlohmann::json Engine::Listing(const std::string& session, int source) {
  return Run<nlohmann::json>([&](State& s) {
    s.Touch(session);
    if (source < 0 || source >= static_cast<int>(sources_.size()) ||
        sources_[source].kind == SourceKind::kLive) {
      throw RequestError(404, "no served episodes in source " + std::to_string(source));
    }
    nlohmann::json& listing = s.listings[source];
    if (!listing.is_null()) return listing;
    const Source& src = sources_[source];
    nlohmann::json episodes = nlohmann::json::array();
    for (const ListedEpisode& e : src.episodes) {
      nlohmann::json row;
      try {
        row = EpisodeColumns(*src.spec, EpisodeRows(src, e.index).steps);
        if (src.kind == SourceKind::kDataset) row.update(s.DatasetDivergence(source, e.index));
      } catch (const std::exception& error) {  // a file gone since, a replay that cannot start
        row = {{"error", error.what()}};
      }
      row["index"] = e.index;
      episodes.push_back(std::move(row));
    }
    listing = {{"source", source}, {"episodes", std::move(episodes)}};
    return listing;
  });
}

namespace {

// The world point the depth layer shows at pixel (x, y) of a one-camera frame: the pixel's ray
// (render/obs_view.h's pinhole model of the view camera) out to its depth; null where nothing is.
nlohmann::json WorldPointAt(Renderer& renderer, const mjData* data, const FrameInfo& info, int x,
                            int y) {
  std::vector<float> depth;
  renderer.RenderDepthMetres(data, info, &depth);
  const double z = depth.at(static_cast<size_t>(y) * renderer.width() + x);
  if (!(z > 0)) return nullptr;
  const mjvGLCamera camera = renderer.view_camera();
  const ObsCameraGeometry g = CameraGeometry(camera, renderer.width(), renderer.height());
  // in the camera frame: x right, y up, looking along -z; image rows grow downwards
  const double cx = (x - g.cx) / g.fx * z, cy = -(y - g.cy) / g.fy * z;
  const double f[3] = {camera.forward[0], camera.forward[1], camera.forward[2]};
  const double up[3] = {camera.up[0], camera.up[1], camera.up[2]};
  const double right[3] = {f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2],
                           f[0] * up[1] - f[1] * up[0]};
  std::array<double, 3> p{};
  for (int k = 0; k < 3; ++k) p[k] = camera.pos[k] + cx * right[k] + cy * up[k] + z * f[k];
  return JsonVector(p.data(), 3);
}

}  // namespace

nlohmann::json Engine::Pick(const std::string& session, const PickRequest& r) {
  return Run<nlohmann::json>([&](State& s) {
    Session& ses = s.Touch(session);
    const StepState state = s.Resolve(ses, r.view.at);
    FrameInfo info;
    std::string camera;
    Renderer& renderer = s.Prepare(r.view, state, &info, &camera);
    const mjData* data = state.env->data();
    const std::optional<PickedObject> picked = renderer.Pick(data, info, r.x, r.y);
    if (!picked) return nlohmann::json{{"body", nullptr}, {"x", r.x}, {"y", r.y}};
    char color[8];
    std::snprintf(color, sizeof(color), "#%02x%02x%02x", picked->color[0], picked->color[1],
                  picked->color[2]);
    nlohmann::json out = {
        {"body", picked->body},
        {"geom", picked->geom.empty() ? nlohmann::json() : nlohmann::json(picked->geom)},
        {"site", picked->site.empty() ? nlohmann::json() : nlohmann::json(picked->site)},
        {"color", color},
        {"x", r.x},
        {"y", r.y},
        {"point", nullptr}};
    if (picked->body_id >= 0) {
      out["body_pos"] = JsonVector(data->xpos + 3 * picked->body_id, 3);
    }
    if (renderer.tiles().size() == 1) out["point"] = WorldPointAt(renderer, data, info, r.x, r.y);
    return out;
  });
}

}  // namespace fetchscope::serve
