#include "inspect/probe.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "base/errors.h"
#include "base/json_util.h"
#include "base/number_format.h"
#include "inspect/probe_parts.h"
#include "inspect/probe_steps.h"
#include "render/vec.h"
#include "src/episode.h"
#include "src/observation_layout.h"

namespace fetchscope {
namespace {

using probe_detail::kAxisNames;
using probe_detail::kCosineFloor;
using probe_detail::kFingerStill;
using probe_detail::kFingerUncommanded;
using probe_detail::kMaxMagnitudes;
using probe_detail::kOpenPrepSteps;
using probe_detail::kSaturationTolerance;
using probe_detail::kStillPerStep;
using probe_detail::Measurement;
using probe_detail::Probe;

std::string FormatMagnitude(double m) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", m);
  return buf;
}

// The six axis probes, then grip+ and grip- (the sweep comes once its axis is chosen).
std::vector<Probe> MakeProbes() {
  std::vector<Probe> probes;
  for (int i = 0; i < 6; ++i) {
    Probe p;
    p.name = kAxisNames[i];
    p.axis = i / 2;
    p.command[p.axis] = i % 2 ? -1 : 1;
    probes.push_back(p);
  }
  Probe open;
  open.name = "grip+";
  open.command[3] = 1;  // fingers start shut at reset: free to open
  probes.push_back(open);
  Probe close;
  close.name = "grip-";
  close.command[3] = -1;
  close.prep.assign(kOpenPrepSteps, {0, 0, 0, 1});  // open first, so there is room to close
  probes.push_back(close);
  return probes;
}

// The sweep along signed axis `signed_axis` (0..5 as kAxisNames): "+y@0.5", ...
std::vector<Probe> MakeSweep(int signed_axis, const std::vector<double>& magnitudes) {
  std::vector<Probe> probes;
  for (double m : magnitudes) {
    Probe p;
    p.name = std::string(kAxisNames[signed_axis]) + "@" + FormatMagnitude(m);
    p.axis = signed_axis / 2;
    p.command[p.axis] = signed_axis % 2 ? -m : m;
    p.magnitude = m;
    p.sweep = true;
    probes.push_back(p);
  }
  return probes;
}

// The signed axis with the most room: the axis probe with the most steps before its first
// limited step (all of them when none is limited); the first in kAxisNames on a tie.
int AxisWithRoom(const std::vector<Measurement>& axis_probes) {
  int best = 0, best_room = -1;
  for (int i = 0; i < 6; ++i) {
    const std::vector<ProbeStep>& steps = axis_probes[static_cast<size_t>(i)].steps;
    int room = 0;
    while (room < static_cast<int>(steps.size()) && !steps[static_cast<size_t>(room)].limited()) {
      ++room;
    }
    if (room > best_room) best = i, best_room = room;
  }
  return best;
}

Vec3 GripPos(const Observation& obs, bool has_object) {
  const size_t i = static_cast<size_t>(FindObservationSlice(has_object, "grip_pos")->first);
  return {obs.observation[i], obs.observation[i + 1], obs.observation[i + 2]};
}

// r finger + l finger positions (gripper_state: indices 3, 4 on Reach, 9, 10 with an object).
double FingerOpening(const Observation& obs, bool has_object) {
  const FingerIndices f = FingerPositionIndices(has_object);
  return obs.observation[f.right] + obs.observation[f.left];
}

// Renders the env's current state with the grip site as the "achieved" point, so the trail
// overlay follows the gripper (for object tasks the achieved goal is the object).
SheetTile RenderTile(Renderer& renderer, const FetchEnv& env, int step, const Probe& probe,
                     const std::string& label) {
  const Observation obs = env.Observe();
  FrameInfo info;
  info.step = step;
  info.has_action = true;  // the arrow shows the probe's command on both frames
  info.action = probe.command;
  info.goal = obs.desired_goal;
  info.achieved = GripPos(obs, env.spec().has_object);
  info.distance_threshold = env.spec().distance_threshold;
  info.title = env.spec().id;
  SheetTile tile;
  tile.width = renderer.width();
  tile.height = renderer.height();
  tile.rgb.resize(static_cast<size_t>(tile.width) * tile.height * 3);
  renderer.Render(env.data(), info, tile.rgb.data());
  tile.label = label;
  return tile;
}

// The finger opening change over `steps` all-zero steps after `prep_steps` opening steps. Reach,
// Push and Slide force the fingers shut after every step, so their fingers move on the first
// step whatever action[3] says; subtracting this isolates what the command itself did.
double FingerBaseline(FetchEnv& env, uint64_t seed, int steps, int prep_steps) {
  const bool has_object = env.spec().has_object;
  Observation obs = env.Reset(seed);
  for (int t = 0; t < prep_steps; ++t) obs = env.Step(Action{{0, 0, 0, 1}, false}).obs;
  const double f0 = FingerOpening(obs, has_object);
  for (int t = 0; t < steps; ++t) obs = env.Step(Action{{0, 0, 0, 0}, false}).obs;
  return FingerOpening(obs, has_object) - f0;
}

// Steps `probe`'s command `steps` times from `start`, filling m's per-step series and totals.
void MeasureSteps(FetchEnv& env, int steps, const Probe& probe, const Observation& start,
                  Measurement* m) {
  const bool has_object = env.spec().has_object;
  Observation before = start;
  for (int t = 0; t < steps; ++t) {
    const Observation after = env.Step(Action{probe.command, false}).obs;
    ProbeStep s;
    const Vec3 p0 = GripPos(before, has_object), p1 = GripPos(after, has_object);
    for (int k = 0; k < 3; ++k) s.displacement[k] = p1[k] - p0[k];
    if (probe.axis >= 0) {
      s.along = (probe.command[probe.axis] < 0 ? -1.0 : 1.0) * s.displacement[probe.axis];
    }
    s.finger_width = FingerOpening(after, has_object);
    s.finger_change = s.finger_width - FingerOpening(before, has_object);
    ReadRobotContacts(env, &s);
    m->steps.push_back(s);
    before = after;
  }
  FlagStepLimits(probe.command, probe.axis, &m->steps);
  m->steady = FindSteadyState(m->steps);
  const Vec3 p0 = GripPos(start, has_object), p1 = GripPos(before, has_object);
  for (int k = 0; k < 3; ++k) m->mean_step[k] = (p1[k] - p0[k]) / steps;
  m->norm = Norm(m->mean_step);
  m->finger_delta = FingerOpening(before, has_object) - FingerOpening(start, has_object);
}

// The probe's totals and flags from its steps. `finger_baseline`: the finger width change of
// the same preparation with an all-zero command (gripper probes); an axis probe's own command
// has action[3] = 0 already, so it is its own baseline and nothing is due to action[3].
void Analyse(const Probe& probe, double finger_baseline, Measurement* m) {
  m->finger_baseline = probe.command[3] == 0 ? m->finger_delta : finger_baseline;
  const double finger_effect = m->finger_delta - m->finger_baseline;
  if (probe.axis >= 0) {
    const double sign = probe.command[probe.axis] < 0 ? -1.0 : 1.0;
    m->along = sign * m->mean_step[probe.axis];
    m->cosine = m->norm > 0 ? m->along / m->norm : NAN;
    m->drift = std::sqrt(std::max(0.0, m->norm * m->norm - m->along * m->along));
    m->commanded = kProbeMetresPerUnit * std::min(std::fabs(probe.command[probe.axis]), 1.0);
    m->ratio = m->along / m->commanded;
    if (!(m->cosine >= kCosineFloor)) m->flags.push_back("cosine below 0.9");
    for (const char* limit : {"table", "object", "reach"}) {
      const int first = FirstLimited(m->steps, limit);
      if (first > 0) {
        m->flags.push_back("limited by " + std::string(limit) + " from step " +
                           std::to_string(first));
      }
    }
    if (FirstLimited(m->steps, "clip") > 0) {
      m->flags.push_back("clipped: the env clips |a| > 1 to 1");
    }
    if (std::fabs(m->finger_delta) > kFingerUncommanded) {
      char text[120];
      std::snprintf(text, sizeof(text),
                    "finger width changed %+.1f mm with action[3] = 0 (not from the gripper "
                    "command)",
                    1000 * m->finger_delta);
      m->flags.push_back(text);
    }
  } else {
    m->drift = m->norm;
    if (m->norm > kStillPerStep) m->flags.push_back("gripper motion where none was commanded");
    if (std::fabs(finger_effect) < kFingerStill) m->flags.push_back("gripper blocked");
  }
}

Measurement RunProbe(FetchEnv& env, uint64_t seed, int steps, const Probe& probe,
                     double finger_baseline, Renderer* renderer) {
  // Measured on the observations the env returns, i.e. what an agent sees.
  Observation start = env.Reset(seed);
  for (const auto& a : probe.prep) start = env.Step(Action{a, false}).obs;
  Measurement m;
  if (renderer) {
    renderer->ResetTrail();
    char label[96];
    std::snprintf(label, sizeof(label), "%s start%s\na = %g %g %g %g", probe.name.c_str(),
                  probe.prep.empty() ? "" : " (after the preparation)", probe.command[0],
                  probe.command[1], probe.command[2], probe.command[3]);
    m.first = RenderTile(*renderer, env, 0, probe, label);
  }
  MeasureSteps(env, steps, probe, start, &m);
  Analyse(probe, finger_baseline, &m);
  if (renderer) {
    char label[96];
    if (probe.axis >= 0) {
      std::snprintf(label, sizeof(label), "%s end t=%d\nsteady %s mm/step cos %s",
                    probe.name.c_str(), steps,
                    m.steady.valid() ? PictureNumber("%.1f", 1000 * m.steady.along).c_str() : "-",
                    PictureNumber("%.2f", m.cosine).c_str());
    } else {
      std::snprintf(label, sizeof(label), "%s end t=%d\nfinger width %s mm", probe.name.c_str(),
                    steps, PictureNumber("%+.1f", 1000 * m.finger_delta).c_str());
    }
    m.last = RenderTile(*renderer, env, steps, probe, label);
  }
  return m;
}

// Adds the saturation flags of the sweep: above |a| = 1 the env clips, so the displacement
// should equal the one at |a| = 1 (the axis probe of the sweep's axis, `unit_probe`).
void FlagSaturation(const std::vector<Probe>& probes, const std::string& unit_probe,
                    std::vector<Measurement>* ms) {
  double unit = NAN;
  for (size_t i = 0; i < probes.size(); ++i) {
    if (probes[i].name == unit_probe) unit = (*ms)[i].along;
  }
  for (size_t i = 0; i < probes.size(); ++i) {
    if (!probes[i].sweep || probes[i].magnitude <= 1) continue;
    const double along = (*ms)[i].along;
    if (std::fabs(along - unit) <= kSaturationTolerance * std::fabs(unit)) {
      (*ms)[i].flags.push_back(
          "saturated: same displacement as |a| = 1 (actions are clipped to [-1, 1])");
    } else {
      (*ms)[i].flags.push_back("not saturated: displacement differs from |a| = 1");
    }
  }
}

}  // namespace

std::vector<double> ParseProbeMagnitudes(const std::string& text) {
  const std::string accepted = ": use a comma list of 1 to 16 positive numbers, e.g. 0.25,0.5,1,2";
  if (text.empty()) throw UsageError("--magnitudes is empty" + accepted);
  std::vector<double> values;
  std::stringstream ss(text);
  std::string token;
  while (std::getline(ss, token, ',')) {
    const char* s = token.c_str();
    char* end = nullptr;
    const double v = token.empty() ? NAN : std::strtod(s, &end);
    if (token.empty() || end == s || *end != '\0' || !std::isfinite(v) || v <= 0) {
      throw UsageError("--magnitudes '" + text + "': '" + token + "' is not a positive number" +
                       accepted);
    }
    values.push_back(v);
  }
  if (text.back() == ',')
    throw UsageError("--magnitudes '" + text + "' ends with a comma" + accepted);
  if (static_cast<int>(values.size()) > kMaxMagnitudes) {
    throw UsageError("--magnitudes '" + text + "' has " + std::to_string(values.size()) +
                     " values" + accepted);
  }
  return values;
}

std::optional<int> ParseSweepAxis(const std::string& text) {
  if (text == "auto") return std::nullopt;
  for (int i = 0; i < 6; ++i) {
    if (text == kAxisNames[i]) return i;
  }
  throw UsageError("--sweep-axis '" + text +
                   "' is not an axis: use auto, +x, -x, +y, -y, +z or -z");
}

ProbeResult ProbeActions(FetchEnv& env, uint64_t seed, int steps,
                         const std::vector<double>& magnitudes, std::optional<int> sweep_axis,
                         Renderer* renderer) {
  const EnvSpec& spec = env.spec();
  const FingerIndices fingers = FingerPositionIndices(spec.has_object);
  std::vector<Probe> probes = MakeProbes();
  const double baseline_reset = FingerBaseline(env, seed, steps, 0);
  const double baseline_open = FingerBaseline(env, seed, steps, kOpenPrepSteps);
  std::vector<Measurement> ms;
  for (const Probe& p : probes) {
    const double baseline = p.prep.empty() ? baseline_reset : baseline_open;
    ms.push_back(RunProbe(env, seed, steps, p, baseline, renderer));
  }
  const int axis = sweep_axis ? *sweep_axis : AxisWithRoom(ms);
  const std::string why = sweep_axis ? "--sweep-axis" : "the axis probe with the most room";
  for (const Probe& p : MakeSweep(axis, magnitudes)) {
    probes.push_back(p);
    ms.push_back(RunProbe(env, seed, steps, p, baseline_reset, renderer));
  }
  FlagSaturation(probes, kAxisNames[axis], &ms);

  nlohmann::json probes_json = nlohmann::json::array();
  for (size_t i = 0; i < probes.size(); ++i) {
    probes_json.push_back(probe_detail::ProbeJson(probes[i], ms[i]));
  }
  const nlohmann::json summary = probe_detail::SummaryJson(spec, probes, ms, kAxisNames[axis], why);
  ProbeResult result;
  result.report = {{"env_id", spec.id},
                   {"seed", seed},
                   {"steps", steps},
                   {"metres_per_unit_action", kProbeMetresPerUnit},
                   {"units",
                    {{"displacement", "m per step (grip_pos, obs[0:3])"},
                     {"finger", "m (finger width: gripper_state.right + gripper_state.left)"}}},
                   {"finger_indices", {fingers.right, fingers.left}},
                   {"sweep_axis", kAxisNames[axis]},
                   {"assets", AssetsJson(env.assets())},
                   {"probes", probes_json},
                   {"summary", summary}};
  probe_detail::PrintTable(spec, seed, steps, probes, ms, summary);
  if (renderer) {
    for (auto& m : ms) {
      result.tiles.push_back(std::move(m.first));
      result.tiles.push_back(std::move(m.last));
    }
  }
  return result;
}

int ProbeSheetColumns(std::size_t tiles) {
  // a pair is two tiles about as wide as they are high: p pairs per row and pairs / p rows make
  // a square when 2 p = pairs / p
  const double pairs = static_cast<double>((tiles + 1) / 2);
  return 2 * std::max(1, static_cast<int>(std::lround(std::sqrt(pairs / 2))));
}

}  // namespace fetchscope
