#include "encode/av_log.h"

#include <cstdarg>
#include <cstring>
#include <mutex>

extern "C" {
#include <libavutil/error.h>
#include <libavutil/log.h>
}

namespace fetchscope {
namespace {

// FFmpeg logs through a process-wide callback. Ours prints nothing (encoders
// and the muxer are chatty) and keeps the last error line of each thread, so
// a failure can quote FFmpeg's own reason. It must not throw: C calls it.
thread_local char t_last_av_error[512];

void CaptureAvLog(void* context, int level, const char* format, va_list args) noexcept {
  if (level > AV_LOG_ERROR) return;
  char line[sizeof(t_last_av_error)];
  int print_prefix = 0;
  if (av_log_format_line2(context, level, format, args, line, sizeof(line), &print_prefix) < 0) {
    return;
  }
  std::size_t length = std::strlen(line);
  while (length > 0 && (line[length - 1] == '\n' || line[length - 1] == ' ')) line[--length] = '\0';
  if (length > 0) std::memcpy(t_last_av_error, line, length + 1);
}

}  // namespace

void InstallAvLogCapture() {
  static std::once_flag once;
  std::call_once(once, [] { av_log_set_callback(CaptureAvLog); });
}

void ClearLastAvError() { t_last_av_error[0] = '\0'; }

std::string DescribeAvError(int code) {
  if (t_last_av_error[0] != '\0') return t_last_av_error;
  char buffer[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(code, buffer, sizeof(buffer));
  return buffer;
}

}  // namespace fetchscope
