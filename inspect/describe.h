// describe's D1: the Gymnasium-style spaces of an env, with what every index means, its reward
// formulas and timing, and where it differs from the course chapter, measured (the anatomy
// card's data too). cli/describe.cc prints it.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "src/fetch_env.h"

namespace fetchscope {

/// What the course chapter says where this environment does otherwise
/// (docs/guide/action-semantics.md: "What the environment really does"): the gripper's sign, for
/// every task.
inline constexpr const char* kChapterGripper = "a[3] > 0 closes the gripper";

/// D1: the chapter's layout (action_space and observation_space's three Boxes with one bound per
/// element) plus our labels, formulas, timing, assets and the D4 answers.
nlohmann::json DescribeJson(const FetchEnv& env);

/// Where `env`'s gripper differs from the chapter, one line each, measured by stepping a fresh
/// copy of the env from reset (seed 0) with a[3] = +1 and -1: "a[3] > 0 opens the fingers (the
/// chapter says it closes them): finger width +0.1000 m after 5 steps of a[3]=+1".
std::vector<std::string> GripperVersusChapter(const FetchEnv& env);

}  // namespace fetchscope
