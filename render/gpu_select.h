// Which GPU renders: EGL device enumeration and the --gpu value (an EGL index, a list, `all`,
// or `cuda:N` in CUDA's numbering), with MUJOCO_EGL_DEVICE_ID and CUDA_VISIBLE_DEVICES as
// defaults. NVIDIA's EGL numbers its devices in its own order, independent of CUDA's and of
// CUDA_VISIBLE_DEVICES; EGL_NV_device_cuda tells, per device, the ordinal CUDA gives it, so a
// GPU named in CUDA's numbering is the one a user's trainer calls by that number.
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace fetchscope {

/// One device of eglQueryDevicesEXT's list.
struct EglDevice {
  int index = 0;           ///< position in the driver's list (EGL numbering, as --gpu N)
  int cuda_id = -1;        ///< EGL_CUDA_DEVICE_NV: the ordinal CUDA gives it; -1 when none
  bool software = false;   ///< EGL_MESA_device_software (llvmpipe)
  std::string drm_node;    ///< EGL_DRM_DEVICE_FILE_EXT, "" when the driver gives none
  std::string extensions;  ///< the device's extension string

  /// "EGL device 1 (CUDA 0)", "EGL device 0 (/dev/dri/card0)", "EGL device 1 (software)".
  std::string Describe() const;
};

/// What the EGL library enumerates.
struct EglDeviceList {
  bool enumerable = false;         ///< EGL_EXT_device_enumeration or _base, and _platform_device
  std::vector<EglDevice> devices;  ///< in the driver's order
  std::string client_extensions;   ///< eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS)
  std::string why_not;             ///< when not enumerable: what is missing
};

/// Loads libEGL and lists its devices. Never initialises a display. Throws RunError when
/// libEGL cannot be loaded.
EglDeviceList ListEglDevices();

/// A --gpu request, parsed but not yet matched against the devices.
struct GpuSpec {
  enum class Kind {
    kAuto,  ///< the first hardware device, else Mesa's surfaceless platform, else software
    kEgl,   ///< EGL indices in `ids`
    kAll,   ///< every hardware device (software ones where there is no other)
    kCuda,  ///< CUDA ordinals in `ids`, matched through EGL_CUDA_DEVICE_NV
  };
  Kind kind = Kind::kAuto;
  std::vector<int> ids;  ///< kEgl, kCuda: in the order given
  std::string text;      ///< as given, for messages
  std::string source;    ///< "--gpu", "MUJOCO_EGL_DEVICE_ID", "CUDA_VISIBLE_DEVICES" or "" (auto)
  /// True when the spec only follows CUDA_VISIBLE_DEVICES: on an EGL that reports no CUDA
  /// ordinals it falls back to auto instead of failing.
  bool soft = false;
};

/// The accepted --gpu forms, for help and messages.
inline constexpr const char* kGpuForms =
    "an EGL device index (0), a comma list (0,2), all, or cuda:N / cuda:N,M (CUDA's numbering, "
    "as CUDA_VISIBLE_DEVICES makes it)";

/// Parses a --gpu value. Throws UsageError naming `source`, the text and the accepted forms.
GpuSpec ParseGpuSpec(const std::string& text, const std::string& source = "--gpu");

/// Looks up an environment variable (nullptr when unset); std::getenv when empty.
using EnvLookup = std::function<const char*(const char*)>;

/// The request in effect: `flag` when not empty; else MUJOCO_EGL_DEVICE_ID (an EGL index);
/// else, when CUDA_VISIBLE_DEVICES is set, cuda:0 (soft: the GPU a CUDA program would use by
/// default); else auto. Throws UsageError for a malformed value.
GpuSpec EffectiveGpuSpec(const std::string& flag, const EnvLookup& env = nullptr);

/// The outcome of matching a request against the devices.
struct GpuChoice {
  std::vector<int> devices;  ///< EGL indices in worker order; empty: auto (CreateEglContext(-1))
  std::string reason;        ///< e.g. "--gpu cuda:1 = EGL device 2", for manifests and --verbose
};

/// Matches `spec` against `list`. Throws UsageError for an index or CUDA ordinal that no device
/// has (listing the ones there are) and RunError when the request needs enumeration or CUDA
/// ordinals that this EGL does not provide (unless the spec is soft: then auto, with a reason).
GpuChoice ChooseGpus(const GpuSpec& spec, const EglDeviceList& list);

/// EGL_CUDA_DEVICE_NV from EGL_NV_device_cuda (eglext.h of older Mesa lacks it).
inline constexpr int kEglCudaDeviceNv = 0x323A;

}  // namespace fetchscope
