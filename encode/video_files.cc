#include "encode/video_files.h"

#include <unistd.h>

#include <fstream>
#include <iterator>

#include "base/errors.h"
#include "encode/video_writer.h"

namespace fetchscope {
namespace {

std::string Quoted(const std::string& s) { return "'" + s + "'"; }

namespace fs = std::filesystem;

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
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
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
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) throw RunError("cannot write GIF " + Quoted(path.string()));
}

}  // namespace fetchscope
