// fetchscope report DIR: the run's index.html (inspect/report).
#include "inspect/report.h"

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "cli/command.h"

namespace fetchscope::cli {

Command AddReport(CLI::App& app) {
  auto dir = std::make_shared<std::string>();
  auto quiet = std::make_shared<bool>(false);
  CLI::App* sub = app.add_subcommand(
      "report",
      "Write DIR/index.html for a record run: provenance, sortable episode table, videos, "
      "contact sheets, distance-to-goal plot, histogram of returns, success rate with its 95% "
      "Wilson interval. Self-contained: opens offline from file:// or any static server");
  sub->add_option("DIR", *dir, "Folder of a record run (holding manifest.json)")->required();
  sub->add_flag("-q,--quiet", *quiet, "Do not print the page's path");
  return {sub, [=] {
            const RecordedRun run = ReadRunFolder(*dir);
            const std::filesystem::path page = WriteRunReport(run);
            if (!*quiet) std::printf("report: %s\n", page.string().c_str());
            return 0;
          }};
}

}  // namespace fetchscope::cli
