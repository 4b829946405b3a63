#include "render/text.h"

#include <fontconfig/fontconfig.h>
#include <ft2build.h>
#include FT_FREETYPE_H

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <fstream>
#include <unordered_map>
#include <vector>

#include "base/errors.h"
#include "render/canvas.h"

namespace fetchscope {
namespace fs = std::filesystem;
namespace {

constexpr int kMinPixelSize = 4;
constexpr int kMaxPixelSize = 512;
constexpr char kFontName[] = "DejaVuSans.ttf";
constexpr char kDebianFont[] = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

bool Readable(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return false;
  std::ifstream in(path, std::ios::binary);
  return in.good();
}

// fontconfig's file for "DejaVu Sans", or empty when it has none (its best match for a missing
// family is some other font, which would change every label: that is refused).
std::string FontconfigMatch() {
  FcConfig* config = FcInitLoadConfigAndFonts();
  if (!config) return "";
  std::string file;
  FcPattern* pattern = FcNameParse(reinterpret_cast<const FcChar8*>("DejaVu Sans:style=Book"));
  if (pattern) {
    FcConfigSubstitute(config, pattern, FcMatchPattern);
    FcDefaultSubstitute(pattern);
    FcResult result = FcResultNoMatch;
    FcPattern* match = FcFontMatch(config, pattern, &result);
    if (match) {
      FcChar8* family = nullptr;
      FcChar8* path = nullptr;
      if (FcPatternGetString(match, FC_FAMILY, 0, &family) == FcResultMatch &&
          FcPatternGetString(match, FC_FILE, 0, &path) == FcResultMatch &&
          std::string(reinterpret_cast<const char*>(family)) == "DejaVu Sans") {
        file = reinterpret_cast<const char*>(path);
      }
      FcPatternDestroy(match);
    }
    FcPatternDestroy(pattern);
  }
  FcConfigDestroy(config);
  return file;
}

// Next code point of `s` from `*at` (advanced past it); U+FFFD for a malformed sequence.
char32_t NextCodePoint(std::string_view s, size_t* at) {
  const auto byte = [&](size_t i) { return static_cast<unsigned char>(s[i]); };
  const unsigned char lead = byte(*at);
  int extra;
  char32_t cp;
  if (lead < 0x80) {
    ++*at;
    return lead;
  } else if ((lead & 0xE0) == 0xC0) {
    extra = 1, cp = lead & 0x1F;
  } else if ((lead & 0xF0) == 0xE0) {
    extra = 2, cp = lead & 0x0F;
  } else if ((lead & 0xF8) == 0xF0) {
    extra = 3, cp = lead & 0x07;
  } else {
    ++*at;
    return 0xFFFD;
  }
  size_t i = *at + 1;
  for (int k = 0; k < extra; ++k, ++i) {
    if (i >= s.size() || (byte(i) & 0xC0) != 0x80) {
      *at = i;
      return 0xFFFD;
    }
    cp = (cp << 6) | (byte(i) & 0x3F);
  }
  *at = i;
  static constexpr char32_t kMinForLength[] = {0, 0x80, 0x800, 0x10000};
  if (cp < kMinForLength[extra] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return 0xFFFD;
  return cp;
}

// Calls line(begin, end) for each line of `text` (split at '\n'), as byte offsets: no copies.
template <typename Line>
void ForEachLine(std::string_view text, Line&& line) {
  size_t start = 0;
  while (true) {
    const size_t end = text.find('\n', start);
    line(start, end == std::string_view::npos ? text.size() : end);
    if (end == std::string_view::npos) break;
    start = end + 1;
  }
}

// Glyph bitmaps made by FreeType, process-wide (GlyphsRasterised()).
std::atomic<long> glyphs_rasterised{0};

// Glyphs cached per font beyond which the cache starts again (text of every script at every
// size would otherwise grow it without bound; frame text uses a few dozen).
constexpr size_t kMaxCachedGlyphs = 4096;

void CheckPixelSize(int pixel_size) {
  if (pixel_size < kMinPixelSize || pixel_size > kMaxPixelSize) {
    throw UsageError("text pixel size " + std::to_string(pixel_size) +
                     " is out of range: accepted " + std::to_string(kMinPixelSize) + ".." +
                     std::to_string(kMaxPixelSize));
  }
}

// The outline of text drawn at (x, y) with metrics `m`: the glyphs' coverage (the largest where
// glyphs overlap) grown by one pixel each way, i.e. the largest coverage in each pixel's 3 x 3
// neighbourhood, blended in style.outline's colour. Glyph pixels further than an em outside the
// text box (none in DejaVu Sans) get no outline.
template <typename ForEachGlyphPixel>
void DrawOutline(Canvas* canvas, int x, int y, const TextMetrics& m, const TextStyle& style,
                 ForEachGlyphPixel&& for_each_glyph_pixel) {
  const int margin = style.pixel_size;
  const int x0 = x - margin, y0 = y - margin;
  const int w = m.width + 2 * margin, h = m.height + 2 * margin;
  std::vector<unsigned char> mask(static_cast<size_t>(w) * h, 0);
  for_each_glyph_pixel([&](int px, int py, unsigned char coverage) {
    const int mx = px - x0, my = py - y0;
    if (mx < 0 || my < 0 || mx >= w || my >= h) return;
    unsigned char& at = mask[static_cast<size_t>(my) * w + mx];
    at = std::max(at, coverage);
  });
  for (int my = 0; my < h; ++my) {
    for (int mx = 0; mx < w; ++mx) {
      unsigned char grown = 0;
      for (int dy = std::max(0, my - 1); dy <= std::min(h - 1, my + 1); ++dy) {
        for (int dx = std::max(0, mx - 1); dx <= std::min(w - 1, mx + 1); ++dx) {
          grown = std::max(grown, mask[static_cast<size_t>(dy) * w + dx]);
        }
      }
      if (grown > 0) canvas->Blend(x0 + mx, y0 + my, *style.outline, grown / 255.0);
    }
  }
}

}  // namespace

fs::path FindFontFile() {
  std::vector<std::string> tried;
  if (const char* env = std::getenv("FETCHSCOPE_FONT"); env && *env) {
    if (Readable(env)) return env;
    throw RunError(std::string("FETCHSCOPE_FONT='") + env +
                   "' is not a readable font file: point it at a .ttf/.otf file, or unset it to "
                   "use DejaVu Sans (Debian package fonts-dejavu-core)");
  }
  tried.push_back("$FETCHSCOPE_FONT (unset)");
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path beside = exe.parent_path() / "fonts" / kFontName;
    if (Readable(beside)) return beside;
    tried.push_back(beside.string());
  }
  if (Readable(kDebianFont)) return kDebianFont;
  tried.push_back(kDebianFont);
  const std::string matched = FontconfigMatch();
  if (!matched.empty() && Readable(matched)) return matched;
  tried.push_back("fontconfig 'DejaVu Sans' (no match)");
  std::string list;
  for (const std::string& t : tried) list += (list.empty() ? "" : ", ") + t;
  throw RunError(
      "no font for drawing text: tried " + list +
      "; install Debian package fonts-dejavu-core or set FETCHSCOPE_FONT to a .ttf file");
}

struct Font::Impl {
  FT_Library library = nullptr;
  FT_Face face = nullptr;
  int size = 0;  // pixel size last set on `face`

  // A glyph as FreeType gives it at one pixel size: its advance, and its rendered bitmap (8-bit
  // coverage, `width` x `rows`, packed). Drawn from here, text is rasterised once per glyph and
  // size, and the pixels are exactly those of a fresh FT_LOAD_RENDER.
  struct Glyph {
    bool measured = false;      // FreeType loaded it (unrendered): `advance` is valid
    FT_Pos advance = 0;         // 26.6 pixels, of the unrendered load (Measure)
    bool rendered = false;      // FreeType rendered it: the fields below are valid
    FT_Pos render_advance = 0;  // 26.6 pixels, of the rendered load (Draw)
    bool gray = false;          // an 8-bit coverage bitmap (others draw nothing)
    int left = 0, top = 0, width = 0, rows = 0;
    std::vector<unsigned char> bitmap;
  };
  std::unordered_map<uint64_t, Glyph> glyphs;  // by pixel size << 32 | code point

  ~Impl() {
    if (face) FT_Done_Face(face);
    if (library) FT_Done_FreeType(library);
  }

  void SetSize(int pixel_size) {
    if (size == pixel_size) return;
    if (FT_Set_Pixel_Sizes(face, 0, static_cast<FT_UInt>(pixel_size)) != 0) {
      throw RunError("FreeType cannot size the font to " + std::to_string(pixel_size) + " pixels");
    }
    size = pixel_size;
  }

  // Metrics of the current size.
  void LineMetrics(TextMetrics* m) const {
    const FT_Size_Metrics& sm = face->size->metrics;
    m->ascent = static_cast<int>((sm.ascender + 63) >> 6);
    m->descent = static_cast<int>((-sm.descender + 63) >> 6);
    m->line_height = std::max(static_cast<int>((sm.height + 32) >> 6), m->ascent + m->descent);
  }

  // Loads the glyph of `cp` (rendered when `render`) into face->glyph. False if it fails.
  bool Load(char32_t cp, bool render) {
    const FT_UInt index = FT_Get_Char_Index(face, cp);
    const FT_Int32 flags = FT_LOAD_DEFAULT | FT_LOAD_TARGET_NORMAL | (render ? FT_LOAD_RENDER : 0);
    return FT_Load_Glyph(face, index, flags) == 0;
  }

  // The glyph of `cp` at the current size, loaded and rendered on first use.
  const Glyph& Get(char32_t cp) {
    const uint64_t key = static_cast<uint64_t>(size) << 32 | cp;
    if (auto it = glyphs.find(key); it != glyphs.end()) return it->second;
    if (glyphs.size() >= kMaxCachedGlyphs) glyphs.clear();
    Glyph g;
    if (Load(cp, false)) {
      g.measured = true;
      g.advance = face->glyph->advance.x;
    }
    if (Load(cp, true)) {
      glyphs_rasterised.fetch_add(1, std::memory_order_relaxed);
      const FT_GlyphSlot slot = face->glyph;
      const FT_Bitmap& bitmap = slot->bitmap;
      g.rendered = true;
      g.render_advance = slot->advance.x;
      g.left = slot->bitmap_left;
      g.top = slot->bitmap_top;
      g.gray = bitmap.pixel_mode == FT_PIXEL_MODE_GRAY;
      if (g.gray) {
        g.width = static_cast<int>(bitmap.width);
        g.rows = static_cast<int>(bitmap.rows);
        g.bitmap.resize(static_cast<size_t>(g.width) * g.rows);
        for (int row = 0; row < g.rows; ++row) {
          const unsigned char* src = bitmap.buffer + static_cast<long>(row) * bitmap.pitch;
          std::copy(src, src + g.width, g.bitmap.begin() + static_cast<long>(row) * g.width);
        }
      }
    }
    return glyphs.emplace(key, std::move(g)).first->second;
  }

  // Advance width of the bytes [begin, end) of `text` (one line), pixels.
  int LineWidth(std::string_view text, size_t begin, size_t end) {
    FT_Pos pen = 0;
    for (size_t at = begin; at < end;) {
      const Glyph& g = Get(NextCodePoint(text, &at));
      if (g.measured) pen += g.advance;
    }
    return static_cast<int>((pen + 32) >> 6);
  }
  int LineWidth(std::string_view line) { return LineWidth(line, 0, line.size()); }

  TextMetrics Measure(std::string_view text) {
    TextMetrics m;
    LineMetrics(&m);
    if (text.empty()) return m;
    ForEachLine(text, [&](size_t begin, size_t end) {
      ++m.lines;
      m.width = std::max(m.width, LineWidth(text, begin, end));
    });
    m.height = (m.lines - 1) * m.line_height + m.ascent + m.descent;
    return m;
  }
};

Font::Font(const fs::path& file) : impl_(std::make_unique<Impl>()), file_(file) {
  if (FT_Init_FreeType(&impl_->library) != 0) throw RunError("FreeType failed to initialise");
  if (FT_New_Face(impl_->library, file.c_str(), 0, &impl_->face) != 0) {
    throw RunError("FreeType cannot load the font '" + file.string() +
                   "': not a font file FreeType reads (use a .ttf/.otf, e.g. DejaVuSans.ttf from "
                   "Debian package fonts-dejavu-core)");
  }
}

Font::~Font() = default;

long Font::GlyphsRasterised() { return glyphs_rasterised.load(std::memory_order_relaxed); }

const Font& Font::Default() {
  static std::mutex mutex;
  static std::unique_ptr<Font> font;
  std::lock_guard<std::mutex> lock(mutex);
  if (!font) font = std::make_unique<Font>(FindFontFile());
  return *font;
}

TextMetrics Font::Measure(std::string_view utf8, int pixel_size) const {
  CheckPixelSize(pixel_size);
  std::lock_guard<std::mutex> lock(mutex_);
  impl_->SetSize(pixel_size);
  return impl_->Measure(utf8);
}

TextMetrics Font::Draw(uint8_t* rgb, int width, int height, int x, int y, std::string_view utf8,
                       const TextStyle& style) const {
  Canvas canvas(rgb, width, height);
  return Draw(&canvas, x, y, utf8, style);
}

TextMetrics Font::Draw(Canvas* canvas, int x, int y, std::string_view utf8,
                       const TextStyle& style) const {
  CheckPixelSize(style.pixel_size);
  if (style.padding < 0) {
    throw UsageError("text box padding " + std::to_string(style.padding) +
                     " is negative: give 0 or more pixels");
  }
  std::lock_guard<std::mutex> lock(mutex_);
  impl_->SetSize(style.pixel_size);
  const TextMetrics m = impl_->Measure(utf8);
  if (style.background) {
    canvas->FillRect(x - style.padding, y - style.padding, m.width + 2 * style.padding,
                     m.height + 2 * style.padding, *style.background);
  }
  if (utf8.empty()) return m;
  // Calls blend(px, py, coverage 0..255) for every pixel of every glyph, in drawing order.
  auto for_each_glyph_pixel = [&](auto&& blend) {
    int baseline = y + m.ascent;
    ForEachLine(utf8, [&](size_t begin, size_t end) {
      FT_Pos pen = static_cast<FT_Pos>(x) * 64;
      for (size_t at = begin; at < end;) {
        const Impl::Glyph& g = impl_->Get(NextCodePoint(utf8, &at));
        if (!g.rendered) continue;
        const int left = static_cast<int>((pen + 32) >> 6) + g.left;
        const int top = baseline - g.top;
        for (int row = 0; row < g.rows; ++row) {
          const int py = top + row;
          if (py < 0 || py >= canvas->height()) continue;
          const unsigned char* src = g.bitmap.data() + static_cast<long>(row) * g.width;
          for (int col = 0; col < g.width; ++col) blend(left + col, py, src[col]);
        }
        pen += g.render_advance;
      }
      baseline += m.line_height;
    });
  };
  if (style.outline) DrawOutline(canvas, x, y, m, style, for_each_glyph_pixel);
  for_each_glyph_pixel([&](int px, int py, unsigned char coverage) {
    // coverage 0..255 as alpha: exactly the integer blend it replaced (canvas.h)
    canvas->Blend(px, py, style.color, coverage / 255.0);
  });
  return m;
}

bool Font::Fits(std::string_view utf8, int pixel_size, int max_width) const {
  CheckPixelSize(pixel_size);
  std::lock_guard<std::mutex> lock(mutex_);
  impl_->SetSize(pixel_size);
  return impl_->LineWidth(utf8) <= max_width;
}

std::string Font::Fit(const std::string& utf8, int pixel_size, int max_width,
                      const std::string& ellipsis) const {
  CheckPixelSize(pixel_size);
  std::lock_guard<std::mutex> lock(mutex_);
  impl_->SetSize(pixel_size);
  if (impl_->LineWidth(utf8) <= max_width) return utf8;
  // code point boundaries, so a cut never splits a UTF-8 sequence
  std::vector<size_t> ends;
  for (size_t at = 0; at < utf8.size();) {
    NextCodePoint(utf8, &at);
    ends.push_back(at);
  }
  for (size_t k = ends.size(); k-- > 0;) {
    const std::string cut = utf8.substr(0, ends[k]) + ellipsis;
    if (impl_->LineWidth(cut) <= max_width) return cut;
  }
  return impl_->LineWidth(ellipsis) <= max_width ? ellipsis : std::string();
}

}  // namespace fetchscope
