#include "encode/jpeg.h"

#include <turbojpeg.h>

#include "base/errors.h"

namespace fetchscope {

JpegEncoder::JpegEncoder() : handle_(tjInitCompress()) {
  if (!handle_) throw RunError(std::string("libjpeg-turbo: ") + tjGetErrorStr());
}

JpegEncoder::~JpegEncoder() { tjDestroy(static_cast<tjhandle>(handle_)); }

std::string JpegEncoder::Encode(const uint8_t* rgb, int width, int height, int quality) {
  if (width <= 0 || height <= 0) {
    throw UsageError("JPEG size " + std::to_string(width) + "x" + std::to_string(height) +
                     " is not positive");
  }
  if (quality < kMinJpegQuality || quality > kMaxJpegQuality) {
    throw UsageError("JPEG quality " + std::to_string(quality) + " is out of range; accepted: " +
                     std::to_string(kMinJpegQuality) + ".." + std::to_string(kMaxJpegQuality));
  }
  unsigned char* out = nullptr;
  unsigned long size = 0;
  const int subsampling = quality >= 90 ? TJSAMP_444 : TJSAMP_420;
  const int failed = tjCompress2(static_cast<tjhandle>(handle_), rgb, width, 0, height, TJPF_RGB,
                                 &out, &size, subsampling, quality, TJFLAG_FASTDCT);
  std::string bytes;
  if (!failed) bytes.assign(reinterpret_cast<const char*>(out), size);
  tjFree(out);
  if (failed) {
    throw RunError(std::string("libjpeg-turbo: ") + tjGetErrorStr2(static_cast<tjhandle>(handle_)));
  }
  return bytes;
}

}  // namespace fetchscope
