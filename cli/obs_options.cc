#include "cli/obs_options.h"

#include <cstdlib>
#include <regex>
#include <set>

#include "base/errors.h"
#include "cli/view_options.h"

namespace fetchscope::cli {

void AddObsOptions(CLI::App* sub, ObsOptions* o) {
  sub->add_option("--obs-camera", o->cameras,
                  "Store this camera's images per step in the dataset, and send them to an "
                  "exec: policy after each line: [NAME=]CAMERA, one --camera value (NAME "
                  "defaults to a model camera's name; needed for default, free: and track "
                  "cameras); repeat for more cameras (docs/guide/datasets.md, \"Pixel "
                  "datasets\"; docs/guide/your-policy.md, \"Images for a vision policy\")")
      ->type_name("[NAME=]CAMERA")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  sub->add_option("--obs-size", o->size, "Pixels of each image, WxH")->capture_default_str();
  sub->add_option("--obs-layers", o->layers,
                  "Layers per camera: a comma list of rgb, depth (float32 metres), "
                  "segmentation (int32 body ids)")
      ->capture_default_str();
  sub->add_option("--obs-overlay", o->overlay,
                  "Overlays drawn into the stored rgb images (as --overlay); none keeps them "
                  "exactly `render --overlay none`'s pixels")
      ->capture_default_str();
}

void AddRobomimicOptions(CLI::App* sub, RobomimicOptions* o) {
  sub->add_option("--robomimic", o->file,
                  "Also write the episodes in robomimic's HDF5 layout to this file (.hdf5): "
                  "data/demo_N with obs, next_obs, actions, rewards, dones and MuJoCo states "
                  "(docs/guide/datasets.md, \"robomimic\")");
  sub->add_flag(
      "--no-next-obs", o->no_next_obs,
      "--robomimic: leave out next_obs (half the images; robomimic's --exclude-next-obs)");
  sub->add_option("--valid-fraction", o->valid_fraction,
                  "--robomimic: write mask/train and mask/valid, this share of the demos (0 <= F "
                  "< 1) in valid, spread evenly");
}

void AddEpisodeSelectionOptions(CLI::App* sub, EpisodeSelectionOptions* o) {
  sub->add_option("--keep", o->keep,
                  "Episodes the dataset keeps: all, or successful (those whose last step is a "
                  "success; the command says how many were tried, the dataset's metadata "
                  "`selection` lists the kept episodes' run indices)")
      ->capture_default_str();
  sub->add_option("--stop-after-success", o->stop_after_success,
                  "End each episode K steps after its first success (0: at it), complete and "
                  "truncated there; the episodes are otherwise those of the run without it")
      ->check(CLI::Range(0, 1000000));
}

bool KeepSuccessful(const EpisodeSelectionOptions& o, bool has_dataset) {
  if (o.keep != "all" && o.keep != "successful") {
    throw UsageError("--keep '" + o.keep + "': use all or successful");
  }
  if (o.keep == "successful" && !has_dataset) {
    throw UsageError(
        "--keep successful chooses the episodes of a dataset: give --minari ID or "
        "--robomimic FILE.hdf5");
  }
  return o.keep == "successful";
}

void CheckValidFraction(double fraction) {
  if (!(fraction >= 0 && fraction < 1)) {
    throw UsageError("--valid-fraction " + std::to_string(fraction) +
                     ": use a share of the demos from 0 up to (not including) 1, e.g. 0.1");
  }
}

PixelPlan PlanPixels(const ObsSetup& setup, const mjModel* model, bool minari, bool robomimic) {
  PixelPlan plan;
  if (!setup.enabled() && !robomimic) return plan;
  plan.setup = setup;
  plan.layout = MakePixelLayout(setup, model);
  plan.to_dataset = minari || robomimic;  // else the images go to an exec: policy alone
  plan.layout.png_rgb = minari;           // Minari 0.5.3 decodes an image space's steps with PIL
  plan.layout.raw_rgb = robomimic;        // robomimic reads uint8 arrays
  plan.layout.states = robomimic;
  plan.layout.state_size = FlatMujocoStateSize(model);
  return plan;
}

ObsCamera ParseObsCamera(const std::string& value, const mjModel* model) {
  static const std::regex kNamed(R"(^([A-Za-z0-9_][A-Za-z0-9_-]*)=(.*)$)");
  static const std::regex kName(R"(^[A-Za-z0-9_][A-Za-z0-9_-]*$)");
  std::smatch m;
  std::string name, camera = value;
  if (std::regex_match(value, m, kNamed)) {
    name = m[1].str();
    camera = m[2].str();
  }
  const std::string accepted =
      "; use [NAME=]CAMERA with one --camera value, e.g. external_camera_0, "
      "top=free:lookat=1.3,0.75,0.4,distance=1.2,elevation=-90 or grip=track";
  if (camera.empty()) throw UsageError("--obs-camera '" + value + "' names no camera" + accepted);
  std::vector<CameraSpec> specs;
  try {
    specs = ParseCameraList(camera, model);
  } catch (const UsageError& e) {
    throw UsageError("--obs-camera '" + value + "': " + e.what());
  }
  if (specs.size() != 1) {
    throw UsageError("--obs-camera '" + value + "' names " + std::to_string(specs.size()) +
                     " cameras; give one camera per --obs-camera" + accepted);
  }
  ObsCamera c;
  c.spec = specs.front();
  c.text = CameraText(c.spec);
  c.moving = CameraMoves(c.spec, model);
  if (name.empty()) {
    if (c.spec.kind != CameraSpec::kNamed) {
      throw UsageError("--obs-camera '" + value + "' needs a NAME= for a " +
                       (c.spec.kind == CameraSpec::kTrack  ? "track"
                        : c.spec.kind == CameraSpec::kFree ? "free"
                                                           : "default") +
                       " camera" + accepted);
    }
    name = c.spec.name;
    if (!std::regex_match(name, kName)) {
      throw UsageError("--obs-camera '" + value +
                       "': the camera's name is not a key (letters, "
                       "digits, '_' and '-'); give one with NAME=" +
                       c.spec.name);
    }
  }
  c.name = name;
  return c;
}

void ParseObsSize(const std::string& text, int* width, int* height) {
  static const std::regex kSize(R"(^([0-9]{1,6})x([0-9]{1,6})$)");
  std::smatch m;
  const auto bad = [&] {
    return UsageError("--obs-size '" + text +
                      "': use WxH with each side from 1 to 4096 pixels, e.g. 128x128");
  };
  if (!std::regex_match(text, m, kSize)) throw bad();
  const long w = std::strtol(m[1].str().c_str(), nullptr, 10);
  const long h = std::strtol(m[2].str().c_str(), nullptr, 10);
  if (w < 1 || h < 1 || w > 4096 || h > 4096) throw bad();
  *width = static_cast<int>(w);
  *height = static_cast<int>(h);
}

ObsSetup ResolveObs(const ObsOptions& o, const mjModel* model, int msaa_samples) {
  ObsSetup setup;
  std::set<std::string> names;
  for (const std::string& value : o.cameras) {
    ObsCamera c = ParseObsCamera(value, model);
    if (!names.insert(c.name).second) {
      throw UsageError("--obs-camera: the name '" + c.name +
                       "' is given twice; give each camera its own NAME=");
    }
    setup.cameras.push_back(std::move(c));
  }
  ParseObsSize(o.size, &setup.width, &setup.height);
  const std::vector<Layer> given = ParseLayers(o.layers, "--obs-layers");
  setup.layers.clear();
  for (Layer l : {Layer::kRgb, Layer::kDepth, Layer::kSegmentation}) {
    if (std::find(given.begin(), given.end(), l) != given.end()) setup.layers.push_back(l);
  }
  try {
    setup.overlays = ParseOverlays(o.overlay);
  } catch (const UsageError& e) {
    throw UsageError(std::string("--obs-overlay: ") + e.what());
  }
  setup.overlay_text = o.overlay;
  setup.msaa_samples = msaa_samples;
  return setup;
}

void CheckObsUse(const CLI::App* sub, const ObsOptions& o, bool has_dataset, bool exec_policy,
                 const RobomimicOptions& robomimic) {
  if (robomimic.file.empty()) {
    for (const char* option : {"--no-next-obs", "--valid-fraction"}) {
      const CLI::Option* given = sub->get_option_no_throw(option);  // serve has no robomimic
      if (given && given->count()) {
        throw UsageError(std::string(option) +
                         " applies to the file of --robomimic; give --robomimic FILE.hdf5");
      }
    }
  }
  CheckValidFraction(robomimic.valid_fraction);
  if (o.cameras.empty()) {
    for (const char* option : {"--obs-size", "--obs-layers", "--obs-overlay"}) {
      if (sub->count(option)) {
        throw UsageError(std::string(option) +
                         " applies to the images of --obs-camera; give --obs-camera [NAME=]CAMERA");
      }
    }
    return;
  }
  if (!has_dataset && !exec_policy && !sub->get_option_no_throw("--minari")) {
    throw UsageError("--obs-camera sends images to an exec: policy here: give --policy exec:CMD");
  }
  if (!has_dataset && !exec_policy) {
    throw UsageError(
        "--obs-camera stores images in a dataset or sends them to an exec: policy: give "
        "--minari ID (or --robomimic FILE.hdf5) to write one, or --policy exec:CMD");
  }
}

}  // namespace fetchscope::cli
