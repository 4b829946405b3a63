// fetchscope list-gpus [--gpu SPEC] [--json]: what this node offers for rendering and encoding:
// the EGL devices (EGL numbering, CUDA ordinals, DRM nodes), what auto, CUDA_VISIBLE_DEVICES
// and --gpu resolve to, and whether NVENC opens. Run it first on a new node or container.
#include <cstdio>
#include <cstdlib>

#include "base/errors.h"
#include "base/json_util.h"
#include "cli/command.h"
#include "cli/common.h"
#include "encode/video_writer.h"
#include "render/gl_context.h"
#include "render/gpu_select.h"

namespace fetchscope::cli {

namespace {

struct ListGpusOptions {
  bool json = false;
  std::string gpu;  ///< a --gpu value to resolve too
};

int RunListGpus(const ListGpusOptions& o) {
  nlohmann::json out;
  EglDeviceList list;
  try {
    list = ListEglDevices();
    out["egl"] = {{"loaded", true},
                  {"client_extensions", list.client_extensions},
                  {"enumerable", list.enumerable},
                  {"why_not", list.why_not}};
  } catch (const RunError& e) {
    out["egl"] = {{"loaded", false}, {"error", e.what()}};
  }
  nlohmann::json devices = nlohmann::json::array();
  for (const EglDevice& d : list.devices) {
    devices.push_back(
        {{"egl_index", d.index},
         {"cuda_id", d.cuda_id < 0 ? nlohmann::json(nullptr) : nlohmann::json(d.cuda_id)},
         {"software", d.software},
         {"drm_node", d.drm_node},
         {"extensions", d.extensions},
         {"description", d.Describe()}});
  }
  out["devices"] = devices;
  const char* visible = std::getenv("CUDA_VISIBLE_DEVICES");
  out["cuda_visible_devices"] = visible ? nlohmann::json(visible) : nlohmann::json(nullptr);
  // what a run would use: the request in effect (flag, else environment) on these devices
  nlohmann::json resolved;
  try {
    const GpuSpec spec = EffectiveGpuSpec(o.gpu);
    const GpuChoice choice = ChooseGpus(spec, list);
    resolved = {
        {"request", spec.kind == GpuSpec::Kind::kAuto ? "auto" : spec.source + " " + spec.text},
        {"devices", choice.devices},
        {"reason", choice.reason}};
  } catch (const std::exception& e) {
    resolved = {{"error", e.what()}};
  }
  out["resolved"] = resolved;
  VideoOptions video;
  try {
    const VideoCodecDecision d = DecideVideoCodec(video);
    out["encoder"] = {{"codec", d.codec}, {"reason", d.reason}};
  } catch (const std::exception& e) {
    out["encoder"] = {{"error", e.what()}};
  }
  if (o.json) {
    std::printf("%s\n", DumpJson(out).c_str());
    return 0;
  }
  if (!out["egl"]["loaded"].get<bool>()) {
    std::printf("EGL: %s\n", out["egl"]["error"].get<std::string>().c_str());
  } else {
    std::printf("EGL client extensions: %s\n", list.client_extensions.c_str());
    std::printf("device enumeration: %s\n",
                list.enumerable ? "yes" : ("no (" + list.why_not + ")").c_str());
  }
  std::printf("%-10s %-6s %-22s %s\n", "EGL index", "CUDA", "DRM node", "kind");
  for (const EglDevice& d : list.devices) {
    std::printf(
        "%-10d %-6s %-22s %s\n", d.index, d.cuda_id < 0 ? "-" : std::to_string(d.cuda_id).c_str(),
        d.drm_node.empty() ? "-" : d.drm_node.c_str(), d.software ? "software" : "hardware");
  }
  if (list.devices.empty()) std::printf("(no devices)\n");
  std::printf("CUDA_VISIBLE_DEVICES: %s\n", visible ? visible : "(unset)");
  if (resolved.contains("error")) {
    std::printf("renders on: error: %s\n", resolved["error"].get<std::string>().c_str());
  } else {
    std::printf("renders on: %s\n", resolved["reason"].get<std::string>().c_str());
  }
  if (out["encoder"].contains("error")) {
    std::printf("encoder: error: %s\n", out["encoder"]["error"].get<std::string>().c_str());
  } else {
    std::printf("encoder (--codec auto): %s (%s)\n",
                out["encoder"]["codec"].get<std::string>().c_str(),
                out["encoder"]["reason"].get<std::string>().c_str());
  }
  return 0;
}

}  // namespace

Command AddListGpus(CLI::App& app) {
  auto o = std::make_shared<ListGpusOptions>();
  CLI::App* sub = app.add_subcommand(
      "list-gpus",
      "List the EGL devices (EGL numbering, CUDA ordinals), what --gpu and CUDA_VISIBLE_DEVICES "
      "resolve to, and whether NVENC is available");
  sub->add_option("--gpu", o->gpu, std::string("Also resolve this --gpu value: ") + kGpuForms);
  sub->add_flag("--json", o->json, "Print JSON instead of text");
  return {sub, [o] { return RunListGpus(*o); }};
}

}  // namespace fetchscope::cli
