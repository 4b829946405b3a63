// fetchscope list-envs [--json]
#include <cstdio>

#include "base/json_util.h"
#include "cli/command.h"
#include "cli/common.h"
#include "src/env_spec.h"

namespace fetchscope::cli {

namespace {

int RunListEnvs(bool json) {
  nlohmann::json rows = nlohmann::json::array();
  for (const EnvSpec& s : AllEnvSpecs()) {
    rows.push_back({{"id", s.id},
                    {"task", TaskName(s.task)},
                    {"reward_type", s.dense ? "dense" : "sparse"},
                    {"model_file", s.model_file},
                    {"max_episode_steps", s.max_episode_steps},
                    {"block_gripper", s.block_gripper},
                    {"has_object", s.has_object}});
  }
  if (json) {
    std::printf("%s\n", DumpJson(rows).c_str());
    return 0;
  }
  std::printf("%-28s %-13s %-7s %s\n", "id", "task", "reward", "gripper");
  for (const EnvSpec& s : AllEnvSpecs()) {
    std::printf("%-28s %-13s %-7s %s\n", s.id.c_str(), TaskName(s.task).c_str(),
                s.dense ? "dense" : "sparse", s.block_gripper ? "blocked" : "actuated");
  }
  std::printf("(auto = FetchReachDense-v4)\n");
  return 0;
}

}  // namespace

Command AddListEnvs(CLI::App& app) {
  auto json = std::make_shared<bool>(false);
  CLI::App* sub = app.add_subcommand("list-envs", "List the 8 Fetch v4 environment ids");
  sub->add_flag("--json", *json, "Print JSON instead of a table");
  return {sub, [json] { return RunListEnvs(*json); }};
}

}  // namespace fetchscope::cli
