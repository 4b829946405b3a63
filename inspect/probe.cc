#include "inspect/probe.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "base/errors.h"
#include "base/json_util.h"
#include "base/number_format.h"
#include "render/vec.h"
#include "src/episode.h"
#include "src/observation_layout.h"

namespace fetchscope {
namespace {

// Steps of action[3] = +1 that open the fingers before grip- is measured.
constexpr int kOpenPrepSteps = 5;
// Thresholds behind the flags (m, per step unless said otherwise).
constexpr double kCosineFloor = 0.9;
constexpr double kStillPerStep = 1e-3;         // slower than this counts as not moving
constexpr double kFingerStill = 1e-4;          // |finger change| below this over a probe: no motion
constexpr double kFingerUncommanded = 2e-3;    // finger change without a gripper command
constexpr double kSaturationTolerance = 0.05;  // relative: "same displacement as |a| = 1"
constexpr int kMaxMagnitudes = 16;

// One probe: a constant command held for the measured steps, after optional preparation.
struct Probe {
  std::string name;
  std::array<double, 4> command{};
  std::vector<std::array<double, 4>> prep;  // steps before the measurement starts
  int axis = -1;                            // commanded axis 0..2; -1 for gripper probes
  double magnitude = 1;                     // |command| on `axis` (or on action[3])
  bool sweep = false;                       // part of the +x magnitude sweep
};

// What one probe measured.
struct Measurement {
  Vec3 mean_step{};            // (p_end - p_start) / steps, m
  double norm = 0;             // |mean_step|
  double along = 0;            // mean_step . axis (signed), m per step
  double cosine = NAN;         // with the commanded axis; NaN for gripper probes or no motion
  double drift = 0;            // |component perpendicular to the axis| per step (all of it if
                               // no axis was commanded)
  double finger_delta = 0;     // change of r + l finger opening over the probe, m
  double finger_baseline = 0;  // the same change with an all-zero command (same preparation)
  double commanded = 0;        // 0.05 * min(|a|, 1) m per step along the axis
  double ratio = NAN;          // along / commanded
  std::vector<std::string> flags;
  SheetTile first, last;  // frames, when rendering
};

std::string FormatMagnitude(double m) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", m);
  return buf;
}

std::vector<Probe> MakeProbes(const std::vector<double>& magnitudes) {
  std::vector<Probe> probes;
  const char* axes = "xyz";
  for (int axis = 0; axis < 3; ++axis) {
    for (int sign : {+1, -1}) {
      Probe p;
      p.name = std::string(sign > 0 ? "+" : "-") + axes[axis];
      p.command[axis] = sign;
      p.axis = axis;
      probes.push_back(p);
    }
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
  for (double m : magnitudes) {
    Probe p;
    p.name = "x@" + FormatMagnitude(m);
    p.command[0] = m;
    p.axis = 0;
    p.magnitude = m;
    p.sweep = true;
    probes.push_back(p);
  }
  return probes;
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

Measurement RunProbe(FetchEnv& env, uint64_t seed, int steps, const Probe& probe,
                     double finger_baseline, Renderer* renderer) {
  const bool has_object = env.spec().has_object;
  // Measured on the observations the env returns, i.e. what an agent sees.
  Observation start = env.Reset(seed);
  for (const auto& a : probe.prep) start = env.Step(Action{a, false}).obs;
  Measurement m;
  if (renderer) {
    renderer->ResetTrail();
    char label[96];
    std::snprintf(label, sizeof(label), "%s start\na = %g %g %g %g", probe.name.c_str(),
                  probe.command[0], probe.command[1], probe.command[2], probe.command[3]);
    m.first = RenderTile(*renderer, env, 0, probe, label);
  }
  Observation end = start;
  for (int t = 0; t < steps; ++t) end = env.Step(Action{probe.command, false}).obs;

  const Vec3 p0 = GripPos(start, has_object), p1 = GripPos(end, has_object);
  for (int k = 0; k < 3; ++k) m.mean_step[k] = (p1[k] - p0[k]) / steps;
  m.norm = Norm(m.mean_step);
  m.finger_delta = FingerOpening(end, has_object) - FingerOpening(start, has_object);
  m.finger_baseline = finger_baseline;
  const double finger_effect = m.finger_delta - finger_baseline;
  if (probe.axis >= 0) {
    const double sign = probe.command[probe.axis] < 0 ? -1.0 : 1.0;
    m.along = sign * m.mean_step[probe.axis];
    m.cosine = m.norm > 0 ? m.along / m.norm : NAN;
    m.drift = std::sqrt(std::max(0.0, m.norm * m.norm - m.along * m.along));
    m.commanded = kProbeMetresPerUnit * std::min(std::fabs(probe.command[probe.axis]), 1.0);
    m.ratio = m.along / m.commanded;
    if (!(m.cosine >= kCosineFloor)) m.flags.push_back("cosine below 0.9");
    if (m.ratio < 0.5) m.flags.push_back("achieved under half the commanded displacement");
    if (std::fabs(finger_effect) > kFingerUncommanded) {
      m.flags.push_back("finger motion where none was commanded");
    }
  } else {
    m.drift = m.norm;
    if (m.norm > kStillPerStep) m.flags.push_back("gripper motion where none was commanded");
    if (std::fabs(finger_effect) < kFingerStill) m.flags.push_back("gripper blocked");
  }
  if (renderer) {
    char label[96];
    if (probe.axis >= 0) {
      std::snprintf(label, sizeof(label), "%s end t=%d\n%s m/step cos %s", probe.name.c_str(),
                    steps, PictureNumber("%.4f", m.norm).c_str(),
                    PictureNumber("%.2f", m.cosine).c_str());
    } else {
      std::snprintf(label, sizeof(label), "%s end t=%d\nfingers %s m", probe.name.c_str(), steps,
                    PictureNumber("%+.4f", m.finger_delta).c_str());
    }
    m.last = RenderTile(*renderer, env, steps, probe, label);
  }
  return m;
}

// Adds the saturation flags of the sweep: above |a| = 1 the env clips, so the displacement
// should equal the one at |a| = 1 (the +x probe).
void FlagSaturation(const std::vector<Probe>& probes, std::vector<Measurement>* ms) {
  double unit = NAN;
  for (size_t i = 0; i < probes.size(); ++i) {
    if (probes[i].name == "+x") unit = (*ms)[i].along;
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

nlohmann::json ProbeJson(const Probe& p, const Measurement& m) {
  nlohmann::json flags = nlohmann::json::array();
  for (const auto& f : m.flags) flags.push_back(f);
  nlohmann::json j = {
      {"name", p.name},
      {"command", JsonVector(p.command.data(), 4)},
      {"preparation_steps", static_cast<int>(p.prep.size())},
      {"mean_step_displacement",
       {{"vector", JsonVector(m.mean_step.data(), 3)}, {"norm", JsonDouble(m.norm)}}},
      {"along_axis", p.axis >= 0 ? JsonDouble(m.along) : nlohmann::json(nullptr)},
      {"cosine", std::isfinite(m.cosine) ? JsonDouble(m.cosine) : nlohmann::json(nullptr)},
      {"cross_axis_drift", JsonDouble(m.drift)},
      {"finger_delta", JsonDouble(m.finger_delta)},
      {"finger_delta_without_command", JsonDouble(m.finger_baseline)},
      {"finger_delta_from_command", JsonDouble(m.finger_delta - m.finger_baseline)},
      {"commanded_displacement", JsonDouble(m.commanded)},
      {"achieved_ratio", std::isfinite(m.ratio) ? JsonDouble(m.ratio) : nlohmann::json(nullptr)},
      {"flags", flags}};
  if (p.sweep) j["magnitude"] = JsonDouble(p.magnitude);
  return j;
}

nlohmann::json SummaryJson(const EnvSpec& spec, const std::vector<Probe>& probes,
                           const std::vector<Measurement>& ms) {
  double open_delta = 0, close_delta = 0, step_sum = 0;
  bool saturated = false, any_above_one = false;
  for (size_t i = 0; i < probes.size(); ++i) {
    const double effect = ms[i].finger_delta - ms[i].finger_baseline;
    if (probes[i].name == "grip+") open_delta = effect;
    if (probes[i].name == "grip-") close_delta = effect;
    if (probes[i].axis >= 0 && !probes[i].sweep) step_sum += ms[i].norm;
    if (probes[i].sweep && probes[i].magnitude > 1) {
      any_above_one = true;
      saturated = saturated || std::find(ms[i].flags.begin(), ms[i].flags.end(),
                                         "saturated: same displacement as |a| = 1 (actions are "
                                         "clipped to [-1, 1])") != ms[i].flags.end();
    }
  }
  const bool blocked =
      std::fabs(open_delta) < kFingerStill && std::fabs(close_delta) < kFingerStill;
  std::string opens;
  if (blocked) {
    opens = "neither: the fingers do not move (gripper blocked)";
  } else if (open_delta > 0 && close_delta < 0) {
    opens = "action[3] > 0 opens the fingers, action[3] < 0 closes them";
  } else if (open_delta < 0 && close_delta > 0) {
    opens = "action[3] < 0 opens the fingers, action[3] > 0 closes them";
  } else {
    opens = "unclear: grip+ and grip- did not move the fingers in opposite directions";
  }
  const double step = step_sum / 6;
  char step_text[160];
  std::snprintf(step_text, sizeof(step_text),
                "%.4f m per step at |a| = 1 (mean over the six axis probes; commanded %.2f m)",
                step, kProbeMetresPerUnit);
  std::string saturation = !any_above_one ? "not measured (no magnitude above 1 in --magnitudes)"
                           : saturated    ? "yes: magnitudes above 1 move as far as 1"
                                          : "no: a magnitude above 1 moved differently from 1";
  return {{"opens_fingers", opens},
          {"opening_sign",
           blocked ? nlohmann::json(nullptr) : nlohmann::json(open_delta > 0 ? "+" : "-")},
          {"gripper", std::string(blocked ? "blocked" : "free") + " in " + spec.id +
                          (blocked ? ": action[3] does not move the fingers"
                                   : ": action[3] moves the fingers")},
          {"gripper_blocked", blocked},
          {"block_gripper_setting", spec.block_gripper},
          {"step_size_at_unit_action", JsonDouble(step)},
          {"step_size", step_text},
          {"saturation_above_one", saturation}};
}

void PrintTable(const EnvSpec& spec, uint64_t seed, int steps, const std::vector<Probe>& probes,
                const std::vector<Measurement>& ms, const nlohmann::json& summary) {
  std::printf("probe-actions %s seed %llu, %d steps per probe\n", spec.id.c_str(),
              static_cast<unsigned long long>(seed), steps);
  std::printf("%-8s %-26s %9s %7s %9s %6s %9s %9s  %s\n", "probe", "m/step (x y z)", "|d|", "cos",
              "drift", "ratio", "fingers", "by cmd", "flags");
  for (size_t i = 0; i < probes.size(); ++i) {
    const Measurement& m = ms[i];
    char vec[64];
    std::snprintf(vec, sizeof(vec), "%+.4f %+.4f %+.4f", m.mean_step[0], m.mean_step[1],
                  m.mean_step[2]);
    std::string flags;
    for (const auto& f : m.flags) flags += (flags.empty() ? "" : "; ") + f;
    char cosine[16] = "-", ratio[16] = "-";
    if (std::isfinite(m.cosine)) std::snprintf(cosine, sizeof(cosine), "%.3f", m.cosine);
    if (std::isfinite(m.ratio)) std::snprintf(ratio, sizeof(ratio), "%.2f", m.ratio);
    std::printf("%-8s %-26s %9.5f %7s %9.5f %6s %+9.5f %+9.5f  %s\n", probes[i].name.c_str(), vec,
                m.norm, cosine, m.drift, ratio, m.finger_delta, m.finger_delta - m.finger_baseline,
                flags.c_str());
  }
  std::printf("gripper: %s\n", summary["gripper"].get<std::string>().c_str());
  std::printf("opening: %s\n", summary["opens_fingers"].get<std::string>().c_str());
  std::printf("step:    %s\n", summary["step_size"].get<std::string>().c_str());
  std::printf("clip:    %s\n", summary["saturation_above_one"].get<std::string>().c_str());
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

ProbeResult ProbeActions(FetchEnv& env, uint64_t seed, int steps,
                         const std::vector<double>& magnitudes, Renderer* renderer) {
  const EnvSpec& spec = env.spec();
  const FingerIndices fingers = FingerPositionIndices(spec.has_object);
  const std::vector<Probe> probes = MakeProbes(magnitudes);
  const double baseline_reset = FingerBaseline(env, seed, steps, 0);
  const double baseline_open = FingerBaseline(env, seed, steps, kOpenPrepSteps);
  std::vector<Measurement> ms;
  for (const Probe& p : probes) {
    const double baseline = p.prep.empty() ? baseline_reset : baseline_open;
    ms.push_back(RunProbe(env, seed, steps, p, baseline, renderer));
  }
  FlagSaturation(probes, &ms);

  nlohmann::json probes_json = nlohmann::json::array();
  for (size_t i = 0; i < probes.size(); ++i) probes_json.push_back(ProbeJson(probes[i], ms[i]));
  const nlohmann::json summary = SummaryJson(spec, probes, ms);
  ProbeResult result;
  result.report = {{"env_id", spec.id},
                   {"seed", seed},
                   {"steps", steps},
                   {"metres_per_unit_action", kProbeMetresPerUnit},
                   {"finger_indices", {fingers.right, fingers.left}},
                   {"assets", AssetsJson(env.assets())},
                   {"probes", probes_json},
                   {"summary", summary}};
  PrintTable(spec, seed, steps, probes, ms, summary);
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
