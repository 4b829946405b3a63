// fetchscope anatomy: the chapter's deliverables in one command (D1 describe, D2 reward check,
// D3 random baseline, the D4 answers) and the anatomy card (inspect/anatomy_card.h): a labelled
// Reach frame and a labelled Push frame that show where each observation slice and each action
// component lives. Below 480 x 360 the card's text would be under 10 px: `--width/--height`
// refuse it.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "base/json_util.h"
#include "cli/chapter.h"
#include "cli/command.h"
#include "cli/common.h"
#include "cli/view_options.h"
#include "inspect/anatomy_card.h"
#include "src/assets.h"
#include "src/env_spec.h"
#include "src/fetch_env.h"

namespace fetchscope::cli {
namespace {

struct AnatomyOptions {
  EnvOptions env;
  std::string out = "results";
  ViewOptions view;  // the card's: width, height (each panel), backend, msaa
  bool no_card = false;
  bool overwrite = false;  // replace D1-D3 files of another env or seed in --out
};

int RunAnatomy(AnatomyOptions o) {
  const EnvSpec& spec = FindEnvSpec(o.env.env_id);  // bad input fails before any file
  const int msaa_samples = ParseMsaa(o.view.msaa);
  const std::string prefix = (std::filesystem::path(o.out) / "ch01").string();
  // all three files are checked before any is written: a refused run leaves --out as it was
  const uint64_t seed = ParseSeed(o.env.seed);
  CheckJsonOutReplaces(JsonOutPath(prefix + "_env", "describe"), {{"env_id", spec.id}},
                       o.overwrite);
  CheckJsonOutReplaces(JsonOutPath(prefix, "reward_check"),
                       {{"task", TaskName(spec.task)}, {"seed", seed}}, o.overwrite);
  CheckJsonOutReplaces(JsonOutPath(prefix, "random_metrics"), {{"env_id", spec.id}, {"seed", seed}},
                       o.overwrite);
  std::printf("D1 (describe, %s)\n", spec.id.c_str());
  DescribeOptions describe;
  describe.env = o.env;
  describe.json_out = prefix + "_env";
  describe.overwrite = o.overwrite;
  RunDescribe(describe);
  std::printf("\nD2 (reward-check)\n");
  RewardCheckOptions check;
  check.env = o.env;
  check.json_out = prefix;
  check.overwrite = o.overwrite;
  const bool pass = RunRewardCheck(check);
  std::printf("\nD3 (random-episodes)\n");
  RandomEpisodesOptions random;
  random.env = o.env;
  random.json_out = prefix;
  random.overwrite = o.overwrite;
  if (const int status = RunRandomEpisodes(random); status != 0) return status;  // interrupted

  std::printf("\nD4 answers (%s)\n", spec.id.c_str());
  FetchEnv fetch(spec, ResolveAssets(o.env.assets));
  const nlohmann::json answers = DescribeJson(fetch)["answers"];
  for (const auto& [key, value] : answers.items()) {
    std::printf("  %-22s %s\n", key.c_str(),
                value.is_string() ? value.get<std::string>().c_str() : DumpJson(value, -1).c_str());
  }
  if (!o.no_card) {
    std::printf("\nanatomy card (FetchReach-v4 and FetchPush-v4)\n");
    AnatomyCardOptions card;
    card.seed = ParseSeed(o.env.seed);
    card.seed_text = o.env.seed;
    card.assets = o.env.assets;
    card.width = o.view.width;
    card.height = o.view.height;
    card.msaa_samples = msaa_samples;
    card.msaa = o.view.msaa;
    const ViewSetup view = ResolveGlView(o.view);
    auto gl = CreateViewContext(view.backend, ResolveGpuChoice(view));
    WriteAnatomyCard(o.out, card, *gl);
  }
  if (!pass) {
    std::printf("\nD2 FAILED: see %s_reward_check.json\n", prefix.c_str());
    return 1;
  }
  return 0;
}

}  // namespace

Command AddAnatomy(CLI::App& app) {
  auto o = std::make_shared<AnatomyOptions>();
  o->view.width = 720;
  o->view.height = 540;
  CLI::App* sub = app.add_subcommand(
      "anatomy",
      "The chapter's deliverables in one go: OUT/ch01_env_describe.json (D1), "
      "OUT/ch01_reward_check.json (D2), OUT/ch01_random_metrics.json (D3), the D4 answers, and "
      "the anatomy card OUT/ch01_anatomy.png (labelled Reach and Push frames) with "
      "OUT/ch01_anatomy_labels.json (each label's text, box and leader line and each marker's "
      "ends, in pixels)");
  AddEnvOptions(sub, &o->env);
  sub->add_option("--out", o->out, "Folder for the files (created if missing)")
      ->capture_default_str();
  // below 480 x 360 the labels would need text under 10 px, too small to read
  sub->add_option("--width", o->view.width,
                  "Width of each of the card's two frames, pixels (480 to 4096; text, lines and "
                  "arrows scale with the frame)")
      ->capture_default_str()
      ->check(CLI::Range(kAnatomyMinPanelWidth, kAnatomyMaxPanelSize));
  sub->add_option("--height", o->view.height, "Height of the card, pixels (360 to 4096)")
      ->capture_default_str()
      ->check(CLI::Range(kAnatomyMinPanelHeight, kAnatomyMaxPanelSize));
  sub->add_option("--backend", o->view.backend,
                  "auto (EGL, then OSMesa), egl or osmesa; default: $MUJOCO_GL, else auto");
  sub->add_option("--msaa", o->view.msaa, "Anti-aliasing samples of the card, as render's")
      ->capture_default_str();
  sub->add_flag("--no-card", o->no_card, "Skip the anatomy card (no rendering, no GL needed)");
  sub->add_flag("--overwrite", o->overwrite,
                "Replace D1-D3 files in --out that hold another env's or seed's results (without "
                "it such files are kept and the run refused; the same env and seed are replaced)");
  return {sub, [o] { return RunAnatomy(*o); }};
}

}  // namespace fetchscope::cli
