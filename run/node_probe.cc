#include "run/node_probe.h"

#include <optional>

#include "base/errors.h"
#include "base/process.h"
#include "render/gl_context.h"

namespace fetchscope {
namespace {

// True when resolving `view`'s GPU request touches EGL devices at all.
bool NamesDevices(const ViewSetup& view) { return view.gpu.kind != GpuSpec::Kind::kAuto; }

// Makes a context on every chosen device; --gpu all keeps those that work.
std::string TestDevices(const ViewSetup& view, GpuChoice* choice) {
  if (choice->devices.empty()) return "";
  const bool all = view.gpu.kind == GpuSpec::Kind::kAll;
  std::vector<int> working;
  std::string warnings;
  for (int device : choice->devices) {
    try {
      CreateGlContext(GlBackend::kEgl, device);
      working.push_back(device);
    } catch (const RunError& e) {
      if (!all) throw RunError(choice->reason + ": " + e.what());
      warnings += std::string(warnings.empty() ? "" : "; ") + "EGL device " +
                  std::to_string(device) + " skipped: " + e.what();
    }
  }
  if (working.empty()) throw RunError("--gpu all: no EGL device initialises (" + warnings + ")");
  if (working.size() != choice->devices.size()) {
    std::string kept;
    for (int d : working) kept += (kept.empty() ? "" : ", ") + std::to_string(d);
    choice->reason += " (using " + kept + ")";
  }
  choice->devices = working;
  return warnings;
}

}  // namespace

nlohmann::json RunInChild(const std::function<nlohmann::json()>& body) {
  ChildProcess child = ChildProcess::Fork([&body](LineChannel& parent) {
    nlohmann::json answer;
    try {
      answer = {{"ok", body()}};
    } catch (const UsageError& e) {
      answer = {{"error", e.what()}, {"usage", true}};
    } catch (const std::exception& e) {
      answer = {{"error", e.what()}, {"usage", false}};
    }
    parent.Send(answer);
    return 0;
  });
  child.channel().CloseOutput();
  std::optional<nlohmann::json> answer;
  try {
    answer = child.channel().Receive();  // nullopt when it died before a whole line
  } catch (const nlohmann::json::exception&) {
  }
  const ChildExit status = child.Wait();
  if (status.signal) {
    throw RunError("the device probe died of signal " + std::to_string(status.signal) +
                   " (a broken GL or CUDA driver?)");
  }
  if (!answer || !answer->is_object()) throw RunError("the device probe answered nothing");
  if (answer->contains("error")) {
    const std::string message = answer->at("error");
    if (answer->value("usage", false)) throw UsageError(message);
    throw RunError(message);
  }
  return answer->at("ok");
}

NodeProbe ProbeNode(const ViewSetup& view, const VideoOptions* video) {
  const bool devices = NamesDevices(view);
  const bool nvenc = video && video->codec != "libx264" && NvidiaDevicePresent();
  auto probe = [&]() -> nlohmann::json {
    nlohmann::json out;
    if (devices) {
      GpuChoice choice = ResolveGpuChoice(view);
      const std::string warnings = TestDevices(view, &choice);
      out["gpu"] = {{"devices", choice.devices}, {"reason", choice.reason}, {"warnings", warnings}};
    }
    if (video) {
      const VideoCodecDecision decision = DecideVideoCodec(*video);
      out["codec"] = {{"codec", decision.codec}, {"reason", decision.reason}};
    }
    return out;
  };
  // Only the driver-loading work needs a child; the rest answers here.
  const nlohmann::json answer = devices || nvenc ? RunInChild(probe) : probe();
  NodeProbe node;
  node.gpu.reason = "auto";
  if (answer.contains("gpu")) {
    node.gpu.devices = answer["gpu"]["devices"].get<std::vector<int>>();
    node.gpu.reason = answer["gpu"]["reason"];
    node.warnings = answer["gpu"]["warnings"];
  }
  if (answer.contains("codec")) {
    node.codec.codec = answer["codec"]["codec"];
    node.codec.reason = answer["codec"]["reason"];
  }
  return node;
}

}  // namespace fetchscope
