// fetchscope describe: Gymnasium-style spaces plus what every index means.
#include "inspect/describe.h"

#include <cstdio>

#include "base/json_util.h"
#include "cli/chapter.h"
#include "cli/command.h"
#include "cli/common.h"
#include "cli/resolve.h"
#include "src/fetch_env.h"

namespace fetchscope::cli {

int RunDescribe(const DescribeOptions& o) {
  const ResolvedEnv env = ResolveEnv(o.env, /*with_seed=*/false);
  const std::string path = JsonOutPath(o.json_out, "describe");
  CheckJsonOutReplaces(path, {{"env_id", env.spec->id}}, o.overwrite);
  FetchEnv fetch(*env.spec, env.assets);
  const nlohmann::json j = DescribeJson(fetch);
  // the differences are said on a line each either way: on stdout beside "wrote", on stderr
  // when stdout carries the JSON (which holds them too, under "chapter_differences")
  FILE* notes = stdout;
  if (o.json_out.empty()) {
    std::printf("%s\n", DumpJson(j).c_str());
    notes = stderr;
  } else {
    WriteJson(path, j);
    std::printf("wrote %s\n", path.c_str());
  }
  for (const auto& line : j["chapter_differences"]) {
    std::fprintf(notes, "differs from the chapter: %s\n", line.get<std::string>().c_str());
  }
  return 0;
}

Command AddDescribe(CLI::App& app) {
  auto o = std::make_shared<DescribeOptions>();
  CLI::App* sub = app.add_subcommand(
      "describe", "Observation/action schema with a label per index, reward formulas, timing");
  AddEnvOptions(sub, &o->env, false);
  sub->add_option("--json-out", o->json_out,
                  "Write P (if it ends in .json), P/describe.json if P ends in /, else "
                  "P_describe.json; without it the JSON goes to stdout. Where the env differs "
                  "from the course chapter, a line says so with the measurement that decides it");
  sub->add_flag("--overwrite", o->overwrite, kJsonOverwriteHelp);
  return {sub, [o] { return RunDescribe(*o); }};
}

}  // namespace fetchscope::cli
