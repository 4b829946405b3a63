#include "render/gpu_select.h"

#include <algorithm>
#include <cerrno>
#include <cstdlib>

#include "base/errors.h"

namespace fetchscope {
namespace {

std::string Trim(const std::string& s) {
  const size_t first = s.find_first_not_of(" \t");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t") - first + 1);
}

// A non-negative integer below 4096, or -1.
int ParseIndex(const std::string& text) {
  if (text.empty() || text.size() > 4 ||
      text.find_first_not_of("0123456789") != std::string::npos) {
    return -1;
  }
  const int value = std::atoi(text.c_str());
  return value < 4096 ? value : -1;
}

std::string JoinIndices(const std::vector<int>& ids) {
  std::string out;
  for (int id : ids) out += (out.empty() ? "" : ", ") + std::to_string(id);
  return out;
}

std::string Plural(const std::vector<int>& ids, const char* one, const char* many) {
  return std::string(ids.size() == 1 ? one : many) + " " + JoinIndices(ids);
}

// "3" or "3, 4" -> {3, 4}; empty on any malformed or repeated item.
std::vector<int> ParseIndexList(const std::string& text) {
  std::vector<int> ids;
  size_t start = 0;
  while (true) {
    const size_t comma = text.find(',', start);
    const int id = ParseIndex(
        Trim(text.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
    if (id < 0 || std::find(ids.begin(), ids.end(), id) != ids.end()) return {};
    ids.push_back(id);
    if (comma == std::string::npos) return ids;
    start = comma + 1;
  }
}

// The devices that report a CUDA ordinal, for messages: "0 (EGL 1), 1 (EGL 0)".
std::string CudaInventory(const EglDeviceList& list) {
  std::vector<const EglDevice*> cuda;
  for (const EglDevice& d : list.devices) {
    if (d.cuda_id >= 0) cuda.push_back(&d);
  }
  std::sort(cuda.begin(), cuda.end(),
            [](const EglDevice* a, const EglDevice* b) { return a->cuda_id < b->cuda_id; });
  std::string out;
  for (const EglDevice* d : cuda) {
    out += (out.empty() ? "" : ", ") + std::to_string(d->cuda_id) + " (EGL " +
           std::to_string(d->index) + ")";
  }
  return out;
}

}  // namespace

std::string EglDevice::Describe() const {
  std::string details;
  if (cuda_id >= 0) details = "CUDA " + std::to_string(cuda_id);
  if (!drm_node.empty()) details += (details.empty() ? "" : ", ") + drm_node;
  if (software) details += (details.empty() ? "" : ", ") + std::string("software");
  return "EGL device " + std::to_string(index) + (details.empty() ? "" : " (" + details + ")");
}

GpuSpec ParseGpuSpec(const std::string& text, const std::string& source) {
  GpuSpec spec;
  spec.text = Trim(text);
  spec.source = source;
  if (spec.text.empty() || spec.text == "auto") {
    spec.kind = GpuSpec::Kind::kAuto;
    return spec;
  }
  if (spec.text == "all") {
    spec.kind = GpuSpec::Kind::kAll;
    return spec;
  }
  const bool cuda = spec.text.rfind("cuda:", 0) == 0;
  spec.kind = cuda ? GpuSpec::Kind::kCuda : GpuSpec::Kind::kEgl;
  spec.ids = ParseIndexList(cuda ? spec.text.substr(5) : spec.text);
  if (spec.ids.empty()) {
    throw UsageError(source + " '" + text + "' is not valid; accepted: " + kGpuForms +
                     ", each device once");
  }
  return spec;
}

GpuSpec EffectiveGpuSpec(const std::string& flag, const EnvLookup& env) {
  const EnvLookup get = env ? env : [](const char* name) { return std::getenv(name); };
  if (!Trim(flag).empty()) return ParseGpuSpec(flag, "--gpu");
  const char* egl_id = get("MUJOCO_EGL_DEVICE_ID");
  if (egl_id && *egl_id) {
    const int id = ParseIndex(Trim(egl_id));
    if (id < 0) {
      throw UsageError(std::string("MUJOCO_EGL_DEVICE_ID '") + egl_id +
                       "' is not a device index; accepted: an integer >= 0 (EGL numbering)");
    }
    GpuSpec spec;
    spec.kind = GpuSpec::Kind::kEgl;
    spec.ids = {id};
    spec.text = Trim(egl_id);
    spec.source = "MUJOCO_EGL_DEVICE_ID";
    return spec;
  }
  if (const char* visible = get("CUDA_VISIBLE_DEVICES")) {
    GpuSpec spec;
    spec.kind = GpuSpec::Kind::kCuda;
    spec.ids = {0};
    spec.text = std::string("cuda:0 (CUDA_VISIBLE_DEVICES=") + visible + ")";
    spec.source = "CUDA_VISIBLE_DEVICES";
    spec.soft = true;
    return spec;
  }
  return GpuSpec{};
}

GpuChoice ChooseGpus(const GpuSpec& spec, const EglDeviceList& list) {
  using Kind = GpuSpec::Kind;
  GpuChoice choice;
  const std::string named =
      spec.source == "CUDA_VISIBLE_DEVICES" ? spec.text : spec.source + " " + spec.text;
  if (spec.kind == Kind::kAuto) {
    choice.reason = "auto";
    return choice;
  }
  const std::string no_devices = list.enumerable ? "it lists no devices" : list.why_not;
  if (!list.enumerable || list.devices.empty()) {
    if (spec.soft) {
      choice.reason = "auto (" + named + ", but this EGL lists no devices)";
      return choice;
    }
    throw RunError("egl: " + named + " asks for an EGL device, but this EGL enumerates none (" +
                   no_devices + ")");
  }
  const int count = static_cast<int>(list.devices.size());
  switch (spec.kind) {
    case Kind::kEgl:
      for (int id : spec.ids) {
        if (id >= count) {
          throw UsageError(spec.source + " " + std::to_string(id) +
                           " is out of range; accepted: 0.." + std::to_string(count - 1) +
                           " (EGL devices on this machine: " + std::to_string(count) + ")");
        }
      }
      choice.devices = spec.ids;
      break;
    case Kind::kAll: {
      for (const EglDevice& d : list.devices) {
        if (!d.software) choice.devices.push_back(d.index);
      }
      if (choice.devices.empty()) {  // a machine with only software devices renders on those
        for (const EglDevice& d : list.devices) choice.devices.push_back(d.index);
      }
      break;
    }
    case Kind::kCuda: {
      const std::string inventory = CudaInventory(list);
      if (inventory.empty()) {
        if (spec.soft) {
          choice.reason = "auto (" + named + ", but no EGL device reports a CUDA ordinal)";
          return choice;
        }
        throw RunError("egl: " + named +
                       ": no EGL device reports a CUDA ordinal (EGL_NV_device_cuda: NVIDIA's "
                       "EGL only); name an EGL index instead (fetchscope list-gpus shows them)");
      }
      for (int id : spec.ids) {
        auto it = std::find_if(list.devices.begin(), list.devices.end(),
                               [id](const EglDevice& d) { return d.cuda_id == id; });
        if (it == list.devices.end()) {
          if (spec.soft) {
            choice.reason = "auto (" + named + ", but no EGL device is CUDA " + std::to_string(id) +
                            "; CUDA ordinals: " + inventory + ")";
            choice.devices.clear();
            return choice;
          }
          throw UsageError(spec.source + " cuda:" + std::to_string(id) +
                           " is not a CUDA device here; accepted CUDA ordinals: " + inventory);
        }
        choice.devices.push_back(it->index);
      }
      break;
    }
    case Kind::kAuto:
      break;
  }
  choice.reason = named + " = " + Plural(choice.devices, "EGL device", "EGL devices");
  return choice;
}

}  // namespace fetchscope
