#include "encode/contact_sheet.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>

#include "base/errors.h"
#include "base/number_format.h"
#include "render/canvas.h"

namespace fetchscope {
namespace {

constexpr int kMinTileWidth = 16;
constexpr int kMaxTileWidth = 4096;
constexpr int kLabelLines = 2;

using Span = SheetSpan;

// Box-filter spans mapping `source` samples onto `destination` samples: each
// destination pixel averages the source interval it covers, partial pixels
// weighted by overlap. Works for up- and downscaling alike.
std::vector<Span> BoxSpans(int source, int destination) {
  std::vector<Span> spans(destination);
  const double step = static_cast<double>(source) / destination;
  for (int i = 0; i < destination; ++i) {
    const double lo = i * step, hi = std::min((i + 1) * step, static_cast<double>(source));
    Span& span = spans[i];
    span.first = std::min(static_cast<int>(std::floor(lo)), source - 1);
    double total = 0;
    for (int j = span.first; j < source && j < hi; ++j) {
      const double overlap = std::min(hi, j + 1.0) - std::max(lo, static_cast<double>(j));
      if (overlap <= 0) continue;
      span.weights.push_back(overlap);
      total += overlap;
    }
    for (double& w : span.weights) w /= total;
  }
  return spans;
}

// `rgb` (width x height) box-filtered to out_width x out_height, RGB24; `scratch` holds the
// horizontal pass (reused between calls, so that no frame-sized buffer is made per tile).
std::vector<uint8_t> Scaled(const uint8_t* rgb, int width, int height, int out_width,
                            int out_height, SheetScratch* scratch) {
  SheetScratch& s = *scratch;
  if (s.from_width != width || s.from_height != height || s.to_width != out_width ||
      s.to_height != out_height) {
    s.columns = BoxSpans(width, out_width);
    s.rows = BoxSpans(height, out_height);
    s.from_width = width, s.from_height = height, s.to_width = out_width, s.to_height = out_height;
  }
  const std::vector<Span>& columns = s.columns;
  const std::vector<Span>& rows = s.rows;
  // Horizontal pass over every source row, then vertical pass.
  std::vector<double>& narrow = s.narrow;
  narrow.resize(static_cast<std::size_t>(height) * out_width * 3);
  for (int y = 0; y < height; ++y) {
    const uint8_t* in = rgb + static_cast<std::size_t>(y) * width * 3;
    double* out = narrow.data() + static_cast<std::size_t>(y) * out_width * 3;
    for (int x = 0; x < out_width; ++x) {
      const Span& span = columns[x];
      double r = 0, g = 0, b = 0;
      for (std::size_t k = 0; k < span.weights.size(); ++k) {
        const uint8_t* p = in + (span.first + k) * 3;
        r += span.weights[k] * p[0];
        g += span.weights[k] * p[1];
        b += span.weights[k] * p[2];
      }
      out[x * 3 + 0] = r;
      out[x * 3 + 1] = g;
      out[x * 3 + 2] = b;
    }
  }
  std::vector<uint8_t> scaled(static_cast<std::size_t>(out_width) * out_height * 3);
  for (int y = 0; y < out_height; ++y) {
    const Span& span = rows[y];
    uint8_t* out = scaled.data() + static_cast<std::size_t>(y) * out_width * 3;
    for (int x = 0; x < out_width * 3; ++x) {
      double value = 0;
      for (std::size_t k = 0; k < span.weights.size(); ++k) {
        value += span.weights[k] * narrow[(span.first + k) * out_width * 3 + x];
      }
      out[x] = static_cast<uint8_t>(std::clamp(std::lround(value), 0L, 255L));
    }
  }
  return scaled;
}

// The first kLabelLines lines of `label`, each fitted to `max_width`.
std::string FitLabel(const Font& font, const std::string& label, int pixel_size, int max_width) {
  std::string fitted;
  std::size_t start = 0;
  for (int line = 0; line < kLabelLines && start <= label.size(); ++line) {
    const std::size_t end = std::min(label.find('\n', start), label.size());
    if (line > 0) fitted += '\n';
    fitted += font.Fit(label.substr(start, end - start), pixel_size, max_width);
    start = end + 1;
  }
  return fitted;
}

int ScaledHeight(int width, int height, int tile_width) {
  const long rounded = std::lround(static_cast<double>(height) * tile_width / width);
  return static_cast<int>(std::max(1L, rounded));
}
int ScaledHeight(const SheetTile& tile, int tile_width) {
  return ScaledHeight(tile.width, tile.height, tile_width);
}

void CheckTileWidth(int tile_width) {
  if (tile_width < kMinTileWidth || tile_width > kMaxTileWidth) {
    throw UsageError("contact sheet tile width " + std::to_string(tile_width) +
                     " is out of range: accepted " + std::to_string(kMinTileWidth) + ".." +
                     std::to_string(kMaxTileWidth));
  }
}

}  // namespace

SheetTile ScaleSheetTile(const uint8_t* rgb, int width, int height, std::string label,
                         int tile_width, SheetScratch* scratch) {
  CheckTileWidth(tile_width);
  if (width <= 0 || height <= 0) {
    throw RunError("contact sheet tile (" + label + ") is " + std::to_string(width) + "x" +
                   std::to_string(height) + ": expected a positive size");
  }
  SheetTile tile;
  tile.width = tile_width;
  tile.height = ScaledHeight(width, height, tile_width);
  tile.rgb = Scaled(rgb, width, height, tile.width, tile.height, scratch);
  tile.label = std::move(label);
  return tile;
}

SheetLayout ContactSheetLayout(int tile_width) {
  const Font& font = Font::Default();
  SheetLayout layout;
  layout.label_pixel_size = std::clamp(static_cast<int>(std::lround(tile_width / 20.0)), 9, 48);
  layout.title_pixel_size = static_cast<int>(std::lround(1.5 * layout.label_pixel_size));
  const TextMetrics label = font.Measure("", layout.label_pixel_size);
  const TextMetrics title = font.Measure("", layout.title_pixel_size);
  layout.label_line_height = label.line_height;
  layout.label_bar_height =
      2 * kSheetLabelPadding + label.ascent + label.line_height + label.descent;
  layout.title_bar_height = kSheetMargin + title.ascent + title.descent;
  return layout;
}

SheetImage MakeContactSheet(const std::string& title, const std::vector<SheetTile>& tiles,
                            int tile_width, int columns) {
  CheckTileWidth(tile_width);
  if (columns < 0) {
    throw UsageError("contact sheet columns " + std::to_string(columns) +
                     " is negative: give 0 (automatic) or more");
  }
  const int n = static_cast<int>(tiles.size());
  for (int i = 0; i < n; ++i) {
    const SheetTile& tile = tiles[i];
    const bool valid = tile.width > 0 && tile.height > 0 &&
                       tile.rgb.size() == static_cast<std::size_t>(tile.width) * tile.height * 3;
    if (!valid) {
      throw RunError("contact sheet tile " + std::to_string(i) + " (" + tile.label + ") is " +
                     std::to_string(tile.width) + "x" + std::to_string(tile.height) + " with " +
                     std::to_string(tile.rgb.size()) + " bytes: expected width * height * 3 > 0");
    }
  }

  if (columns == 0) columns = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n))));
  columns = std::max(1, std::min(columns, n));
  const int rows = (n + columns - 1) / columns;
  int cell_height = 0;
  for (const SheetTile& tile : tiles)
    cell_height = std::max(cell_height, ScaledHeight(tile, tile_width));

  const Font& font = Font::Default();
  const SheetLayout layout = ContactSheetLayout(tile_width);
  SheetImage sheet;
  sheet.width = kSheetMargin + columns * (tile_width + kSheetMargin);
  sheet.height = layout.title_bar_height +
                 rows * (kSheetMargin + cell_height + layout.label_bar_height) + kSheetMargin;
  sheet.rgb.resize(static_cast<std::size_t>(sheet.width) * sheet.height * 3);
  Canvas canvas(sheet.rgb.data(), sheet.width, sheet.height);
  canvas.FillRect(0, 0, sheet.width, sheet.height, kSheetBackground);

  // A long title drops to the label size before it is cut.
  const int title_room = sheet.width - 2 * kSheetMargin;
  const std::string first_line = title.substr(0, title.find('\n'));
  const int title_size = font.Measure(first_line, layout.title_pixel_size).width <= title_room
                             ? layout.title_pixel_size
                             : layout.label_pixel_size;
  canvas.Text(kSheetMargin, kSheetMargin, font.Fit(first_line, title_size, title_room), title_size,
              kSheetText);

  const int label_room = tile_width - 2 * kSheetLabelPadding;
  SheetScratch scratch;
  for (int i = 0; i < n; ++i) {
    const int x0 = kSheetMargin + (i % columns) * (tile_width + kSheetMargin);
    const int y0 = layout.title_bar_height + kSheetMargin +
                   (i / columns) * (kSheetMargin + cell_height + layout.label_bar_height);
    const SheetTile& tile = tiles[i];
    const int scaled_height = ScaledHeight(tile, tile_width);
    if (tile.width == tile_width && tile.height == scaled_height) {
      // already at its size (ScaleSheetTile): the box filter would give each pixel back as it is
      canvas.Paste(tile.rgb.data(), tile_width, scaled_height, x0, y0);
    } else {
      canvas.Paste(
          Scaled(tile.rgb.data(), tile.width, tile.height, tile_width, scaled_height, &scratch)
              .data(),
          tile_width, scaled_height, x0, y0);
    }
    const int bar_y = y0 + cell_height;
    canvas.FillRect(x0, bar_y, tile_width, layout.label_bar_height, kSheetLabelBar);
    canvas.Text(x0 + kSheetLabelPadding, bar_y + kSheetLabelPadding,
                FitLabel(font, tiles[i].label, layout.label_pixel_size, label_room),
                layout.label_pixel_size, kSheetText);
  }
  return sheet;
}

std::string SheetCaption(const FrameInfo& info) {
  const std::string first =
      info.step == 0 ? std::string("t=0 reset")
                     : "t=" + std::to_string(info.step) + PictureNumber(" r=%.3g", info.reward);
  // "d=0.123 " ends in a space when it is no success, as it always has
  return first + "\n" + PictureNumber("d=%.3f", info.distance) + " " +
         (info.success ? "SUCCESS" : "");
}

std::vector<int> SheetFrameIndices(int num_frames, int every) {
  if (every < 0) {
    throw UsageError("contact sheet frame step " + std::to_string(every) +
                     " is negative: give 0 (about 12 tiles) or a step in frames");
  }
  std::vector<int> indices;
  if (num_frames <= 0) return indices;
  const int last = num_frames - 1;
  if (every == 0) every = std::max(1, (last + 10) / 11);  // ceil(last / 11): 12 tiles at most
  for (int i = 0; i < last; i += every) indices.push_back(i);
  indices.push_back(last);
  return indices;
}

}  // namespace fetchscope
