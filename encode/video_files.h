// The files a video writer writes: the output folder's check, the hidden temporary name, and the
// tags of GIF and APNG files (FFmpeg's GIF and APNG muxers write none: a GIF89a comment
// extension is inserted, which FFmpeg's demuxer, and so ffprobe, reads back as the tag "comment";
// PNG text chunks, which FFmpeg's PNG decoder reads back as each frame's tags).
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace fetchscope {

/// The folder that holds `path` ("." for a bare file name).
std::filesystem::path FolderOf(const std::filesystem::path& path);

/// Fails early (RunError naming the folder) when the output folder cannot take the video.
void CheckOutputFolder(const std::filesystem::path& final_path);

/// ".<stem>.partial.<ext>" beside the final file: hidden, and never mistaken for a finished
/// video by a glob on "*_000.mp4".
std::filesystem::path TemporaryPathFor(const std::filesystem::path& final_path,
                                       std::string_view extension);

/// The GIF form of the tags: one comment, "key=value; key=value".
std::string GifComment(const std::vector<std::pair<std::string, std::string>>& metadata);

/// Inserts a GIF89a comment extension holding `comment` after the header, the logical screen
/// descriptor and the global colour table of the GIF file at `path`. Throws RunError naming the
/// file when it is not a GIF89a file or is truncated.
void InsertGifComment(const std::filesystem::path& path, const std::string& comment);

/// Inserts one PNG text chunk per tag right after the IHDR chunk of the (A)PNG file at `path`:
/// tEXt for an ASCII value, iTXt (UTF-8, uncompressed) otherwise. FFmpeg's APNG muxer writes no
/// tags. Throws RunError naming the file when it is not a PNG file or a tag name is not 1 to 79
/// characters.
void InsertPngText(const std::filesystem::path& path,
                   const std::vector<std::pair<std::string, std::string>>& metadata);

}  // namespace fetchscope
