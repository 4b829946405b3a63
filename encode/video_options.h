// Checking and naming video options: sizes, fps, codecs, presets, formats, GIF frame counts.
// (VideoOptions itself and the public functions are declared in encode/video_writer.h.)
#pragma once

#include <string>

namespace fetchscope {

/// The index of an x264 preset name (ultrafast 0 .. placebo 9), -1 when unknown.
int PresetIndex(const std::string& preset);

/// The nearest NVENC preset (p1 fastest .. p7 best) for x264 preset `index`.
const char* NvencPresetFor(int index);

/// libvpx's speed settings for VP9 (WebM) at an x264 preset name ("" = the default).
struct Vp9Speed {
  const char* deadline;  ///< "realtime" or "good"
  int cpu_used;          ///< libvpx's cpu-used: higher is faster
};

/// Up to veryfast (the default): libvpx's realtime mode, ultrafast -> cpu-used 8, superfast 7,
/// veryfast 6. "good" even at its fastest (cpu-used 5) took 2x MP4's record time; realtime 6
/// takes about as long as H.264 at 0.4 dB less PSNR and 7% more bytes (BENCHMARKS.md). Slower
/// presets keep "good": faster -> cpu-used 4, medium -> 2, slower and slower -> 0.
Vp9Speed Vp9SpeedFor(const std::string& preset);

/// True when this machine has an NVIDIA driver node (/dev/nvidiactl).
bool NvidiaDevicePresent();

}  // namespace fetchscope
