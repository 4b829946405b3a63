#include "inspect/probe_steps.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "base/json_util.h"
#include "inspect/probe.h"

namespace fetchscope {
namespace {

// Thresholds of "stalled" (probe_steps.h), as fractions of the commanded displacement or of the
// largest earlier step.
constexpr double kStallOfCommand = 0.5;
constexpr double kStallOfBest = 0.75;
constexpr double kStallFirstStep = 0.1;

}  // namespace

void ReadRobotContacts(const FetchEnv& env, ProbeStep* step) {
  const mjModel* m = env.model();
  const mjData* d = env.data();
  const int base = mj_name2id(m, mjOBJ_BODY, "robot0:base_link");
  const int table = env.contact_bodies().table;
  const int object = env.contact_bodies().object;
  if (base < 0) return;
  const int robot_root = m->body_rootid[base];
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& c = d->contact[i];
    if (c.efc_address < 0) continue;  // excluded from the solver: not touching
    const int b1 = m->geom_bodyid[c.geom1], b2 = m->geom_bodyid[c.geom2];
    const bool robot1 = m->body_rootid[b1] == robot_root, robot2 = m->body_rootid[b2] == robot_root;
    if (robot1 == robot2) continue;  // not robot against something else
    const int other = robot1 ? b2 : b1;
    if (table >= 0 && other == table) step->robot_on_table = true;
    if (object >= 0 && other == object) step->robot_on_object = true;
  }
}

void FlagStepLimits(const std::array<double, 4>& command, int axis, std::vector<ProbeStep>* steps) {
  bool clipped = false;
  for (double a : command) clipped = clipped || std::fabs(a) > 1;
  const double commanded =
      axis >= 0 ? kProbeMetresPerUnit * std::min(std::fabs(command[axis]), 1.0) : 0;
  double best = 0;
  for (size_t t = 0; t < steps->size(); ++t) {
    ProbeStep& s = (*steps)[t];
    s.clip = clipped;
    if (axis < 0) continue;
    s.table = command[2] < 0 && s.robot_on_table;
    const bool stalled =
        t == 0 ? s.along < kStallFirstStep * commanded
               : s.along < kStallOfCommand * commanded && s.along < kStallOfBest * best;
    s.object = stalled && !s.table && s.robot_on_object;
    s.reach = stalled && !s.table && !s.object;
    best = std::max(best, s.along);
  }
}

SteadyState FindSteadyState(const std::vector<ProbeStep>& steps) {
  std::vector<double> values;
  SteadyState st;
  for (size_t t = 1; t < steps.size() && !steps[t].limited(); ++t) {
    if (steps[0].limited()) break;
    values.push_back(steps[t].along);
  }
  if (values.empty()) return st;
  st.first = 2;
  st.last = static_cast<int>(values.size()) + 1;
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  st.along = n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
  return st;
}

int FirstLimited(const std::vector<ProbeStep>& steps, const std::string& limit) {
  for (size_t t = 0; t < steps.size(); ++t) {
    const std::vector<std::string> names = StepLimits(steps[t]);
    if (std::find(names.begin(), names.end(), limit) != names.end()) return static_cast<int>(t) + 1;
  }
  return 0;
}

std::vector<std::string> StepLimits(const ProbeStep& step) {
  std::vector<std::string> names;
  if (step.clip) names.push_back("clip");
  if (step.table) names.push_back("table");
  if (step.object) names.push_back("object");
  if (step.reach) names.push_back("reach");
  return names;
}

nlohmann::json StepsJson(const std::vector<ProbeStep>& steps, bool has_axis) {
  nlohmann::json out = nlohmann::json::array();
  for (size_t t = 0; t < steps.size(); ++t) {
    const ProbeStep& s = steps[t];
    out.push_back({{"step", t + 1},
                   {"displacement", JsonVector(s.displacement.data(), 3)},
                   {"along_axis", has_axis ? JsonDouble(s.along) : nlohmann::json(nullptr)},
                   {"finger_width", JsonDouble(s.finger_width)},
                   {"finger_change", JsonDouble(s.finger_change)},
                   {"limits", StepLimits(s)}});
  }
  return out;
}

std::string StepSeriesText(const std::vector<ProbeStep>& steps, bool has_axis) {
  std::string text;
  for (const ProbeStep& s : steps) {
    std::string letters;
    for (const std::string& limit : StepLimits(s)) letters += limit[0];
    char cell[32];
    std::snprintf(cell, sizeof(cell), " %6.1f%-2s", 1000 * (has_axis ? s.along : s.finger_change),
                  letters.c_str());
    text += cell;
  }
  return text;
}

}  // namespace fetchscope
