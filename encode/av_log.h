// FFmpeg's log, captured: encode/'s FFmpeg users quote FFmpeg's own reason for a failure.
#pragma once

#include <string>

namespace fetchscope {

/// Routes FFmpeg's log into a per-thread "last error" (printing nothing); once per process.
void InstallAvLogCapture();

/// Forgets earlier messages so the next one quoted belongs to this failure.
void ClearLastAvError();

/// FFmpeg's last logged error for this thread when there is one (it says more, e.g. "Cannot load
/// libcuda.so.1"), else the text for `code`.
std::string DescribeAvError(int code);

}  // namespace fetchscope
