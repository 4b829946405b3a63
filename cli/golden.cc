// fetchscope golden check|update: the options of the golden-image regression checks
// (inspect/golden.h), which render the scenes of golden/manifest.json and compare them with (or
// write them as) the committed goldens.
#include "inspect/golden.h"

#include <memory>

#include "cli/command.h"

namespace fetchscope::cli {
namespace {

// GoldenOptions with the option text resolved once the command line is parsed.
struct GoldenCommandOptions {
  GoldenOptions golden;
  std::string backend;  // --backend: auto|egl|osmesa; empty: $MUJOCO_GL, else auto
};

void AddOptions(CLI::App* sub, GoldenCommandOptions* command) {
  GoldenOptions* o = &command->golden;
  sub->add_option("--golden-dir", o->golden_dir,
                  "Folder holding manifest.json and the goldens (default: ./golden; for check, "
                  "where there is none, the goldens installed beside the binary)");
  sub->add_option("--backend", command->backend,
                  "auto (EGL, then OSMesa), egl or osmesa; default: $MUJOCO_GL, else auto");
  sub->add_option("--gpu", o->gpu,
                  "EGL device index (default: $MUJOCO_EGL_DEVICE_ID, else the first)")
      ->check(CLI::Range(0, 4096));
  sub->add_option("--only", o->only, "Only these scenes (repeat, or a comma list)");
  sub->add_option("--genuine-assets", o->genuine_assets,
                  "Gymnasium-Robotics envs/assets folder for the scenes with \"assets\": "
                  "\"genuine\" (default: $FETCHSCOPE_SHARED_DIR/gymnasium-robotics-assets, else "
                  "GOLDEN_DIR/../../shared/gymnasium-robotics-assets); those scenes are skipped "
                  "when it is absent");
  sub->add_flag("--require-genuine", o->require_genuine,
                "Exit 2 instead of skipping the genuine-asset scenes when their assets are absent");
}

}  // namespace

Command AddGolden(CLI::App& app) {
  auto command = std::make_shared<GoldenCommandOptions>();
  GoldenOptions* options = &command->golden;
  CLI::App* golden = app.add_subcommand(
      "golden",
      "Golden-image regression tests: render the scenes of golden/manifest.json and "
      "compare them with the committed images and states (check), or rewrite them (update)");
  golden->require_subcommand(1);
  CLI::App* check = golden->add_subcommand(
      "check",
      "Compare every scene with its goldens; print a table worst first and write a review page "
      "(index.html: golden, actual and diff of each failed scene) under --out. Exit 0 every "
      "scene passes, 1 a scene regressed, 2 the manifest, assets or GL cannot be used");
  AddOptions(check, command.get());
  check->add_option("--out", options->out, "Folder for the review page and the failures' images")
      ->capture_default_str();
  check->add_option("--junit", options->junit,
                    "Write a JUnit XML report here (one testcase per scene)");
  check->add_option("--json", options->json, "Write a JSON report here");
  check
      ->add_option("--tolerance", options->tolerance,
                   "auto (the goldens' own backend and GL renderer: threshold 8 levels, 0.02 %, "
                   "rms 1; else the manifest's cross-backend tolerance, threshold 32, 0.2 %, rms "
                   "2), same, cross, or threshold=N[,max_fraction=F][,max_rms=R] for every scene")
      ->capture_default_str();
  CLI::App* update = golden->add_subcommand(
      "update",
      "Render every scene and write its goldens (NAME.png, NAME_state.json, NAME_meta.json); "
      "say what changed (pixels, state by named quantity) and review it in --out/index.html");
  AddOptions(update, command.get());
  update->add_option("--out", options->out, "Folder for the review page of the changes")
      ->capture_default_str();
  return {golden, [command, check] {
            command->golden.backend = ResolveGlBackend(command->backend);
            return check->parsed() ? GoldenCheck(command->golden) : GoldenUpdate(command->golden);
          }};
}

}  // namespace fetchscope::cli
