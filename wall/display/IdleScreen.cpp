#include "wall/display/IdleScreen.h"

#include <ft2build.h>
#include FT_FREETYPE_H

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "base/Error.h"

namespace wall {
namespace {

// Nominal sizes (pixels per em) before the text is shrunk to fit the display. Below kMinTextPx
// text is not legible: what would need to be smaller is left out.
constexpr int kMinTextPx = 6;
constexpr int kMinTitlePx = 12;
constexpr int kMaxTitlePx = 320;
constexpr int kMinLinePx = 10;
constexpr int kMaxLinePx = 120;
constexpr const char* kFontPackage = "fonts-dejavu-core";

// --- fonts -----------------------------------------------------------------------------------

// The FreeType library and every face opened so far, by path (nullptr: the file could not be
// opened; remembered, so a missing file is looked up once). FreeType objects are not thread-safe:
// everything that touches them holds `mutex`. Never destroyed (a thread may still draw while the
// process exits); the faces stay reachable, so leak checkers do not count them.
struct FontCache {
  std::mutex mutex;
  bool initTried = false;
  FT_Library library = nullptr;
  std::string initError;
  std::map<std::string, FT_Face> faces;
  std::map<std::string, std::string> errors;  // why a face is nullptr
};

FontCache& fontCache() {
  static FontCache* cache = new FontCache;
  return *cache;
}

// The face of `path`, opening it the first time; nullptr and a message in `why` when it cannot
// be opened. Called with the cache's mutex held.
FT_Face faceLocked(FontCache& cache, const std::string& path, std::string& why) {
  if (!cache.initTried) {
    cache.initTried = true;
    if (const FT_Error e = FT_Init_FreeType(&cache.library); e != 0) {
      cache.library = nullptr;
      cache.initError = "FreeType failed to initialise (error " + std::to_string(e) + ")";
    }
  }
  if (!cache.library) {
    why = cache.initError;
    return nullptr;
  }
  if (auto it = cache.faces.find(path); it != cache.faces.end()) {
    if (!it->second) why = cache.errors[path];
    return it->second;
  }
  FT_Face face = nullptr;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    cache.errors[path] = "font file " + path + " not found (the Debian package " + kFontPackage +
                         " installs it: apt-get install " + kFontPackage + ")";
  } else if (const FT_Error e = FT_New_Face(cache.library, path.c_str(), 0, &face); e != 0) {
    face = nullptr;
    cache.errors[path] = "font file " + path + " cannot be read by FreeType (error " +
                         std::to_string(e) + "; reinstall the Debian package " + kFontPackage + ")";
  } else if (!FT_IS_SCALABLE(face) || face->units_per_EM == 0) {
    FT_Done_Face(face);
    face = nullptr;
    cache.errors[path] = "font file " + path + " is not a scalable font";
  }
  cache.faces[path] = face;
  if (!face) why = cache.errors[path];
  return face;
}

// --- text ------------------------------------------------------------------------------------

// UTF-8 to code points; a byte that does not start a valid, shortest sequence (or a surrogate, or
// a code point past U+10FFFF) becomes U+FFFD. Control characters are dropped (a tab is a space).
std::u32string decodeUtf8(const std::string& s) {
  std::u32string out;
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(s[i]); };
  for (std::size_t i = 0; i < s.size();) {
    const unsigned char b = byte(i);
    int extra = 0;
    char32_t cp = 0, min = 0;
    if (b < 0x80) {
      cp = b;
    } else if ((b & 0xE0) == 0xC0) {
      extra = 1, cp = b & 0x1F, min = 0x80;
    } else if ((b & 0xF0) == 0xE0) {
      extra = 2, cp = b & 0x0F, min = 0x800;
    } else if ((b & 0xF8) == 0xF0) {
      extra = 3, cp = b & 0x07, min = 0x10000;
    } else {
      out.push_back(U'\uFFFD');
      ++i;
      continue;
    }
    bool ok = true;
    for (int k = 1; ok && k <= extra; ++k) {
      if (i + k >= s.size() || (byte(i + k) & 0xC0) != 0x80) {
        ok = false;
        break;
      }
      cp = cp << 6 | (byte(i + k) & 0x3F);
    }
    if (!ok || cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) {
      out.push_back(U'\uFFFD');
      ++i;  // resynchronise on the next byte
      continue;
    }
    i += 1 + extra;
    if (cp == U'\t') cp = U' ';
    if (cp < 0x20 || (cp >= 0x7F && cp < 0xA0)) continue;
    out.push_back(cp);
  }
  return out;
}

// One line of text rasterised: 8-bit coverage, `width` x `height`, the baseline `ascent` rows
// below its top. Empty when nothing has ink.
struct Run {
  int width = 0, height = 0, ascent = 0;
  std::vector<std::uint8_t> alpha;
};

// `text` in `face` at `px` pixels per em (light hinting, anti-aliased, kerned when the font has a
// kern table). Called with the cache's mutex held.
Run rasterize(FT_Face face, int px, const std::u32string& text) {
  Run run;
  if (text.empty() || FT_Set_Pixel_Sizes(face, 0, static_cast<FT_UInt>(px)) != 0) return run;
  struct Glyph {
    int x, top, width, rows;
    std::vector<std::uint8_t> alpha;
  };
  std::vector<Glyph> glyphs;
  const bool kerning = FT_HAS_KERNING(face);
  FT_Pos pen = 0;  // 26.6
  FT_UInt previous = 0;
  for (const char32_t c : text) {
    const FT_UInt index = FT_Get_Char_Index(face, c);
    if (kerning && previous != 0 && index != 0) {
      FT_Vector delta{};
      if (FT_Get_Kerning(face, previous, index, FT_KERNING_DEFAULT, &delta) == 0) pen += delta.x;
    }
    previous = index;
    if (FT_Load_Glyph(face, index, FT_LOAD_RENDER | FT_LOAD_TARGET_LIGHT) != 0) continue;
    const FT_GlyphSlot slot = face->glyph;
    const FT_Bitmap& bm = slot->bitmap;
    if (bm.pixel_mode == FT_PIXEL_MODE_GRAY && bm.width > 0 && bm.rows > 0) {
      Glyph g{static_cast<int>((pen + 32) >> 6) + slot->bitmap_left,
              slot->bitmap_top,
              static_cast<int>(bm.width),
              static_cast<int>(bm.rows),
              {}};
      g.alpha.resize(static_cast<std::size_t>(g.width) * g.rows);
      const int levels = std::max(bm.num_grays - 1, 1);
      for (int r = 0; r < g.rows; ++r) {
        // A negative pitch means the rows are stored bottom up.
        const unsigned char* src =
            bm.pitch >= 0 ? bm.buffer + static_cast<std::ptrdiff_t>(r) * bm.pitch
                          : bm.buffer + static_cast<std::ptrdiff_t>(g.rows - 1 - r) * -bm.pitch;
        for (int x = 0; x < g.width; ++x)
          g.alpha[static_cast<std::size_t>(r) * g.width + x] =
              static_cast<std::uint8_t>(std::min(255, src[x] * 255 / levels));
      }
      glyphs.push_back(std::move(g));
    }
    pen += slot->advance.x;
  }
  if (glyphs.empty()) return run;
  int x0 = glyphs[0].x, x1 = x0, top = glyphs[0].top, bottom = top;
  for (const Glyph& g : glyphs) {
    x0 = std::min(x0, g.x);
    x1 = std::max(x1, g.x + g.width);
    top = std::max(top, g.top);
    bottom = std::min(bottom, g.top - g.rows);
  }
  run.width = x1 - x0;
  run.height = top - bottom;
  run.ascent = top;
  run.alpha.assign(static_cast<std::size_t>(run.width) * run.height, 0);
  for (const Glyph& g : glyphs)
    for (int r = 0; r < g.rows; ++r)
      for (int x = 0; x < g.width; ++x) {
        std::uint8_t& dst =
            run.alpha[static_cast<std::size_t>(top - g.top + r) * run.width + (g.x - x0 + x)];
        dst = std::max(dst, g.alpha[static_cast<std::size_t>(r) * g.width + x]);
      }
  return run;
}

// The largest size <= `px` (and >= kMinTextPx) at which `text` is at most `maxWidth` wide, with
// its run; `fits` false (and an empty run) when even the smallest is too wide.
struct Fitted {
  int px;
  Run run;
  bool fits;
};
Fitted fitWidth(FT_Face face, int px, const std::u32string& text, int maxWidth) {
  Run run = rasterize(face, px, text);
  while (run.width > maxWidth && px > kMinTextPx) {
    const int scaled = static_cast<int>(static_cast<long long>(px) * maxWidth / run.width);
    px = std::max(kMinTextPx, std::min(px - 1, scaled));
    run = rasterize(face, px, text);
  }
  if (run.width > maxWidth) return {px, Run{}, false};
  return {px, std::move(run), true};
}

// Vertical metrics of a face per pixel of size: ascender, and the line box (ascender - descender).
struct VMetrics {
  double ascent, box;
};
VMetrics vmetrics(FT_Face face) {
  const double em = face->units_per_EM;
  return {face->ascender / em, (face->ascender - face->descender) / em};
}

// A run and where its top-left goes in the image.
struct Placed {
  int x, y;
  Run run;
  std::uint32_t color;
};

// Lays the text out for a `width` x `height` display. Holds the cache's mutex for all of it.
std::vector<Placed> layoutText(int width, int height, const IdleText& text, const IdleFonts& fonts,
                               std::string* warning) {
  FontCache& cache = fontCache();
  std::lock_guard lock(cache.mutex);
  std::string whyRegular, whyBold;
  FT_Face regular = faceLocked(cache, fonts.regular, whyRegular);
  FT_Face bold = faceLocked(cache, fonts.bold, whyBold);
  if (warning) {
    std::string why = whyRegular;
    if (!whyBold.empty() && whyBold != whyRegular) why += (why.empty() ? "" : "; ") + whyBold;
    if (why.empty())
      warning->clear();
    else
      *warning = (regular || bold ? "idle screen: " : "idle screen without text: ") + why;
  }
  FT_Face titleFace = bold ? bold : regular;
  FT_Face lineFace = regular ? regular : bold;
  if (!titleFace) return {};

  const std::u32string title = decodeUtf8(text.title);
  std::vector<std::u32string> lines;
  for (const std::string& l : text.lines) lines.push_back(decodeUtf8(l));

  const int marginX = width / 16, marginY = height / 12;
  const int availW = width - 2 * marginX, availH = height - 2 * marginY;
  const VMetrics tm = vmetrics(titleFace), lm = vmetrics(lineFace);
  const auto titleBox = [&](int px) { return static_cast<int>(std::ceil(px * tm.box)); };
  const auto lineBox = [&](int px) { return static_cast<int>(std::ceil(px * lm.box * 1.2)); };
  const auto gap = [](int titlePx) { return titlePx / 3; };

  bool hasTitle = !title.empty(), hasLines = !lines.empty();
  int titlePx = 0, linePx = 0;
  const auto blockHeight = [&] {
    return (hasTitle ? titleBox(titlePx) : 0) + (hasTitle && hasLines ? gap(titlePx) : 0) +
           (hasLines ? static_cast<int>(lines.size()) * lineBox(linePx) : 0);
  };
  // Nominal sizes, shrunk together until the block fits the height; lines that would be too small
  // to read go first, then the title.
  for (;;) {
    titlePx = std::clamp(height / 8, kMinTitlePx, kMaxTitlePx);
    linePx = std::clamp(height / 24, kMinLinePx, kMaxLinePx);
    while ((hasTitle || hasLines) && blockHeight() > availH &&
           (!hasTitle || titlePx >= kMinTextPx) && (!hasLines || linePx >= kMinTextPx)) {
      const double f = static_cast<double>(std::max(availH, 0)) / blockHeight();
      titlePx = std::min(titlePx - 1, static_cast<int>(titlePx * f));
      linePx = std::min(linePx - 1, static_cast<int>(linePx * f));
    }
    if (hasLines && linePx < kMinTextPx) {
      hasLines = false;
      continue;
    }
    if (hasTitle && titlePx < kMinTextPx) hasTitle = false;
    break;
  }
  if (!hasTitle && !hasLines) return {};

  // Each line narrower than the image's inner width: the title on its own, the lines at one size
  // (the widest one's, and smaller than the title's), a line that cannot fit even at the smallest
  // size left out (an empty line keeps its place).
  Run titleRun;
  if (hasTitle) {
    Fitted fitted = fitWidth(titleFace, titlePx, title, availW);
    titlePx = fitted.px;
    titleRun = std::move(fitted.run);
    hasTitle = titleRun.width > 0;  // a title of spaces is no title
    if (hasTitle) linePx = std::min(linePx, std::max(kMinTextPx, titlePx * 3 / 4));
  }
  std::vector<Run> lineRuns;
  if (hasLines) {
    int common = linePx;
    for (const std::u32string& l : lines) {
      const Fitted fitted = fitWidth(lineFace, linePx, l, availW);
      if (fitted.fits && fitted.run.width > 0) common = std::min(common, fitted.px);
    }
    linePx = common;
    std::vector<std::u32string> kept;
    for (const std::u32string& l : lines) {
      Fitted fitted = fitWidth(lineFace, linePx, l, availW);
      if (!fitted.fits) continue;
      kept.push_back(l);
      lineRuns.push_back(std::move(fitted.run));
    }
    lines = std::move(kept);
    hasLines = !lines.empty();
  }

  std::vector<Placed> placed;
  int y = marginY + std::max(0, (availH - blockHeight()) / 2);
  if (hasTitle) {
    const int baseline = y + static_cast<int>(std::lround(titlePx * tm.ascent));
    if (titleRun.width > 0)
      placed.push_back({(width - titleRun.width) / 2, baseline - titleRun.ascent,
                        std::move(titleRun), rgba8(246, 248, 252)});
    y += titleBox(titlePx) + (hasLines ? gap(titlePx) : 0);
  }
  if (hasLines) {
    for (Run& run : lineRuns) {  // an empty line has no ink, hence no run
      const int baseline = y + static_cast<int>(std::lround(linePx * lm.ascent));
      if (run.width > 0)
        placed.push_back(
            {(width - run.width) / 2, baseline - run.ascent, std::move(run), rgba8(168, 176, 190)});
      y += lineBox(linePx);
    }
  }
  return placed;
}

// --- pixels ----------------------------------------------------------------------------------

// A dark vertical gradient with a thin lighter border, so that where one display ends and the
// next begins shows on the wall.
void fillBackground(Image& img) {
  const int w = img.width, h = img.height;
  constexpr int top[3] = {30, 36, 48}, bottom[3] = {10, 12, 17};
  for (int y = 0; y < h; ++y) {
    std::uint8_t c[3];
    for (int k = 0; k < 3; ++k)
      c[k] = static_cast<std::uint8_t>(top[k] + (bottom[k] - top[k]) * y / std::max(h - 1, 1));
    std::fill_n(&img.at(0, y), w, rgba8(c[0], c[1], c[2]));
  }
  const int border = std::max(1, std::min(w, h) / 360);
  const std::uint32_t edge = rgba8(64, 76, 96);
  for (int y = 0; y < h; ++y) {
    if (y < border || y >= h - border) {
      std::fill_n(&img.at(0, y), w, edge);
    } else {
      std::fill_n(&img.at(0, y), std::min(border, w), edge);
      std::fill_n(&img.at(std::max(w - border, 0), y), std::min(border, w), edge);
    }
  }
}

// Blends `p.run` in `p.color` over the image, clipped to it.
void composite(Image& img, const Placed& p) {
  const int x0 = std::max(p.x, 0), x1 = std::min(p.x + p.run.width, img.width);
  const int y0 = std::max(p.y, 0), y1 = std::min(p.y + p.run.height, img.height);
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const unsigned a = p.run.alpha[static_cast<std::size_t>(y - p.y) * p.run.width + (x - p.x)];
      if (a == 0) continue;
      std::uint32_t& dst = img.at(x, y);
      std::uint32_t out = 0xFF000000u;
      for (int shift = 0; shift < 24; shift += 8) {
        const unsigned bg = dst >> shift & 0xFF, fg = p.color >> shift & 0xFF;
        out |= ((bg * (255 - a) + fg * a + 127) / 255) << shift;
      }
      dst = out;
    }
}

}  // namespace

Image renderIdleScreen(int width, int height, const IdleText& text, std::string* warning) {
  return renderIdleScreen(width, height, text, IdleFonts{}, warning);
}

Image renderIdleScreen(int width, int height, const IdleText& text, const IdleFonts& fonts,
                       std::string* warning) {
  if (width <= 0 || height <= 0)
    throw base::Error("idle screen: size " + std::to_string(width) + "x" + std::to_string(height) +
                      " is not a display's size (both must be positive)");
  const std::vector<Placed> placed = layoutText(width, height, text, fonts, warning);
  Image img(width, height);
  fillBackground(img);
  for (const Placed& p : placed) composite(img, p);
  return img;
}

}  // namespace wall
