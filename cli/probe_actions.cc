// fetchscope probe-actions: measures what each action component really does (the probes and
// their analysis: inspect/probe.h) and prints the table; --json-out writes the report, --out
// writes it with a contact sheet of the first and last frame of every probe.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "base/atomic_file.h"
#include "base/errors.h"
#include "cli/command.h"
#include "cli/common.h"
#include "cli/view_options.h"
#include "encode/contact_sheet.h"
#include "encode/png_io.h"
#include "inspect/grasp_probe.h"
#include "inspect/probe.h"
#include "render/renderer.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/fetch_env.h"

namespace fetchscope::cli {
namespace {

namespace fs = std::filesystem;

struct ProbeOptions {
  EnvOptions env;
  ViewOptions view;
  int steps = 10;
  std::string magnitudes = "0.25,0.5,1,2";
  std::string sweep_axis = "auto";
  std::string out;
  std::string json_out;
};

int RunProbeActions(const ProbeOptions& o) {
  if (o.steps < 1 || o.steps > 50) {
    throw UsageError("--steps " + std::to_string(o.steps) +
                     " is out of range: use 1 to 50 (the episode limit)");
  }
  const std::vector<double> magnitudes = ParseProbeMagnitudes(o.magnitudes);
  const std::optional<int> sweep_axis = ParseSweepAxis(o.sweep_axis);
  const EnvSpec& spec = FindEnvSpec(o.env.env_id);
  const uint64_t seed = ParseSeed(o.env.seed);
  ParseOverlays(o.view.overlay);  // reject a bad --overlay before any work
  FetchEnv env(spec, ResolveAssets(o.env.assets));

  // Rendering only for the sheet, i.e. with --out; it reads the state and never steps it.
  std::unique_ptr<GlContext> gl;
  std::optional<Renderer> renderer;
  if (!o.out.empty()) {
    const ViewSetup view = ResolveView(o.view, env.model());
    CreateOutputFolder(o.out);
    gl = CreateViewContext(view.backend, ResolveGpuChoice(view));
    renderer.emplace(*gl, env.model(), view.render);
  }

  ProbeResult result =
      ProbeActions(env, seed, o.steps, magnitudes, sweep_axis, renderer ? &*renderer : nullptr);
  nlohmann::json& report = result.report;
  // the grasp: after a close from above the object, which fingers touch it and does it lift
  report["grasp"] = GraspProbe(env, seed, renderer ? &*renderer : nullptr, &result.tiles);
  std::printf("grasp: %s\n",
              report["grasp"].value("answer", report["grasp"].value("why", "")).c_str());
  report["versions"] = VersionsJson();
  if (renderer) {
    char title[160];
    std::snprintf(title, sizeof(title), "probe-actions %s seed %llu, %d steps", spec.id.c_str(),
                  static_cast<unsigned long long>(seed), o.steps);
    const SheetImage sheet =
        MakeContactSheet(title, result.tiles, std::clamp(o.view.width, 16, 4096),
                         ProbeSheetColumns(result.tiles.size()));
    const std::string sheet_path = (fs::path(o.out) / "probe_actions_sheet.png").string();
    report["sheet"] = "probe_actions_sheet.png";
    WritePng(sheet_path, sheet.width, sheet.height, 3, 8, sheet.rgb.data());
    const std::string json_path = (fs::path(o.out) / "probe_actions.json").string();
    WriteJson(json_path, report);
    std::printf("wrote %s\nwrote %s\n", sheet_path.c_str(), json_path.c_str());
  }
  if (!o.json_out.empty()) {
    const std::string path = JsonOutPath(o.json_out, "probe_actions");
    WriteJson(path, report);
    std::printf("wrote %s\n", path.c_str());
  }
  return 0;
}

}  // namespace

Command AddProbeActions(CLI::App& app) {
  auto o = std::make_shared<ProbeOptions>();
  // A closer view than Gymnasium's, as the probes move the gripper centimetres, in frames big
  // enough to show the fingers open and shut (at 240 px they were a few pixels).
  o->view.width = 480;
  o->view.height = 480;
  o->view.overlay = "action,trail";
  o->view.camera = "free:lookat=1.3,0.75,0.5,distance=1.1,azimuth=150,elevation=-25";
  CLI::App* sub = app.add_subcommand(
      "probe-actions",
      "Measure what each action component does: per-axis, gripper and magnitude probes from "
      "the same reset -> table, JSON report, contact sheet");
  AddEnvOptions(sub, &o->env);
  AddViewOptions(sub, &o->view);
  sub->add_option("--steps", o->steps, "Steps per probe, 1 to 50")->capture_default_str();
  sub->add_option("--magnitudes", o->magnitudes,
                  "Comma list of positive magnitudes for the sweep (<axis>@M probes, e.g. +y@0.5)")
      ->capture_default_str();
  sub->add_option("--sweep-axis", o->sweep_axis,
                  "The sweep's axis: +x, -x, +y, -y, +z, -z, or auto (the axis probe that went the "
                  "most steps before reach, table or object limited it)")
      ->capture_default_str();
  sub->add_option("--out", o->out,
                  "Output folder: probe_actions.json and probe_actions_sheet.png (none: no files "
                  "but --json-out)");
  sub->add_option("--json-out", o->json_out,
                  "Write the report to P (if it ends in .json) or P_probe_actions.json");
  return {sub, [o] { return RunProbeActions(*o); }};
}

}  // namespace fetchscope::cli
