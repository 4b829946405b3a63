// fetchscope render: one frame (after reset, or after --steps K of a policy) to PNG;
// fetchscope list-cameras: the cameras a model names.
#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "cli/common.h"
#include "cli/episode_scheduler.h"
#include "cli/render_common.h"
#include "render/png_io.h"
#include "render/renderer.h"
#include "src/errors.h"

namespace fetchscope::cli {
namespace {

// frame.png + "depth" -> frame_depth.png
std::string LayerPath(const std::string& path, const std::string& layer) {
  std::filesystem::path p(path);
  return (p.parent_path() / (p.stem().string() + "_" + layer + p.extension().string())).string();
}

// -o frame.png -> frame_segmentation_legend.json, whether the segmentation layer went to
// frame_segmentation.png (beside other layers) or to frame.png (alone)
std::string LegendPath(const std::string& output) {
  std::filesystem::path p(output);
  return (p.parent_path() / (p.stem().string() + "_segmentation_legend.json")).string();
}

nlohmann::json SegmentationLegendJson(const std::vector<SegmentObject>& objects) {
  nlohmann::json list = nlohmann::json::array();
  for (const SegmentObject& o : objects) list.push_back(SegmentObjectJson(o));
  return {{"background", "#000000"},
          {"note",
           "one colour per body (all its geoms) or site; fixed palette, the same in every frame"},
          {"objects", list}};
}

}  // namespace

void RegisterRender(CLI::App& app) {
  auto env = std::make_shared<EnvOptions>();
  auto view = std::make_shared<ViewOptions>();
  auto steps = std::make_shared<int>(0);
  auto policy_spec = std::make_shared<std::string>("random");
  auto layers = std::make_shared<std::string>("rgb");
  auto output = std::make_shared<std::string>();
  auto verbose = std::make_shared<bool>(false);
  CLI::App* sub =
      app.add_subcommand("render", "Render one frame to PNG (after reset, or after --steps K)");
  AddEnvOptions(sub, env.get());
  AddViewOptions(sub, view.get());
  sub->add_option("--steps", *steps, "Steps of --policy to take before the frame")
      ->capture_default_str()
      ->check(CLI::Range(0, 50));
  sub->add_option("--policy", *policy_spec, kPolicyHelp)->capture_default_str();
  sub->add_option("--layers", *layers,
                  "Comma list of rgb, depth (16-bit PNG, millimetres), segmentation (a fixed, "
                  "distinct colour per body or site, black background, with a legend JSON "
                  "NAME_segmentation_legend.json naming each colour's body and geoms). With -o "
                  "NAME.png, NAME.png holds rgb if listed, else depth, else segmentation; the "
                  "other layers go to NAME_depth.png and NAME_segmentation.png")
      ->capture_default_str();
  sub->add_option("-o,--output", *output, "Output PNG")->required();
  sub->add_flag("-v,--verbose", *verbose,
                "Print the GL vendor, renderer and version, and the MSAA samples used and why");
  sub->callback([=]() {
    const std::vector<Layer> wanted = ParseLayers(*layers);
    auto want = [&](Layer l) { return std::find(wanted.begin(), wanted.end(), l) != wanted.end(); };
    const bool want_rgb = want(Layer::kRgb), want_depth = want(Layer::kDepth),
               want_seg = want(Layer::kSegmentation);
    const EnvSpec& spec = FindEnvSpec(env->env_id);
    const uint64_t seed = ParseSeed(env->seed);
    ParseOverlays(view->overlay);  // reject a bad --overlay before any work
    // a trajectory JSON (replay:episode_003.json) renders its first episode, under its own
    // index and so from its own reset; any other policy plays episode 0
    const std::vector<int> replayed =
        ReplayedEpisodes(*policy_spec, 0, spec.id, seed, /*quiet=*/false)
            .value_or(std::vector<int>{0});
    const int k = replayed.front();
    PolicyContext context;
    context.seed = seed;
    context.steps_per_episode = *steps;
    context.episodes = k + 1;
    context.episode_indices = {k};
    EpisodeSequence sequence(std::make_unique<FetchEnv>(spec, ResolveAssets(env->assets)),
                             MakePolicy(*policy_spec, spec, context), seed, *steps);
    FetchEnv& fetch = sequence.env();
    const RenderOptions options = MakeRenderOptions(*view, fetch.model());
    const EpisodeRecord episode = sequence.Play(k);
    auto gl = CreateViewContext(*view, ResolveGpuChoice(*view));
    Renderer renderer(*gl, fetch.model(), options);
    if (*verbose) {
      const GlInfo& i = gl->info();
      std::fprintf(stderr, "GL: backend %s (%s), vendor %s, renderer %s, version %s\n",
                   i.backend.c_str(), i.device.c_str(), i.vendor.c_str(), i.renderer.c_str(),
                   i.version.c_str());
      std::fprintf(stderr, "GPU: %s\n", gl->selection().c_str());
      std::fprintf(stderr, "MSAA: %d samples (%s)\n", renderer.msaa_samples(),
                   renderer.msaa_reason().c_str());
    }
    const FrameInfo info = MakeFrameInfo(fetch, episode.steps.back());
    if (want_rgb) {
      std::vector<uint8_t> rgb(static_cast<size_t>(renderer.width()) * renderer.height() * 3);
      renderer.Render(fetch.data(), info, rgb.data());
      WritePng(*output, renderer.width(), renderer.height(), 3, 8, rgb.data());
      std::printf("wrote %s\n", output->c_str());
    }
    std::vector<uint8_t> layer;
    if (want_depth) {
      renderer.RenderLayer(fetch.data(), info, Layer::kDepth, &layer);
      const std::string path = want_rgb ? LayerPath(*output, "depth") : *output;
      WritePng(path, renderer.width(), renderer.height(), 1, 16, layer.data());
      std::printf("wrote %s (depth, 16-bit, millimetres)\n", path.c_str());
    }
    if (want_seg) {
      renderer.RenderLayer(fetch.data(), info, Layer::kSegmentation, &layer);
      const std::string path =
          (want_rgb || want_depth) ? LayerPath(*output, "segmentation") : *output;
      WritePng(path, renderer.width(), renderer.height(), 3, 8, layer.data());
      const std::string legend = LegendPath(*output);
      WriteJson(legend, SegmentationLegendJson(renderer.segmentation_legend()));
      std::printf("wrote %s (segmentation) and %s (its colours)\n", path.c_str(), legend.c_str());
    }
  });
}

void RegisterListCameras(CLI::App& app) {
  auto env = std::make_shared<EnvOptions>();
  CLI::App* sub =
      app.add_subcommand("list-cameras", "List the cameras --camera accepts for a model");
  AddEnvOptions(sub, env.get(), false);
  sub->callback([env]() {
    const EnvSpec& spec = FindEnvSpec(env->env_id);
    FetchEnv fetch(spec, ResolveAssets(env->assets));
    const mjModel* m = fetch.model();
    std::printf(
        "default   Gymnasium's free camera: distance 2.5, azimuth 132, elevation -14, lookat 1.3 "
        "0.75 0.55\n");
    std::printf("track     follows robot0:gripper_link\n");
    std::printf("free:...  free:lookat=x,y,z,distance=d,azimuth=a,elevation=e (any subset)\n");
    for (int i = 0; i < m->ncam; ++i) {
      std::printf("%-26s model camera %d (body %s)\n", mj_id2name(m, mjOBJ_CAMERA, i), i,
                  mj_id2name(m, mjOBJ_BODY, m->cam_bodyid[i]));
    }
  });
}

}  // namespace fetchscope::cli
