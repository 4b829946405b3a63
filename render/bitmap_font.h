// A small embedded fixed-width pixel font for labels drawn straight into RGB
// images (contact sheets, HUD-less stills), so no font file or library is
// needed at run time.
//
// Glyphs cover printable ASCII 32..126 on a 5x8 grid (7 rows above the
// baseline, 1 descender row); anything else is drawn as '?'. Each glyph cell
// advances 6 pixels and each line 10 pixels, both times `scale`.
#pragma once

#include <cstdint>
#include <string>

namespace fetchscope {

/// An 8-bit sRGB colour.
struct Rgb {
  uint8_t r;  ///< red, 0..255
  uint8_t g;  ///< green, 0..255
  uint8_t b;  ///< blue, 0..255
};

inline constexpr int kGlyphWidth = 5;    ///< lit columns per glyph, pixels at scale 1
inline constexpr int kGlyphHeight = 8;   ///< rows per glyph incl. descender, pixels at scale 1
inline constexpr int kGlyphAdvance = 6;  ///< horizontal step between glyphs, pixels at scale 1
inline constexpr int kLineHeight = 10;   ///< vertical step between lines, pixels at scale 1

/// Draws `text` into an RGB24 image (`width` x `height`, row 0 = top) with the
/// top-left corner of the first glyph cell at (x, y); '\n' starts a new line at
/// x. Each font pixel becomes a `scale` x `scale` block. Pixels outside the
/// image are clipped, so any position is safe. Only lit pixels are written
/// (the background shows through).
void DrawText(uint8_t* rgb, int width, int height, int x, int y, const std::string& text, int scale,
              Rgb color);

/// Width in pixels of the widest line of `text` at `scale`, from the left edge
/// of the first glyph to the right edge of the last (no trailing gap); 0 for
/// empty text.
int TextWidth(const std::string& text, int scale);

/// Height in pixels of `text` at `scale`: one line height per line, the last
/// line counted down to the bottom of its descender row; 0 for empty text.
int TextHeight(const std::string& text, int scale);

}  // namespace fetchscope
