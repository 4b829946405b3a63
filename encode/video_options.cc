#include "encode/video_options.h"

#include <algorithm>
#include <array>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "base/errors.h"
#include "base/suggest.h"
#include "encode/video_format.h"
#include "encode/video_writer.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;

constexpr int kMaxDimension = 8192;
constexpr int kMaxFps = 1000;
constexpr const char* kAcceptedCodecs = "auto, libx264, h264_nvenc";
constexpr int kMaxGifFps = 50;
constexpr int kMinGifWidth = 16;
constexpr int kMaxGifWidth = 4096;
constexpr std::array<const char*, 10> kX264Presets = {
    "ultrafast", "superfast", "veryfast", "faster",   "fast",
    "medium",    "slow",      "slower",   "veryslow", "placebo"};
// The nearest NVENC preset (p1 fastest .. p7 best) for each x264 name above.
constexpr std::array<const char*, 10> kNvencPresets = {"p1", "p1", "p2", "p3", "p3",
                                                       "p4", "p5", "p6", "p7", "p7"};

}  // namespace

int PresetIndex(const std::string& preset) {
  for (std::size_t i = 0; i < kX264Presets.size(); ++i) {
    if (preset == kX264Presets[i]) return static_cast<int>(i);
  }
  return -1;
}

std::string X264ParamsFor(const std::string& preset) {
  return preset == "veryfast" ? "me=dia:subme=1" : "";
}

const char* NvencPresetFor(int index) { return kNvencPresets[static_cast<size_t>(index)]; }

void ValidateVideoOptions(const VideoOptions& options) {
  auto in_range = [](int value, int low, int high) { return value >= low && value <= high; };
  if (!in_range(options.width, 1, kMaxDimension) || !in_range(options.height, 1, kMaxDimension)) {
    throw UsageError(
        "video size " + std::to_string(options.width) + "x" + std::to_string(options.height) +
        " is out of range: width and height must be 1.." + std::to_string(kMaxDimension));
  }
  if (!in_range(options.fps, 1, kMaxFps)) {
    throw UsageError("video fps " + std::to_string(options.fps) + " is out of range: accepted 1.." +
                     std::to_string(kMaxFps));
  }
  if (options.codec != "auto" && options.codec != "libx264" && options.codec != "h264_nvenc") {
    throw UsageError("unknown video codec " + Quoted(options.codec) + ": accepted " +
                     kAcceptedCodecs);
  }
  if (!in_range(options.crf, 0, 51)) {
    throw UsageError(
        "video crf " + std::to_string(options.crf) +
        " is out of range: accepted 0..51 (lower is better quality, 23 is the default)");
  }
  if (options.format == nullptr) throw UsageError("no video format: accepted " + VideoFormatList());
  if (!in_range(options.gif_fps, 1, kMaxGifFps)) {
    throw UsageError("GIF fps " + std::to_string(options.gif_fps) +
                     " is out of range: accepted 1.." + std::to_string(kMaxGifFps) +
                     " (GIF delays are whole centiseconds; browsers slow anything faster)");
  }
  if (!in_range(options.gif_width, kMinGifWidth, kMaxGifWidth)) {
    throw UsageError("GIF width " + std::to_string(options.gif_width) +
                     " is out of range: accepted " + std::to_string(kMinGifWidth) + ".." +
                     std::to_string(kMaxGifWidth) + " pixels");
  }
  for (const auto& [key, value] : options.metadata) {
    if (key.empty() || key.find_first_of("=;\n") != std::string::npos) {
      throw UsageError("video metadata key " + Quoted(key) +
                       " is not usable: give a non-empty name without '=', ';' or newlines");
    }
  }
  if (!options.preset.empty() && PresetIndex(options.preset) < 0) {
    std::string accepted;
    for (const char* name : kX264Presets)
      accepted += (accepted.empty() ? "" : ", ") + std::string(name);
    throw UsageError("unknown video preset " + Quoted(options.preset) + ": accepted " + accepted);
  }
}

bool GifKeepsFrame(int index, int fps, int gif_fps) {
  if (gif_fps >= fps || index == 0) return true;
  const long tick = static_cast<long>(index) * gif_fps / fps;
  const long before = static_cast<long>(index - 1) * gif_fps / fps;
  return tick != before;
}

int GifFrameCount(int frames, int fps, int gif_fps) {
  if (frames <= 0) return 0;
  if (gif_fps >= fps) return frames;
  // frames 0 and the first at or after each later 1/gif_fps tick: ticks 0 .. floor((N-1) G / F)
  return static_cast<int>(static_cast<long>(frames - 1) * gif_fps / fps) + 1;
}

bool NvidiaDevicePresent() {
  std::error_code error;
  return fs::exists("/dev/nvidiactl", error);
}

Vp9Speed Vp9SpeedFor(const std::string& preset) {
  const int index = PresetIndex(preset);
  const int speed = index < 0 ? PresetIndex(kDefaultVideoPreset) : index;
  if (speed <= PresetIndex("veryfast")) return {"realtime", 8 - speed};
  return {"good", std::clamp(7 - speed, 0, 4)};
}

}  // namespace fetchscope
