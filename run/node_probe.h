// What a run needs to know about the node before it starts workers: which EGL devices it
// renders on and which video encoder it uses. Anything that loads NVIDIA's driver or CUDA
// (EGL device enumeration, a test NVENC session) runs in a short-lived child process, so that
// the parent forks its workers from a process that never touched the GPU.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "encode/video_writer.h"
#include "render/view.h"

namespace fetchscope {

/// The node facts a run decides once, in the parent.
struct NodeProbe {
  GpuChoice gpu;             ///< the EGL devices workers render on (empty: auto)
  VideoCodecDecision codec;  ///< the encoder every worker opens
  std::string warnings;      ///< e.g. a device of --gpu all that failed to initialise
};

/// Resolves the GPU request of `view` (view.gpu on view.backend; testing each named device by
/// making a context on it: with --gpu all a failing device is dropped with a warning, otherwise it
/// is an error) and, when `video` is given, the encoder. Throws UsageError/RunError as ChooseGpus,
/// CreateGlContext and DecideVideoCodec do, before anything is written.
NodeProbe ProbeNode(const ViewSetup& view, const VideoOptions* video);

/// Runs `body` in a forked child and returns what it returned. An exception in the child is
/// rethrown here with its message and kind (UsageError or RunError); a child that dies is a
/// RunError naming the signal.
nlohmann::json RunInChild(const std::function<nlohmann::json()>& body);

}  // namespace fetchscope
