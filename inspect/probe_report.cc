// probe-actions' report: each probe's JSON, the summary's answers and the printed table.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "base/json_util.h"
#include "inspect/probe.h"
#include "inspect/probe_parts.h"

namespace fetchscope::probe_detail {
namespace {

using nlohmann::json;

json OrNull(double v) { return std::isfinite(v) ? JsonDouble(v) : json(nullptr); }
json OrNull(int step) { return step > 0 ? json(step) : json(nullptr); }

const char* const kSaturated =
    "saturated: same displacement as |a| = 1 (actions are clipped to [-1, 1])";

double Median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string PreparationText(const Probe& p) {
  if (p.prep.empty()) return "none: measured from the reset";
  char text[160];
  const auto& a = p.prep.front();
  std::snprintf(text, sizeof(text), "%zu steps of a = (%g, %g, %g, %g) after the reset%s",
                p.prep.size(), a[0], a[1], a[2], a[3],
                a[3] > 0 ? ", opening the fingers so that there is room to close them" : "");
  return text;
}

std::string PreparationSummary(const std::vector<Probe>& probes) {
  std::string text;
  for (const Probe& p : probes) {
    if (!p.prep.empty()) text += p.name + " starts after " + PreparationText(p) + "; ";
  }
  return text + "every other probe starts at the reset";
}

// The sweep's steady states per magnitude, relative to each one's command: equal ratios mean
// the displacement is proportional to |a| (up to the clip at 1).
json SweepJson(const std::vector<Probe>& probes, const std::vector<Measurement>& ms,
               const std::string& axis, const std::string& why) {
  json rows = json::array();
  std::string text = "along " + axis + " (" + why + "), steady mm/step (ratio to command):";
  for (size_t i = 0; i < probes.size(); ++i) {
    if (!probes[i].sweep) continue;
    const Measurement& m = ms[i];
    const double steady = m.steady.valid() ? m.steady.along : NAN;
    rows.push_back({{"name", probes[i].name},
                    {"magnitude", JsonDouble(probes[i].magnitude)},
                    {"commanded_displacement", JsonDouble(m.commanded)},
                    {"steady_state", OrNull(steady)},
                    {"steady_ratio", OrNull(steady / m.commanded)}});
    char cell[80];
    if (std::isfinite(steady)) {
      std::snprintf(cell, sizeof(cell), " %g: %.1f (%.2f)", probes[i].magnitude, 1000 * steady,
                    steady / m.commanded);
    } else {
      std::snprintf(cell, sizeof(cell), " %g: - (limited from step 1 or 2)", probes[i].magnitude);
    }
    text += cell;
  }
  return {{"axis", axis}, {"why", why}, {"probes", rows}, {"text", text}};
}

}  // namespace

json ProbeJson(const Probe& p, const Measurement& m) {
  json flags = json::array();
  for (const auto& f : m.flags) flags.push_back(f);
  const bool axis = p.axis >= 0;
  json steady = nullptr;
  if (axis && m.steady.valid()) {
    steady = {{"along_axis", JsonDouble(m.steady.along)},
              {"ratio", JsonDouble(m.steady.along / m.commanded)},
              {"from_step", m.steady.first},
              {"to_step", m.steady.last}};
  }
  json first_limited = json::object();
  for (const char* limit : {"clip", "table", "object", "reach"}) {
    first_limited[limit] = OrNull(FirstLimited(m.steps, limit));
  }
  json j = {{"name", p.name},
            {"command", JsonVector(p.command.data(), 4)},
            {"preparation_steps", static_cast<int>(p.prep.size())},
            {"preparation",
             {{"steps", static_cast<int>(p.prep.size())},
              {"action", p.prep.empty() ? json(nullptr) : JsonVector(p.prep.front().data(), 4)},
              {"text", PreparationText(p)}}},
            {"mean_step_displacement",
             {{"vector", JsonVector(m.mean_step.data(), 3)}, {"norm", JsonDouble(m.norm)}}},
            {"along_axis", axis ? JsonDouble(m.along) : json(nullptr)},
            {"cosine", OrNull(m.cosine)},
            {"cross_axis_drift", JsonDouble(m.drift)},
            {"steady_state", steady},
            {"first_limited_step", first_limited},
            {"finger_delta", JsonDouble(m.finger_delta)},
            {"finger_delta_without_command", JsonDouble(m.finger_baseline)},
            {"finger_delta_from_command", JsonDouble(m.finger_delta - m.finger_baseline)},
            {"commanded_displacement", JsonDouble(m.commanded)},
            {"achieved_ratio", OrNull(m.ratio)},
            {"steps", StepsJson(m.steps, axis)},
            {"flags", flags}};
  if (p.sweep) j["magnitude"] = JsonDouble(p.magnitude);
  return j;
}

json SummaryJson(const EnvSpec& spec, const std::vector<Probe>& probes,
                 const std::vector<Measurement>& ms, const std::string& sweep_axis,
                 const std::string& sweep_why) {
  double open_delta = 0, close_delta = 0, step_sum = 0;
  bool saturated = false, any_above_one = false;
  std::vector<double> steadies;
  for (size_t i = 0; i < probes.size(); ++i) {
    const double effect = ms[i].finger_delta - ms[i].finger_baseline;
    if (probes[i].name == "grip+") open_delta = effect;
    if (probes[i].name == "grip-") close_delta = effect;
    if (probes[i].axis >= 0 && !probes[i].sweep) {
      step_sum += ms[i].norm;
      if (ms[i].steady.valid()) steadies.push_back(ms[i].steady.along);
    }
    if (probes[i].sweep && probes[i].magnitude > 1) {
      any_above_one = true;
      saturated = saturated || std::find(ms[i].flags.begin(), ms[i].flags.end(), kSaturated) !=
                                   ms[i].flags.end();
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
  char step_text[160], steady_text[200];
  std::snprintf(step_text, sizeof(step_text),
                "%.4f m per step at |a| = 1 (mean over the six axis probes; commanded %.2f m)",
                step, kProbeMetresPerUnit);
  const double steady = Median(steadies);
  std::snprintf(steady_text, sizeof(steady_text),
                "%.4f m per step at |a| = 1 (median of the steady states of %zu of the six axis "
                "probes, steps 2 on before any limit; commanded %.2f m)",
                steady, steadies.size(), kProbeMetresPerUnit);
  std::string saturation = !any_above_one ? "not measured (no magnitude above 1 in --magnitudes)"
                           : saturated    ? "yes: magnitudes above 1 move as far as 1"
                                          : "no: a magnitude above 1 moved differently from 1";
  return {{"opens_fingers", opens},
          {"opening_sign", blocked ? json(nullptr) : json(open_delta > 0 ? "+" : "-")},
          {"gripper", std::string(blocked ? "blocked" : "free") + " in " + spec.id +
                          (blocked ? ": action[3] does not move the fingers"
                                   : ": action[3] moves the fingers")},
          {"gripper_blocked", blocked},
          {"block_gripper_setting", spec.block_gripper},
          {"step_size_at_unit_action", JsonDouble(step)},
          {"step_size", step_text},
          {"steady_step_at_unit_action", OrNull(steady)},
          {"steady_step", steadies.empty() ? "none: every axis probe was limited from step 2"
                                           : std::string(steady_text)},
          {"saturation_above_one", saturation},
          {"sweep", SweepJson(probes, ms, sweep_axis, sweep_why)},
          {"preparation", PreparationSummary(probes)}};
}

void PrintTable(const EnvSpec& spec, uint64_t seed, int steps, const std::vector<Probe>& probes,
                const std::vector<Measurement>& ms, const json& summary) {
  std::printf("probe-actions %s seed %llu, %d steps per probe\n", spec.id.c_str(),
              static_cast<unsigned long long>(seed), steps);
  std::printf(
      "grip site displacement in mm per step (commanded: 50 x min(|a|, 1) mm); steady: median "
      "of steps 2 on before a limit; fingers: width change over the probe in mm, a[3]: of it "
      "due to action[3]\n");
  std::printf("%-8s %-20s %5s %6s %5s %5s %6s %5s %6s %6s %6s  %s\n", "probe", "mean (x y z)",
              "|d|", "cos", "drift", "ratio", "steady", "ratio", "steps", "finger", "a[3]",
              "flags");
  for (size_t i = 0; i < probes.size(); ++i) {
    const Measurement& m = ms[i];
    char vec[64], cosine[16] = "-", ratio[16] = "-", steady[16] = "-", sratio[16] = "-",
                  span[16] = "-";
    std::snprintf(vec, sizeof(vec), "%+.1f %+.1f %+.1f", 1000 * m.mean_step[0],
                  1000 * m.mean_step[1], 1000 * m.mean_step[2]);
    std::string flags;
    for (const auto& f : m.flags) flags += (flags.empty() ? "" : "; ") + f;
    if (std::isfinite(m.cosine)) std::snprintf(cosine, sizeof(cosine), "%.3f", m.cosine);
    if (std::isfinite(m.ratio)) std::snprintf(ratio, sizeof(ratio), "%.2f", m.ratio);
    if (probes[i].axis >= 0 && m.steady.valid()) {
      std::snprintf(steady, sizeof(steady), "%.1f", 1000 * m.steady.along);
      std::snprintf(sratio, sizeof(sratio), "%.2f", m.steady.along / m.commanded);
      std::snprintf(span, sizeof(span), "%d-%d", m.steady.first, m.steady.last);
    }
    if (!flags.empty()) flags = "  " + flags;
    std::printf("%-8s %-20s %5.1f %6s %5.1f %5s %6s %5s %6s %+6.1f %+6.1f%s\n",
                probes[i].name.c_str(), vec, 1000 * m.norm, cosine, 1000 * m.drift, ratio, steady,
                sratio, span, 1000 * m.finger_delta, 1000 * (m.finger_delta - m.finger_baseline),
                flags.c_str());
  }
  std::printf(
      "per step, mm along the command (gripper probes: finger width change); limited by "
      "c clip, t table, o object, r reach\n");
  for (size_t i = 0; i < probes.size(); ++i) {
    std::string series = StepSeriesText(ms[i].steps, probes[i].axis >= 0);
    series.erase(series.find_last_not_of(' ') + 1);
    std::printf("%-8s%s\n", probes[i].name.c_str(), series.c_str());
  }
  for (const auto& [key, field] : {std::pair{"gripper: ", "gripper"},
                                   {"opening: ", "opens_fingers"},
                                   {"step:    ", "step_size"},
                                   {"steady:  ", "steady_step"},
                                   {"clip:    ", "saturation_above_one"},
                                   {"prep:    ", "preparation"}}) {
    std::printf("%s%s\n", key, summary[field].get<std::string>().c_str());
  }
  std::printf("sweep:   %s\n", summary["sweep"]["text"].get<std::string>().c_str());
}

}  // namespace fetchscope::probe_detail
