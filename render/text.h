// Anti-aliased text drawn straight into RGB24 images (contact sheets, tile labels, cards) with
// FreeType and the DejaVu Sans font from Debian's fonts-dejavu-core.
//
// Where the font comes from (first that exists wins; FindFontFile()):
//   1. $FETCHSCOPE_FONT, when set (then it must name a readable font file: no fallback)
//   2. <folder of the fetchscope binary>/fonts/DejaVuSans.ttf   (the relocatable bundle)
//   3. /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf          (Debian fonts-dejavu-core)
//   4. fontconfig's match for "DejaVu Sans", if it really is DejaVu Sans
// When none is found a RunError names every place tried and the Debian package.
//
// Coordinates: (x, y) is the top-left corner of the text's box; the first baseline lies
// `ascent` pixels below y and each further line (split at '\n') `line_height` pixels lower.
// Pixels outside the image are clipped, so any position is safe. Text is UTF-8; invalid bytes
// are drawn as U+FFFD, characters the font lacks as its missing-glyph box.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

namespace fetchscope {

class Canvas;

/// An 8-bit sRGB colour.
struct Rgb {
  uint8_t r;  ///< red, 0..255
  uint8_t g;  ///< green, 0..255
  uint8_t b;  ///< blue, 0..255
};

/// Size of a piece of text at one pixel size.
struct TextMetrics {
  int width = 0;        ///< advance width of the widest line, pixels; 0 for empty text
  int height = 0;       ///< (lines - 1) * line_height + ascent + descent; 0 for empty text
  int ascent = 0;       ///< pixels from the top of a line to its baseline
  int descent = 0;      ///< pixels from the baseline to the bottom of a line
  int line_height = 0;  ///< baseline-to-baseline distance, pixels
  int lines = 0;        ///< number of lines ('\n' + 1); 0 for empty text
};

/// How to draw a piece of text.
struct TextStyle {
  int pixel_size = 12;            ///< em size in pixels, 4..512
  Rgb color = {255, 255, 255};    ///< glyph colour, blended by coverage
  std::optional<Rgb> background;  ///< when set, a filled box behind the text
  int padding = 0;                ///< box margin around the text box, pixels (>= 0)
  /// When set, a 1-pixel outline in this colour around every glyph (the glyphs' coverage grown
  /// by one pixel each way, blended under the text), so that text reads on any background.
  std::optional<Rgb> outline;
};

/// The font file text is drawn with, found in the order given at the top of this file.
/// Throws RunError naming every place tried (and fonts-dejavu-core) when there is none.
std::filesystem::path FindFontFile();

/// One loaded font face. Measure() and Draw() may be called from several threads.
class Font {
 public:
  /// Loads `file`; throws RunError if FreeType cannot open it as a font.
  explicit Font(const std::filesystem::path& file);
  ~Font();
  Font(const Font&) = delete;
  Font& operator=(const Font&) = delete;

  /// The process-wide default font (FindFontFile()), loaded on first use. Throws RunError.
  static const Font& Default();

  /// Size of `utf8` at `pixel_size`. Throws UsageError for a pixel size outside 4..512.
  TextMetrics Measure(std::string_view utf8, int pixel_size) const;

  /// Draws `utf8` into the RGB24 image `rgb` (`width` x `height`, row 0 = top) with the top-left
  /// corner of its text box at (x, y). With style.background, first fills the text box grown by
  /// style.padding on every side. Returns the metrics of the text.
  TextMetrics Draw(uint8_t* rgb, int width, int height, int x, int y, std::string_view utf8,
                   const TextStyle& style) const;

  /// Draw() onto `canvas` (render/canvas.h): the glyphs are blended by their coverage through
  /// the canvas's one blend.
  TextMetrics Draw(Canvas* canvas, int x, int y, std::string_view utf8,
                   const TextStyle& style) const;

  /// `utf8` cut at a character boundary so it is at most `max_width` pixels wide at `pixel_size`,
  /// marking a cut with `ellipsis`; empty if not even the ellipsis fits. Single line.
  std::string Fit(const std::string& utf8, int pixel_size, int max_width,
                  const std::string& ellipsis = "...") const;
  /// Whether Fit would give `utf8` back uncut (it is at most `max_width` pixels wide).
  bool Fits(std::string_view utf8, int pixel_size, int max_width) const;

  /// Glyph bitmaps FreeType has rendered so far, by every font of the process. Each font keeps
  /// the glyphs it rendered (per pixel size), so drawing the same characters again renders none:
  /// a frame's HUD costs blits, not rasterisation (tests count this).
  static long GlyphsRasterised();

  /// The file the font was loaded from.
  const std::filesystem::path& file() const { return file_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::filesystem::path file_;
  mutable std::mutex mutex_;  // FreeType faces are not thread-safe
};

}  // namespace fetchscope
