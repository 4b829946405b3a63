// probe-actions' per-step series: what each step of a constant-command probe did, which steps
// were limited (and by what), and the steady state. Definitions (docs/guide/action-semantics.md,
// "Per step: the series, the limits, the steady state"):
//  - a step's displacement is grip_pos after it minus grip_pos before it (obs[0:3], m);
//  - "clip": a component of the command lies outside [-1, 1], so the env clipped it (v4 has no
//    other clip: the mocap target is the gripper's position + 0.05 m x action, re-anchored every
//    step, with no workspace range);
//  - "table": the command has a -z component and, after the step, a robot body touches the table;
//  - "object": the step is stalled (below) and a robot body touches the object;
//  - "reach": the step is stalled and neither the table nor the object explains it: the arm
//    itself (stretched out, folded, at a joint limit) no longer lets the grip follow its target.
//    Stalled: from step 2 on, the displacement along the command is under half the commanded
//    0.05 m x min(|a|, 1) AND under 3/4 of the largest earlier step (a gripper that gets going
//    keeps its speed; one that is held back falls from it); on step 1, under a tenth of the
//    command (a free gripper covers a third to 0.6 of it from rest);
//  - steady state: the median of the displacements along the command over steps 2 .. k-1, where
//    k is the first step limited by table, object or reach (a clipped step still counts: it moves
//    by the clipped command); step 1 is left out, as it is the weld's start from rest. None when
//    no such step remains.
#pragma once

#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "render/vec.h"
#include "src/contacts.h"
#include "src/fetch_env.h"

namespace fetchscope {

/// What one step of a probe measured.
struct ProbeStep {
  Vec3 displacement{};           ///< grip_pos after minus before, m
  double along = 0;              ///< displacement along the commanded axis (signed), m; 0 w/o axis
  double finger_width = 0;       ///< gripper_state.right + gripper_state.left after the step, m
  double finger_change = 0;      ///< its change over the step, m
  bool robot_on_table = false;   ///< a robot body touches the table after the step
  bool robot_on_object = false;  ///< a robot body touches the object after the step
  bool clip = false, table = false, object = false, reach = false;  ///< the limits (above)
  bool limited() const { return table || object || reach; }         ///< ends the steady state
};

/// Which robot bodies touch the table and the object in `env`'s current state.
void ReadRobotContacts(const FetchEnv& env, ProbeStep* step);

/// Sets the limit flags of every step of a probe that held `command` constant; `axis` is the
/// commanded axis (0..2) or -1 for a gripper probe (which only gets "clip").
void FlagStepLimits(const std::array<double, 4>& command, int axis, std::vector<ProbeStep>* steps);

/// The steady state (above) of `steps`: the median, m per step, and the steps it spans (1-based,
/// first..last); NaN and 0, 0 when there is none.
struct SteadyState {
  double along = NAN;
  int first = 0, last = 0;
  bool valid() const { return first > 0; }
};
SteadyState FindSteadyState(const std::vector<ProbeStep>& steps);

/// The first step (1-based) with the named limit ("clip", "table", "object", "reach"); 0: none.
int FirstLimited(const std::vector<ProbeStep>& steps, const std::string& limit);

/// The names of step's limits, in the order clip, table, object, reach.
std::vector<std::string> StepLimits(const ProbeStep& step);

/// The per-step series as JSON: one object per step {step, displacement [x, y, z] (m),
/// along_axis (m, null without axis), finger_width, finger_change (m), limits [names]}.
nlohmann::json StepsJson(const std::vector<ProbeStep>& steps, bool has_axis);

/// The series as one table line: along the command (axis probes) or the finger width change
/// (gripper probes) per step, in mm, each limited step followed by its limits' letters
/// (c clip, t table, o object, r reach).
std::string StepSeriesText(const std::vector<ProbeStep>& steps, bool has_axis);

}  // namespace fetchscope
