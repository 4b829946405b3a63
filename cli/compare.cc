// fetchscope compare RUN_A RUN_B --out DIR: two record runs of the same env and episodes side by
// side (inspect/compare.h), and a summary table on stdout. Exit 0: the same run; 1: different; 2:
// could not compare.
#include "inspect/compare.h"

#include <cmath>
#include <cstdio>
#include <memory>

#include "base/errors.h"
#include "cli/command.h"
#include "cli/common.h"

namespace fetchscope::cli {
namespace {

using nlohmann::json;

int RunCompare(CompareOptions o) {
  o.command_line = CommandLine();
  o.versions = VersionsJson();
  const CompareResult result = CompareRuns(o);
  const json& rows = result.rows;
  const bool same = result.same;
  const int differing = result.differing;
  const std::string html = result.page.string();
  if (!o.quiet) {
    std::printf("compare: A = %s, B = %s\n", o.run_a.c_str(), o.run_b.c_str());
    std::printf("%-8s %-16s %-14s %-12s %-12s %s\n", "episode", "first diverges", "max |dstate|",
                "max |dpixel|", "success A/B", "return A/B");
    for (const json& r : rows) {
      const std::string diverge =
          r["first_divergence_step"].is_null() ? "-" : "step " + r["first_divergence_step"].dump();
      char state[32];
      std::snprintf(state, sizeof(state), "%.3g",
                    r["max_state_difference"].is_number() ? r["max_state_difference"].get<double>()
                                                          : HUGE_VAL);
      const std::string pixel = r["video"].is_null() ? "-" : r["max_pixel_difference"].dump();
      const std::string success = std::string(r["a"]["success"].get<bool>() ? "yes" : "no") + "/" +
                                  (r["b"]["success"].get<bool>() ? "yes" : "no");
      const std::string returns = r["a"]["return"].dump() + "/" + r["b"]["return"].dump();
      std::printf("%-8s %-16s %-14s %-12s %-12s %s\n", r["label"].get<std::string>().c_str(),
                  diverge.c_str(), state, pixel.c_str(), success.c_str(), returns.c_str());
      // --signals contacts in both runs: where the contact sequences part
      const json& contacts = r.value("first_contact_difference", json());
      if (contacts.is_object() && !contacts["step"].is_null()) {
        const auto list = [](const json& keys) {
          std::string text;
          for (const json& k : keys) text += (text.empty() ? "" : ", ") + k.get<std::string>();
          return text.empty() ? std::string("none") : text;
        };
        std::printf("         contacts first differ at step %d: only in A %s; only in B %s\n",
                    contacts["step"].get<int>(), list(contacts["only_a"]).c_str(),
                    list(contacts["only_b"]).c_str());
      }
    }
    std::printf(
        "         (|dstate|: the largest difference of any observation or goal component, in its "
        "unit: m for positions and finger widths, m per step for velocities, rad for angles; "
        "|dpixel|: 0 to 255 per channel)\n");
    std::printf(
        "compare: %s: %d of %zu episode(s) differ (state tolerance %g, pixel tolerance %d) -> %s\n",
        same ? "same" : "different", differing, rows.size(), o.tolerance, o.pixel_tolerance,
        html.c_str());
  }
  return same ? 0 : 1;
}

}  // namespace

Command AddCompare(CLI::App& app) {
  auto o = std::make_shared<CompareOptions>();
  CLI::App* sub = app.add_subcommand(
      "compare",
      "Compare two record runs of the same env, seed and episodes: per episode a video A | B | "
      "per-pixel difference heat map, the first step where the states differ beyond --tolerance "
      "and the state difference over steps; DIR/index.html, DIR/compare.json and a table on "
      "stdout. Exit 0: same run; 1: different; 2: could not compare (bad input)");
  sub->add_option("RUN_A", o->run_a, "Folder of the first record run (holding manifest.json)")
      ->required();
  sub->add_option("RUN_B", o->run_b, "Folder of the second record run")->required();
  sub->add_option("--out", o->out, "Output folder for the page, videos and compare.json")
      ->required();
  sub->add_option("--tolerance", o->tolerance,
                  "Largest |A - B| of any state component (observation, achieved and desired "
                  "goal) at a step that still counts as equal")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--pixel-tolerance", o->pixel_tolerance,
                  "Largest per-channel pixel difference (0..255) that still counts as equal")
      ->capture_default_str()
      ->check(CLI::Range(0, 255));
  sub->add_flag("--states-only", o->states_only,
                "Compare the trajectories only: no videos decoded or written (faster, for CI)");
  sub->add_flag("-q,--quiet", o->quiet, "No table on stdout");
  return {sub, [o] {
            try {
              return RunCompare(*o);
            } catch (const UsageError&) {
              throw;
            } catch (const std::exception& e) {
              // exit 1 means "different": a comparison that could not be made is exit 2
              throw UsageError(e.what());
            }
          }};
}

}  // namespace fetchscope::cli
