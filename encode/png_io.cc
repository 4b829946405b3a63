#include "encode/png_io.h"

#include <fcntl.h>
#include <png.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "base/atomic_file.h"
#include "base/errors.h"
#include "base/kill_point.h"

namespace fetchscope {
namespace {

// libpng reports errors through a callback that must not return (nor throw: C++ exceptions
// must not cross libpng's C frames). It records the message and longjmps back to the setjmp
// in Encode/Decode, which then return false; only the callers below throw.
struct PngErrorState {
  char message[256] = "";
};

void OnPngError(png_structp png, png_const_charp message) {
  auto* state = static_cast<PngErrorState*>(png_get_error_ptr(png));
  std::snprintf(state->message, sizeof(state->message), "%s", message);
  png_longjmp(png, 1);
}

void OnPngWarning(png_structp, png_const_charp) {}  // e.g. unknown chunks: not our concern

bool HostIsLittleEndian() {
  const uint16_t probe = 1;
  return *reinterpret_cast<const uint8_t*>(&probe) == 1;
}

// No objects with destructors live in these two frames across setjmp; `rows` and `image`
// belong to the callers.
bool Encode(FILE* file, int width, int height, int color_type, int bit_depth, png_bytep* rows,
            bool fast, PngErrorState* state) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, state, OnPngError, OnPngWarning);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_init_io(png, file);
  png_set_IHDR(png, info, width, height, bit_depth, color_type, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (fast) {  // the Sub filter alone and zlib level 3 (WritePng)
    png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
    png_set_compression_level(png, 3);
  }
  png_write_info(png, info);
  if (bit_depth == 16 && HostIsLittleEndian()) png_set_swap(png);
  png_write_image(png, rows);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

bool Decode(FILE* file, Image* image, std::vector<png_bytep>* rows, PngErrorState* state) {
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, state, OnPngError, OnPngWarning);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  png_init_io(png, file);
  png_set_sig_bytes(png, 8);  // the caller checked the signature
  png_read_info(png, info);
  const int color_type = png_get_color_type(png, info);
  const int depth = png_get_bit_depth(png, info);
  if (color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (color_type == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (png_get_valid(png, info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png);
  if (depth == 16 && HostIsLittleEndian()) png_set_swap(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);

  image->width = static_cast<int>(png_get_image_width(png, info));
  image->height = static_cast<int>(png_get_image_height(png, info));
  image->channels = png_get_channels(png, info);
  image->bit_depth = png_get_bit_depth(png, info);
  const size_t row_bytes = png_get_rowbytes(png, info);
  if (row_bytes != image->row_bytes()) png_error(png, "unexpected row layout");
  image->pixels.resize(row_bytes * image->height);
  rows->resize(image->height);
  for (int y = 0; y < image->height; ++y) (*rows)[y] = image->pixels.data() + y * row_bytes;
  png_read_image(png, rows->data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return true;
}

constexpr int kColorTypes[] = {0, PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA,
                               PNG_COLOR_TYPE_RGB, PNG_COLOR_TYPE_RGB_ALPHA};

// Throws UsageError for arguments WritePng and EncodePng refuse; returns the row pointers.
std::vector<png_bytep> CheckedRows(const std::string& path, int width, int height, int channels,
                                   int bit_depth, const void* pixels) {
  if (channels < 1 || channels > 4) {
    throw UsageError("PNG channels " + std::to_string(channels) + " for " + path +
                     "; accepted: 1 (gray), 2 (gray+alpha), 3 (RGB), 4 (RGBA)");
  }
  if (bit_depth != 8 && bit_depth != 16) {
    throw UsageError("PNG bit depth " + std::to_string(bit_depth) + " for " + path +
                     "; accepted: 8, 16");
  }
  if (width <= 0 || height <= 0 || width > 1000000 || height > 1000000) {
    throw UsageError("PNG size " + std::to_string(width) + "x" + std::to_string(height) + " for " +
                     path + "; accepted: 1..1000000 per side");
  }

  const size_t row_bytes = static_cast<size_t>(width) * channels * (bit_depth / 8);
  std::vector<png_bytep> rows(height);
  for (int y = 0; y < height; ++y) {
    // libpng does not write through row pointers; the cast only satisfies its signature
    rows[y] = const_cast<png_bytep>(static_cast<const png_byte*>(pixels) + y * row_bytes);
  }
  return rows;
}

// Decodes the PNG in `file` (its signature not yet read); `what` names it in messages.
Image DecodeFile(FILE* file, const std::string& what) {
  png_byte signature[8] = {};
  if (std::fread(signature, 1, 8, file) != 8 || png_sig_cmp(signature, 0, 8) != 0) {
    std::fclose(file);
    throw RunError(what + " is not a PNG file");
  }
  Image image;
  std::vector<png_bytep> rows;
  PngErrorState state;
  bool decoded = Decode(file, &image, &rows, &state);
  std::fclose(file);
  if (!decoded) {
    throw RunError(what + " is a damaged PNG file (libpng: " +
                   (state.message[0] ? state.message : "out of memory") + ")");
  }
  return image;
}

}  // namespace

void WritePng(const std::string& path, int width, int height, int channels, int bit_depth,
              const void* pixels, bool fast) {
  std::vector<png_bytep> rows = CheckedRows(path, width, height, channels, bit_depth, pixels);
  ParentFolders parents(path);  // missing folders are created; removed again if this fails
  // hidden (".NAME.tmp-XXXXXX"), like every other temporary, so a killed run leaves nothing that
  // looks like an output
  const size_t slash = path.rfind('/');
  const size_t name_at = slash == std::string::npos ? 0 : slash + 1;
  std::string temp = path.substr(0, name_at) + "." + path.substr(name_at) + ".tmp-XXXXXX";
  int fd = mkstemp(temp.data());
  if (fd < 0) {
    const int error = errno;
    ThrowPathError("cannot write " + path + ": " + std::strerror(error), error);
  }
  fchmod(fd, 0644);  // mkstemp makes 0600; images are meant to be shared
  FILE* file = fdopen(fd, "wb");
  if (!file) {
    int err = errno;
    close(fd);
    unlink(temp.c_str());
    throw RunError("cannot write " + path + ": " + std::strerror(err));
  }
  PngErrorState state;
  bool encoded =
      Encode(file, width, height, kColorTypes[channels], bit_depth, rows.data(), fast, &state);
  int write_error = std::ferror(file) ? errno : 0;
  bool closed = std::fclose(file) == 0;
  if (!closed && write_error == 0) write_error = errno;
  if (!encoded || write_error != 0 || !closed) {
    unlink(temp.c_str());
    std::string why = write_error        ? std::strerror(write_error)
                      : state.message[0] ? std::string("libpng: ") + state.message
                                         : std::string("libpng failed");
    throw RunError("cannot write " + path + ": " + why);
  }
  KillPoint("png written, not renamed");
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    int err = errno;
    unlink(temp.c_str());
    throw RunError("cannot write " + path + ": " + std::strerror(err));
  }
  KillPoint("png renamed");
  parents.Keep();
}

std::string EncodePng(int width, int height, int channels, int bit_depth, const void* pixels,
                      bool fast, const std::string& what) {
  std::vector<png_bytep> rows = CheckedRows(what, width, height, channels, bit_depth, pixels);
  char* buffer = nullptr;
  size_t size = 0;
  FILE* file = open_memstream(&buffer, &size);
  if (!file) throw RunError("cannot encode " + what + " as PNG: " + std::strerror(errno));
  PngErrorState state;
  const bool encoded =
      Encode(file, width, height, kColorTypes[channels], bit_depth, rows.data(), fast, &state);
  const bool closed = std::fclose(file) == 0;
  std::string bytes(buffer ? buffer : "", buffer ? size : 0);
  std::free(buffer);
  if (!encoded || !closed) {
    throw RunError("cannot encode " + what + " as PNG: " +
                   (state.message[0] ? std::string("libpng: ") + state.message
                                     : std::string("out of memory")));
  }
  return bytes;
}

Image ReadPng(const std::string& path) {
  FILE* file = std::fopen(path.c_str(), "rb");
  if (!file) throw RunError("cannot read " + path + ": " + std::strerror(errno));
  return DecodeFile(file, path);
}

Image DecodePng(const std::string& bytes, const std::string& what) {
  FILE* file = fmemopen(const_cast<char*>(bytes.data()), bytes.size(), "rb");
  if (!file) throw RunError("cannot read " + what + ": " + std::strerror(errno));
  return DecodeFile(file, what);
}

}  // namespace fetchscope
