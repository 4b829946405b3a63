#include "encode/video_files.h"

#include <unistd.h>
#include <zlib.h>

#include <cstdint>
#include <fstream>
#include <iterator>

#include "base/errors.h"
#include "encode/video_writer.h"

namespace fetchscope {
namespace {

namespace fs = std::filesystem;

std::string ReadWholeFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void WriteWholeFile(const fs::path& path, const std::string& bytes, const char* what) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) throw RunError(std::string("cannot write ") + what + " " + Quoted(path.string()));
}

void AppendBigEndian32(std::string* bytes, uint32_t value) {
  for (int shift = 24; shift >= 0; shift -= 8) *bytes += static_cast<char>((value >> shift) & 0xff);
}

// One PNG chunk: length, type, data, CRC-32 of type and data.
std::string PngChunk(const std::string& type, const std::string& data) {
  std::string chunk;
  AppendBigEndian32(&chunk, static_cast<uint32_t>(data.size()));
  const std::string body = type + data;
  chunk += body;
  AppendBigEndian32(&chunk,
                    static_cast<uint32_t>(crc32(0, reinterpret_cast<const Bytef*>(body.data()),
                                                static_cast<uInt>(body.size()))));
  return chunk;
}

}  // namespace

fs::path FolderOf(const fs::path& path) {
  return path.parent_path().empty() ? fs::path(".") : path.parent_path();
}

void CheckOutputFolder(const fs::path& final_path) {
  const fs::path folder = FolderOf(final_path);
  std::error_code error;
  const fs::file_status status = fs::status(folder, error);
  if (!fs::exists(status)) {
    throw RunError("cannot write video " + Quoted(final_path.string()) + ": folder " +
                   Quoted(folder.string()) + " does not exist");
  }
  if (!fs::is_directory(status)) {
    throw RunError("cannot write video " + Quoted(final_path.string()) + ": " +
                   Quoted(folder.string()) + " is not a folder");
  }
  if (fs::is_directory(final_path, error)) {
    throw RunError("cannot write video " + Quoted(final_path.string()) + ": it is a folder");
  }
}

fs::path TemporaryPathFor(const fs::path& final_path, std::string_view extension) {
  // the writer's PID in the name: two processes writing one folder never share a temporary file
  return final_path.parent_path() / ("." + final_path.stem().string() + ".partial-" +
                                     std::to_string(::getpid()) + "." + std::string(extension));
}

std::string GifComment(const std::vector<std::pair<std::string, std::string>>& metadata) {
  std::string comment;
  for (const auto& [key, value] : metadata) {
    comment += (comment.empty() ? "" : "; ") + key + "=" + value;
  }
  return comment;
}

void InsertGifComment(const std::filesystem::path& path, const std::string& comment) {
  std::string bytes = ReadWholeFile(path);
  if (bytes.size() < 13 || bytes.compare(0, 6, "GIF89a") != 0) {
    throw RunError("cannot tag GIF " + Quoted(path.string()) + ": not a GIF89a file");
  }
  const auto flags = static_cast<unsigned char>(bytes[10]);
  const std::size_t table = (flags & 0x80) ? 3u << ((flags & 7) + 1) : 0;
  const std::size_t at = 13 + table;
  if (at > bytes.size()) throw RunError("cannot tag GIF " + Quoted(path.string()) + ": truncated");
  std::string block = "\x21\xfe";  // extension introducer, comment label
  for (std::size_t i = 0; i < comment.size(); i += 255) {
    const std::string piece = comment.substr(i, 255);
    block += static_cast<char>(piece.size());
    block += piece;
  }
  block += '\0';  // block terminator
  bytes.insert(at, block);
  WriteWholeFile(path, bytes, "GIF");
}

void InsertPngText(const std::filesystem::path& path,
                   const std::vector<std::pair<std::string, std::string>>& metadata) {
  std::string bytes = ReadWholeFile(path);
  // the signature, then IHDR: 4 bytes of length (13), "IHDR", 13 bytes, 4 bytes of CRC
  constexpr std::size_t kAfterHeader = 8 + 4 + 4 + 13 + 4;
  if (bytes.size() < kAfterHeader || bytes.compare(0, 8, "\x89PNG\r\n\x1a\n") != 0 ||
      bytes.compare(12, 4, "IHDR") != 0) {
    throw RunError("cannot tag PNG " + Quoted(path.string()) + ": not a PNG file");
  }
  std::string chunks;
  for (const auto& [key, value] : metadata) {
    if (key.empty() || key.size() > 79 || key.find('\0') != std::string::npos) {
      throw RunError("cannot tag PNG " + Quoted(path.string()) + ": the tag name '" + key +
                     "' is not 1 to 79 characters without a NUL");
    }
    bool ascii = true;
    for (char c : value) ascii = ascii && static_cast<unsigned char>(c) < 0x80 && c != '\0';
    // tEXt holds Latin-1; a value with other bytes (UTF-8) goes in an iTXt chunk, uncompressed
    chunks += ascii ? PngChunk("tEXt", key + '\0' + value)
                    : PngChunk("iTXt", key + std::string("\0\0\0\0\0", 5) + value);
  }
  bytes.insert(kAfterHeader, chunks);
  WriteWholeFile(path, bytes, "PNG");
}

}  // namespace fetchscope
