#include "run/node_probe.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "base/errors.h"
#include "base/json_util.h"
#include "render/gl_context.h"

namespace fetchscope::cli {
namespace {

// True when resolving `view`'s GPU request touches EGL devices at all.
bool NamesDevices(const ViewOptions& view) {
  return EffectiveGpuSpec(view.gpu).kind != GpuSpec::Kind::kAuto;
}

// Makes a context on every chosen device; --gpu all keeps those that work.
std::string TestDevices(const ViewOptions& view, GpuChoice* choice) {
  if (choice->devices.empty()) return "";
  const bool all = EffectiveGpuSpec(view.gpu).kind == GpuSpec::Kind::kAll;
  std::vector<int> working;
  std::string warnings;
  for (int device : choice->devices) {
    try {
      CreateGlContext("egl", device);
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
  int pipe_fds[2];
  if (pipe2(pipe_fds, O_CLOEXEC) != 0) {
    throw RunError(std::string("cannot create a pipe: ") + std::strerror(errno));
  }
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = fork();
  if (pid < 0) throw RunError(std::string("cannot fork: ") + std::strerror(errno));
  if (pid == 0) {
    close(pipe_fds[0]);
    nlohmann::json answer;
    try {
      answer = {{"ok", body()}};
    } catch (const UsageError& e) {
      answer = {{"error", e.what()}, {"usage", true}};
    } catch (const std::exception& e) {
      answer = {{"error", e.what()}, {"usage", false}};
    }
    const std::string text = DumpJson(answer, -1);
    size_t done = 0;
    while (done < text.size()) {
      const ssize_t n = write(pipe_fds[1], text.data() + done, text.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      done += static_cast<size_t>(n);
    }
    _exit(0);
  }
  close(pipe_fds[1]);
  std::string text;
  char buffer[4096];
  while (true) {
    const ssize_t n = read(pipe_fds[0], buffer, sizeof(buffer));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    text.append(buffer, static_cast<size_t>(n));
  }
  close(pipe_fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFSIGNALED(status)) {
    throw RunError("the device probe died of signal " + std::to_string(WTERMSIG(status)) +
                   " (a broken GL or CUDA driver?)");
  }
  const nlohmann::json answer = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (answer.is_discarded()) throw RunError("the device probe answered nothing");
  if (answer.contains("error")) {
    const std::string message = answer.at("error");
    if (answer.value("usage", false)) throw UsageError(message);
    throw RunError(message);
  }
  return answer.at("ok");
}

NodeProbe ProbeNode(const ViewOptions& view, const VideoOptions* video) {
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

}  // namespace fetchscope::cli
