// Checking and naming video options: sizes, fps, codecs, presets, formats, GIF frame counts.
// (VideoOptions itself and the public functions are declared in encode/video_writer.h.)
#pragma once

#include <string>

namespace fetchscope {

/// The index of an x264 preset name (ultrafast 0 .. placebo 9), -1 when unknown.
int PresetIndex(const std::string& preset);

/// The nearest NVENC preset (p1 fastest .. p7 best) for x264 preset `index`.
const char* NvencPresetFor(int index);

/// True when this machine has an NVIDIA driver node (/dev/nvidiactl).
bool NvidiaDevicePresent();

}  // namespace fetchscope
