// The files a video writer writes: the output folder's check, the hidden temporary name, and the
// tags of GIF files (FFmpeg's GIF muxer writes none, so a GIF89a comment extension is inserted,
// which FFmpeg's demuxer, and so ffprobe, reads back as the tag "comment").
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

}  // namespace fetchscope
