// fetchscope render: one frame (after reset, or after --steps K of a policy) to PNG;
// fetchscope list-cameras: the cameras a model names.
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>

#include "base/errors.h"
#include "base/text_table.h"
#include "cli/command.h"
#include "cli/common.h"
#include "cli/look_options.h"
#include "cli/resolve.h"
#include "cli/view_options.h"
#include "encode/png_io.h"
#include "render/camera.h"
#include "render/layers.h"
#include "render/look.h"
#include "render/renderer.h"
#include "run/episode_scheduler.h"
#include "src/policy.h"

namespace fetchscope::cli {
namespace {

nlohmann::json SegmentationLegendJson(const std::vector<SegmentObject>& objects) {
  nlohmann::json list = nlohmann::json::array();
  for (const SegmentObject& o : objects) list.push_back(SegmentObjectJson(o));
  return {{"background", "#000000"},
          {"note",
           "one colour per body (all its geoms) or site; fixed palette, the same in every frame"},
          {"objects", list}};
}

// Throws UsageError unless `output` (render's -o) ends in .png (any case): the image files
// are PNG, and a .jpg or .bmp name would hold PNG data.
void CheckPngOutput(const std::string& option, const std::string& output) {
  std::string ext = std::filesystem::path(output).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".png") return;
  throw UsageError(option + " '" + output +
                   "': render writes PNG images only; accepted: a name ending in .png");
}

}  // namespace

namespace {

struct RenderCommandOptions {
  EnvOptions env;
  ViewOptions view;
  int steps = 0;
  std::string policy_spec = "random";
  std::string layers = "rgb";
  std::string output;
  bool verbose = false;
  LookOptions look;  // --randomize, --randomize-config
};

int RunRender(const RenderCommandOptions& o) {
  CheckPngOutput("-o", o.output);
  const std::vector<Layer> wanted = ParseLayers(o.layers);
  auto want = [&](Layer l) { return std::find(wanted.begin(), wanted.end(), l) != wanted.end(); };
  const bool want_rgb = want(Layer::kRgb), want_depth = want(Layer::kDepth),
             want_seg = want(Layer::kSegmentation);
  ParseOverlays(o.view.overlay);  // reject a bad --overlay before any work
  const LookConfig look_config = ResolveLook(o.look).value_or(LookConfig{});
  EpisodeRequest request;
  request.policy = ParsePolicySpec(o.policy_spec);
  request.steps = o.steps;
  request.past_limit_marks = "in the HUD";
  ResolvedRun run = ResolveRun(o.env, request);
  // a trajectory JSON (replay:episode_003.json) renders its first episode, under its own
  // index and so from its own reset; any other policy plays episode 0
  const int k = run.episodes.front();
  run.policy_context.episodes = k + 1;
  run.policy_context.episode_indices = {k};
  const EnvSpec& spec = *run.env.spec;
  const uint64_t seed = run.env.seed;
  EpisodeSequence sequence(std::make_unique<FetchEnv>(spec, run.env.assets),
                           MakePolicy(request.policy, spec, run.policy_context), seed, o.steps);
  FetchEnv& fetch = sequence.env();
  const ViewSetup view = ResolveView(o.view, fetch.model());
  const EpisodeRecord episode = sequence.Play(k);
  auto gl = CreateViewContext(view.backend, ResolveGpuChoice(view));
  Renderer renderer(*gl, fetch.model(), view.render);
  if (look_config.any()) {  // episode k's draw, as record draws it for its frames
    const LookDraw look = DrawLook(look_config, LookSeed(ResolveLookSeed(o.look).value_or(seed), k),
                                   renderer.camera_keys(), fetch.model());
    renderer.SetLook(&look);
  }
  if (o.verbose) {
    const GlInfo& i = gl->info();
    std::fprintf(stderr, "GL: backend %s (%s), vendor %s, renderer %s, version %s\n",
                 i.backend.c_str(), i.device.c_str(), i.vendor.c_str(), i.renderer.c_str(),
                 i.version.c_str());
    std::fprintf(stderr, "GPU: %s\n", gl->selection().c_str());
    std::fprintf(stderr, "MSAA: %d samples (%s)\n", renderer.msaa_samples(),
                 renderer.msaa_reason().c_str());
  }
  const FrameInfo info = MakeFrameInfo(fetch, episode.steps.back());
  // --overlay trail: the achieved goals of the steps before this frame, as record draws them
  std::vector<std::array<double, 3>> trail;
  for (size_t t = 0; t + 1 < episode.steps.size(); ++t) {
    trail.push_back(episode.steps[t].obs.achieved_goal);
  }
  renderer.SetTrail(trail);
  if (want_rgb) {
    std::vector<uint8_t> rgb(static_cast<size_t>(renderer.width()) * renderer.height() * 3);
    renderer.Render(fetch.data(), info, rgb.data());
    const std::string path = LayerFilePath(o.output, Layer::kRgb, wanted.size());
    WritePng(path, renderer.width(), renderer.height(), 3, 8, rgb.data());
    std::printf("wrote %s\n", path.c_str());
  }
  std::vector<uint8_t> layer;
  if (want_depth) {
    renderer.RenderLayer(fetch.data(), info, Layer::kDepth, &layer);
    const std::string path = LayerFilePath(o.output, Layer::kDepth, wanted.size());
    WritePng(path, renderer.width(), renderer.height(), 1, 16, layer.data());
    std::printf("wrote %s (depth, 16-bit, millimetres)\n", path.c_str());
  }
  if (want_seg) {
    renderer.RenderLayer(fetch.data(), info, Layer::kSegmentation, &layer);
    const std::string path = LayerFilePath(o.output, Layer::kSegmentation, wanted.size());
    WritePng(path, renderer.width(), renderer.height(), 3, 8, layer.data());
    const std::string legend = LegendFilePath(o.output);
    WriteJson(legend, SegmentationLegendJson(renderer.segmentation_legend()));
    std::printf("wrote %s (segmentation) and %s (its colours)\n", path.c_str(), legend.c_str());
  }
  return 0;
}

}  // namespace

Command AddRender(CLI::App& app) {
  auto o = std::make_shared<RenderCommandOptions>();
  CLI::App* sub =
      app.add_subcommand("render", "Render one frame to PNG (after reset, or after --steps K)");
  AddEnvOptions(sub, &o->env);
  AddViewOptions(sub, &o->view);
  sub->add_option("--steps", o->steps,
                  "Steps of --policy to take before the frame, 0..10000 (past the TimeLimit of 50 "
                  "the HUD and stderr say so)")
      ->capture_default_str()
      ->check(CLI::Range(0, kMaxSteps));
  sub->add_option("--policy", o->policy_spec, kPolicyHelp)->capture_default_str();
  sub->add_option("--layers", o->layers,
                  "Comma list of rgb, depth (16-bit PNG, millimetres), segmentation (a fixed, "
                  "distinct colour per body or site, black background, with a legend JSON "
                  "NAME_segmentation_legend.json naming each colour's body and geoms). With -o "
                  "NAME.png and one layer, NAME.png holds it; with several, NAME.png holds rgb "
                  "(when listed) and each other layer goes to NAME_depth.png or "
                  "NAME_segmentation.png, as record names its layer videos. The files written "
                  "are printed")
      ->capture_default_str();
  sub->add_option("-o,--output", o->output,
                  "Output PNG: a name ending in .png (other image formats are refused)")
      ->required();
  AddLookOptions(sub, &o->look);
  sub->add_flag("-v,--verbose", o->verbose,
                "Print the GL vendor, renderer and version, and the MSAA samples used and why");
  return {sub, [o] { return RunRender(*o); }};
}

namespace {

struct ListCamerasOptions {
  EnvOptions env;
};

int RunListCameras(const ListCamerasOptions& o) {
  const ResolvedEnv env = ResolveEnv(o.env, /*with_seed=*/false);
  FetchEnv fetch(*env.spec, env.assets);
  const mjModel* m = fetch.model();
  // columns as wide as their widest name (a model camera's name can be long)
  std::vector<std::vector<std::string>> rows;
  for (const CameraKind& kind : CameraKinds()) {
    rows.push_back({std::string(kind.listed), std::string(kind.summary)});
  }
  auto name = [&](int type, int id) {
    const char* n = mj_id2name(m, type, id);
    return std::string(n ? n : "(unnamed)");
  };
  for (int i = 0; i < m->ncam; ++i) {
    rows.push_back({name(mjOBJ_CAMERA, i), "model camera " + std::to_string(i) + " (body " +
                                               name(mjOBJ_BODY, m->cam_bodyid[i]) + ")"});
  }
  std::fputs(AlignColumns(rows).c_str(), stdout);
  return 0;
}

}  // namespace

Command AddListCameras(CLI::App& app) {
  auto o = std::make_shared<ListCamerasOptions>();
  CLI::App* sub =
      app.add_subcommand("list-cameras", "List the cameras --camera accepts for a model");
  AddEnvOptions(sub, &o->env, false);
  return {sub, [o] { return RunListCameras(*o); }};
}

}  // namespace fetchscope::cli
