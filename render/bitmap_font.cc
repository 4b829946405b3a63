// The glyph table is drawn as ASCII art ('#' lit, '.' dark) so it can be read
// and edited by eye; it is parsed once into row bitmasks on first use.
#include "render/bitmap_font.h"

#include <algorithm>
#include <array>
#include <cstddef>

namespace fetchscope {
namespace {

constexpr int kFirstChar = 32;  // ' '
constexpr int kLastChar = 126;  // '~'
constexpr int kNumGlyphs = kLastChar - kFirstChar + 1;
constexpr int kGlyphsPerBlock = 12;

// Blocks of 12 glyphs in ASCII order, 8 rows each; glyphs separated by one
// space. Rows 0..6 sit on the baseline, row 7 holds descenders.
constexpr const char* kGlyphArt[] = {
    // ' '   '!'   '"'   '#'   '$'   '%'   '&'   '''   '('   ')'   '*'   '+'
    "..... ..#.. .#.#. .#.#. ..#.. ##... .##.. ..#.. ...#. .#... ..... .....",
    "..... ..#.. .#.#. .#.#. .#### ##..# #..#. ..#.. ..#.. ..#.. ..#.. ..#..",
    "..... ..#.. ..... ##### #.#.. ...#. #.#.. ..... .#... ...#. #.#.# ..#..",
    "..... ..#.. ..... .#.#. .###. ..#.. .#... ..... .#... ...#. .###. #####",
    "..... ..#.. ..... ##### ..#.# .#... #.#.# ..... .#... ...#. #.#.# ..#..",
    "..... ..... ..... .#.#. ####. #..## #..#. ..... ..#.. ..#.. ..#.. ..#..",
    "..... ..#.. ..... .#.#. ..#.. ...## .##.# ..... ...#. .#... ..... .....",
    "..... ..... ..... ..... ..... ..... ..... ..... ..... ..... ..... .....",
    // ','   '-'   '.'   '/'   '0'   '1'   '2'   '3'   '4'   '5'   '6'   '7'
    "..... ..... ..... ..... .###. ..#.. .###. ##### ...#. ##### ..##. #####",
    "..... ..... ..... ....# #...# .##.. #...# ...#. ..##. #.... .#... ....#",
    "..... ..... ..... ...#. #..## ..#.. ....# ..#.. .#.#. ####. #.... ...#.",
    "..... ##### ..... ..#.. #.#.# ..#.. ...#. ...#. #..#. ....# ####. ..#..",
    "..... ..... ..... .#... ##..# ..#.. ..#.. ....# ##### ....# #...# .#...",
    ".##.. ..... .##.. #.... #...# ..#.. .#... #...# ...#. #...# #...# .#...",
    "..#.. ..... .##.. ..... .###. .###. ##### .###. ...#. .###. .###. .#...",
    ".#... ..... ..... ..... ..... ..... ..... ..... ..... ..... ..... .....",
    // '8'   '9'   ':'   ';'   '<'   '='   '>'   '?'   '@'   'A'   'B'   'C'
    ".###. .###. ..... ..... ...#. ..... .#... .###. .###. .###. ####. .###.",
    "#...# #...# .##.. .##.. ..#.. ..... ..#.. #...# #...# #...# #...# #...#",
    "#...# #...# .##.. .##.. .#... ##### ...#. ....# ....# #...# #...# #....",
    ".###. .#### ..... ..... #.... ..... ....# ...#. .##.# ##### ####. #....",
    "#...# ....# .##.. .##.. .#... ##### ...#. ..#.. #.#.# #...# #...# #....",
    "#...# ...#. .##.. ..#.. ..#.. ..... ..#.. ..... #.#.# #...# #...# #...#",
    ".###. .##.. ..... .#... ...#. ..... .#... ..#.. .###. #...# ####. .###.",
    "..... ..... ..... ..... ..... ..... ..... ..... ..... ..... ..... .....",
    // 'D'   'E'   'F'   'G'   'H'   'I'   'J'   'K'   'L'   'M'   'N'   'O'
    "###.. ##### ##### .###. #...# .###. ..### #...# #.... #...# #...# .###.",
    "#..#. #.... #.... #...# #...# ..#.. ...#. #..#. #.... ##.## #...# #...#",
    "#...# #.... #.... #.... #...# ..#.. ...#. #.#.. #.... #.#.# ##..# #...#",
    "#...# ####. ####. #.### ##### ..#.. ...#. ##... #.... #.#.# #.#.# #...#",
    "#...# #.... #.... #...# #...# ..#.. ...#. #.#.. #.... #...# #..## #...#",
    "#..#. #.... #.... #...# #...# ..#.. #..#. #..#. #.... #...# #...# #...#",
    "###.. ##### #.... .#### #...# .###. .##.. #...# ##### #...# #...# .###.",
    "..... ..... ..... ..... ..... ..... ..... ..... ..... ..... ..... .....",
    // 'P'   'Q'   'R'   'S'   'T'   'U'   'V'   'W'   'X'   'Y'   'Z'   '['
    "####. .###. ####. .#### ##### #...# #...# #...# #...# #...# ##### .###.",
    "#...# #...# #...# #.... ..#.. #...# #...# #...# #...# #...# ....# .#...",
    "#...# #...# #...# #.... ..#.. #...# #...# #...# .#.#. .#.#. ...#. .#...",
    "####. #...# ####. .###. ..#.. #...# #...# #.#.# ..#.. ..#.. ..#.. .#...",
    "#.... #.#.# #.#.. ....# ..#.. #...# #...# #.#.# .#.#. ..#.. .#... .#...",
    "#.... #..#. #..#. ....# ..#.. #...# .#.#. #.#.# #...# ..#.. #.... .#...",
    "#.... .##.# #...# ####. ..#.. .###. ..#.. .#.#. #...# ..#.. ##### .###.",
    "..... ..... ..... ..... ..... ..... ..... ..... ..... ..... ..... .....",
    // '\'   ']'   '^'   '_'   '`'   'a'   'b'   'c'   'd'   'e'   'f'   'g'
    "..... .###. ..#.. ..... .#... ..... #.... ..... ....# ..... ..##. .....",
    "#.... ...#. .#.#. ..... ..#.. ..... #.... ..... ....# ..... .#..# .....",
    ".#... ...#. #...# ..... ..... .###. ####. .###. .#### .###. .#... .####",
    "..#.. ...#. ..... ..... ..... ....# #...# #.... #...# #...# ###.. #...#",
    "...#. ...#. ..... ..... ..... .#### #...# #.... #...# ##### .#... #...#",
    "....# ...#. ..... ..... ..... #...# #...# #...# #...# #.... .#... .####",
    "..... .###. ..... ..... ..... .#### ####. .###. .#### .###. .#... ....#",
    "..... ..... ..... ##### ..... ..... ..... ..... ..... ..... ..... .###.",
    // 'h'   'i'   'j'   'k'   'l'   'm'   'n'   'o'   'p'   'q'   'r'   's'
    "#.... ..#.. ...#. #.... .##.. ..... ..... ..... ..... ..... ..... .....",
    "#.... ..... ..... #.... ..#.. ..... ..... ..... ..... ..... ..... .....",
    "#.##. .##.. ..##. #..#. ..#.. ##.#. #.##. .###. ####. .#### #.##. .####",
    "##..# ..#.. ...#. #.#.. ..#.. #.#.# ##..# #...# #...# #...# ##..# #....",
    "#...# ..#.. ...#. ##... ..#.. #.#.# #...# #...# #...# #...# #.... .###.",
    "#...# ..#.. ...#. #.#.. ..#.. #.#.# #...# #...# ####. .#### #.... ....#",
    "#...# .###. #..#. #..#. .###. #.#.# #...# .###. #.... ....# #.... ####.",
    "..... ..... .##.. ..... ..... ..... ..... ..... #.... ....# ..... .....",
    // 't'   'u'   'v'   'w'   'x'   'y'   'z'   '{'   '|'   '}'   '~'
    ".#... ..... ..... ..... ..... ..... ..... ...## ..#.. ##... .....",
    ".#... ..... ..... ..... ..... ..... ..... ..#.. ..#.. ..#.. .....",
    "###.. #...# #...# #...# #...# #...# ##### ..#.. ..#.. ..#.. .#...",
    ".#... #...# #...# #...# .#.#. #...# ...#. .#... ..#.. ...#. #.#.#",
    ".#... #...# #...# #.#.# ..#.. #...# ..#.. ..#.. ..#.. ..#.. ...#.",
    ".#..# #..## .#.#. #.#.# .#.#. .#### .#... ..#.. ..#.. ..#.. .....",
    "..##. .##.# ..#.. .#.#. #...# ....# ##### ...## ..#.. ##... .....",
    "..... ..... ..... ..... ..... .###. ..... ..... ..... ..... .....",
};
constexpr int kNumArtRows = sizeof(kGlyphArt) / sizeof(kGlyphArt[0]);
static_assert(kNumArtRows == kGlyphHeight * ((kNumGlyphs + kGlyphsPerBlock - 1) / kGlyphsPerBlock),
              "glyph art must have 8 rows per block of 12 glyphs");

// One byte per glyph row, bit 4 = leftmost column.
using GlyphRows = std::array<uint8_t, kGlyphHeight>;

const std::array<GlyphRows, kNumGlyphs>& Glyphs() {
  static const std::array<GlyphRows, kNumGlyphs> glyphs = [] {
    std::array<GlyphRows, kNumGlyphs> parsed{};
    for (int g = 0; g < kNumGlyphs; ++g) {
      const int block = g / kGlyphsPerBlock;
      const int column = (g % kGlyphsPerBlock) * (kGlyphWidth + 1);
      for (int row = 0; row < kGlyphHeight; ++row) {
        const char* art = kGlyphArt[block * kGlyphHeight + row];
        uint8_t bits = 0;
        for (int c = 0; c < kGlyphWidth; ++c) {
          bits = static_cast<uint8_t>((bits << 1) | (art[column + c] == '#' ? 1 : 0));
        }
        parsed[g][row] = bits;
      }
    }
    return parsed;
  }();
  return glyphs;
}

const GlyphRows& GlyphFor(char ch) {
  const int code = static_cast<unsigned char>(ch);
  const int index =
      (code >= kFirstChar && code <= kLastChar) ? code - kFirstChar : '?' - kFirstChar;
  return Glyphs()[index];
}

// Fills the clipped square [x, x+scale) x [y, y+scale) with `color`.
void FillBlock(uint8_t* rgb, int width, int height, int x, int y, int scale, Rgb color) {
  const int x0 = std::max(x, 0), x1 = std::min(x + scale, width);
  const int y0 = std::max(y, 0), y1 = std::min(y + scale, height);
  for (int py = y0; py < y1; ++py) {
    uint8_t* p = rgb + (static_cast<std::size_t>(py) * width + x0) * 3;
    for (int px = x0; px < x1; ++px, p += 3) {
      p[0] = color.r;
      p[1] = color.g;
      p[2] = color.b;
    }
  }
}

}  // namespace

void DrawText(uint8_t* rgb, int width, int height, int x, int y, const std::string& text, int scale,
              Rgb color) {
  if (rgb == nullptr || width <= 0 || height <= 0 || scale <= 0) return;
  int pen_x = x, pen_y = y;
  for (char ch : text) {
    if (ch == '\n') {
      pen_x = x;
      pen_y += kLineHeight * scale;
      continue;
    }
    // Skip glyphs wholly outside the image: long labels stay cheap.
    const bool visible = pen_x < width && pen_x + kGlyphWidth * scale > 0 && pen_y < height &&
                         pen_y + kGlyphHeight * scale > 0;
    if (visible) {
      const GlyphRows& glyph = GlyphFor(ch);
      for (int row = 0; row < kGlyphHeight; ++row) {
        for (int col = 0; col < kGlyphWidth; ++col) {
          if (glyph[row] & (1 << (kGlyphWidth - 1 - col))) {
            FillBlock(rgb, width, height, pen_x + col * scale, pen_y + row * scale, scale, color);
          }
        }
      }
    }
    pen_x += kGlyphAdvance * scale;
  }
}

int TextWidth(const std::string& text, int scale) {
  std::size_t widest = 0, current = 0;
  for (char ch : text) {
    current = (ch == '\n') ? 0 : current + 1;
    widest = std::max(widest, current);
  }
  if (widest == 0) return 0;
  return static_cast<int>(widest) * kGlyphAdvance * scale - (kGlyphAdvance - kGlyphWidth) * scale;
}

int TextHeight(const std::string& text, int scale) {
  if (text.empty()) return 0;
  const int lines = 1 + static_cast<int>(std::count(text.begin(), text.end(), '\n'));
  return ((lines - 1) * kLineHeight + kGlyphHeight) * scale;
}

}  // namespace fetchscope
