// Contact sheets: a grid of downscaled frames with a label under each and a
// title on top, as one RGB image (written to PNG by the caller).
//
// Text is DejaVu Sans through FreeType (render/text.h), sized to the tiles:
// see ContactSheetLayout().
//
// Layout, all in pixels (M = kSheetMargin, T = title_bar_height,
// L = label_bar_height of ContactSheetLayout(W), W = tile_width, H = tallest scaled tile):
//   width  = M + columns * (W + M)
//   height = T + rows * (M + H + L) + M
// Tile i sits in row i / columns, column i % columns, its top-left corner at
// (M + column * (W + M), T + M + row * (M + H + L)); its label bar is the W x L
// strip right under the H rows of the cell.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "render/overlay.h"
#include "render/text.h"

namespace fetchscope {

inline constexpr int kSheetTileWidth = 240;  ///< MakeContactSheet's tile width unless told
inline constexpr int kSheetMargin = 8;       ///< gap around and between cells, pixels
inline constexpr Rgb kSheetBackground = {24, 24, 28};  ///< behind everything
inline constexpr Rgb kSheetLabelBar = {44, 44, 50};    ///< label band fill
inline constexpr Rgb kSheetText = {235, 235, 235};     ///< title and label text

/// Text sizes and bands of a sheet, all in pixels, from the tile width W:
///   label_pixel_size = clamp(round(W / 20), 9, 48)   (12 at the default W = 240)
///   title_pixel_size = round(1.5 * label_pixel_size)
///   label_bar_height = 2 * kSheetLabelPadding + two label lines (ascent + line height + descent)
///   title_bar_height = kSheetMargin + one title line (ascent + descent)
/// Throws RunError if the font cannot be found (render/text.h).
struct SheetLayout {
  int label_pixel_size = 0;
  int title_pixel_size = 0;
  int label_bar_height = 0;
  int title_bar_height = 0;
  int label_line_height = 0;  ///< baseline-to-baseline distance of the label lines
};
SheetLayout ContactSheetLayout(int tile_width);

inline constexpr int kSheetLabelPadding = 3;  ///< left and top inset of label text, pixels

/// One frame for the sheet.
struct SheetTile {
  std::vector<uint8_t> rgb;  ///< RGB24, width * height * 3 bytes, row 0 = top
  int width = 0;             ///< pixels
  int height = 0;            ///< pixels
  std::string label;         ///< up to 2 lines separated by '\n'; longer lines are cut with "..."
};

/// An RGB24 image, row 0 = top.
struct SheetImage {
  int width = 0;             ///< pixels
  int height = 0;            ///< pixels
  std::vector<uint8_t> rgb;  ///< width * height * 3 bytes
};

/// Lays `tiles` out in a grid, in order, row by row: `columns` per row
/// (0 = ceil(sqrt(n)); never more than n), each tile scaled to `tile_width`
/// pixels wide keeping its aspect (box filter: every source pixel counts, so
/// thin lines survive downscaling), its label in a bar underneath and `title`
/// on top (cut with "..." if wider than the sheet). Throws UsageError for
/// tile_width outside 16..4096 or negative columns, RunError for a tile whose
/// buffer does not match its size (naming the tile).
SheetImage MakeContactSheet(const std::string& title, const std::vector<SheetTile>& tiles,
                            int tile_width = kSheetTileWidth, int columns = 0);

/// Source pixels that cover one destination pixel, with their box-filter weights.
struct SheetSpan {
  int first = 0;                ///< the first source index
  std::vector<double> weights;  ///< weights[k] is for source index first + k; they sum to 1
};

/// ScaleSheetTile's working memory, reused between calls: the filter's spans for the last sizes
/// it scaled (from x to), and the intermediate rows of its horizontal pass.
struct SheetScratch {
  int from_width = 0, from_height = 0, to_width = 0, to_height = 0;
  std::vector<SheetSpan> columns, rows;
  std::vector<double> narrow;
};

/// The frame `rgb` (RGB24, `width` x `height`, row 0 = top) scaled to `tile_width` wide as
/// MakeContactSheet scales a tile (box filter, aspect kept), labelled `label`: a sheet made of
/// such tiles at the same tile_width is byte for byte the sheet of the full frames, so a recorder
/// keeps the small tile, not the frame. `scratch` is the filter's working buffer, reused between
/// calls. Throws UsageError for tile_width outside 16..4096, RunError for a size not positive.
SheetTile ScaleSheetTile(const uint8_t* rgb, int width, int height, std::string label,
                         int tile_width, SheetScratch* scratch);

/// A frame's caption on an episode's sheet: "t=0 reset" at the reset, else "t=STEP r=REWARD",
/// then "d=DISTANCE" and "SUCCESS" when it is one. Numbers through PictureNumber
/// (base/number_format.h): a sparse reward of -0.0 reads r=0.
std::string SheetCaption(const FrameInfo& info);

/// Which frames go on the sheet of an episode with `num_frames` frames
/// (frame 0 = reset, frame num_frames - 1 = last step: T + 1 frames for T
/// steps): every `every`-th from 0, and the last frame always. `every` = 0
/// picks about 12 tiles: every ceil((num_frames - 1) / 11)-th. Empty for
/// num_frames <= 0; throws UsageError for negative `every`.
std::vector<int> SheetFrameIndices(int num_frames, int every);

}  // namespace fetchscope
