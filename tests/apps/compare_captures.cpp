// compare_captures LAYOUT CAPTURE_DIR FULL_CANVAS_PNG FRAME [DISPLAY]
//                                                            (or: compare_captures --info LAYOUT)
//                  --displays LAYOUT: a line "NAME X Y WIDTH HEIGHT" per display
//                  DISPLAY: only that display's capture (a wall that lost processes has no
//                  complete frame of every display)
//                  --preview LAYOUT PREVIEW_PNG FULL_CANVAS_PNG [X,Y,W,H]: a job's preview
//                  (its page's /api/preview.png) equals the box filter of the render inside
//                  every display; with a window, of a service job in that window of the wall
//                  --colors PNG: how many distinct colours the image has, to tell a picture
//                  from a blank
//                  --raw PNG OUT: the image's pixels as they sit in memory (and travel in a raw
//                  batch) to OUT; prints "WIDTH HEIGHT"
//                  --window X,Y,W,H LAYOUT CAPTURE_DIR WINDOW_PNG FRAME: a service job in that
//                  window of the wall (wall/layout/Window.h): each display's capture is the
//                  window's part of it, equal to that part cut out of a single-process render of
//                  the window (W x H), and the job's wall preview equals it where displays are
//                  --composite X,Y,W,H LAYOUT CAPTURE_DIR WINDOW_PNG FRAME #rrggbb: a serving
//                  wall's own captures (serve --capture): each display's equals its rectangle of
//                  the canvas filled with the background, the window's render at its offset.
//                  Several jobs at once: WINDOW+WINDOW... and PNG+PNG..., bottom first, each
//                  render at its window in that order; FRAME `any`: some capture of each display
//                  equals its rectangle (a wall of several jobs numbers its frames per process)
//                  --thumbnail X,Y,W,H LAYOUT THUMB_PNG WINDOW_PNG SIDE: a window's thumbnail
//                  (serve --control: GET /api/windows/ID/thumbnail, its longest side at most
//                  SIDE) equals the box filter of the window's one-process render by the
//                  smallest whole factor, each cell the rounded mean of its pixels that a display
//                  shows and transparent where none does, exactly (computed here on its own, not
//                  with the wall's code)
// Invariant 2 of docs/design.md: every display's capture of frame FRAME equals its rectangle cut
// out of a single-process render of the whole canvas, byte for byte; the wall preview exists and
// shows the same pixels. Exit 0 when all match, 1 with a message naming the first mismatch.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "wall/display/Capture.h"
#include "wall/image/Image.h"
#include "wall/image/Png.h"
#include "wall/layout/Layout.h"
#include "wall/layout/Window.h"
#include "wall/route/Preview.h"

namespace {

// --preview: dfbwall's assembled preview (--preview FILE.png, decorated) against the box filter
// of a single-process render of the canvas: every cell that lies wholly inside a display and off
// its outline must match within rounding (exactly when the tile size is a multiple of the factor).
int comparePreview(const wall::Layout& layout, const wall::Image& preview,
                   const wall::Image& full) {
  const wall::PreviewGrid grid{layout.canvasWidth, layout.canvasHeight,
                               wall::previewFactor(layout.canvasWidth, layout.canvasHeight)};
  if (preview.width != grid.width() || preview.height != grid.height()) {
    std::fprintf(stderr, "preview is %dx%d, expected %dx%d\n", preview.width, preview.height,
                 grid.width(), grid.height());
    return 1;
  }
  const wall::Image expected = wall::downsample(grid, full);
  int checked = 0, worst = 0, exact = 0;
  for (const wall::Display& d : layout.displays) {
    const dfb::Region cells = grid.cellsOf(d.rect);
    for (int cy = cells.y0 + 1; cy < cells.y1 - 1; ++cy)
      for (int cx = cells.x0 + 1; cx < cells.x1 - 1; ++cx) {
        if (dfb::intersect(grid.cellPixels(cx, cy), d.rect) != grid.cellPixels(cx, cy)) continue;
        int diff = 0;
        for (int c = 0; c < 3; ++c)
          diff = std::max(diff, std::abs(static_cast<int>(preview.at(cx, cy) >> (8 * c) & 0xff) -
                                         static_cast<int>(expected.at(cx, cy) >> (8 * c) & 0xff)));
        if (diff > 1) {
          std::fprintf(stderr, "display %s, preview cell (%d, %d): 0x%08x, box filter 0x%08x\n",
                       d.name.c_str(), cx, cy, preview.at(cx, cy), expected.at(cx, cy));
          return 1;
        }
        worst = std::max(worst, diff);
        exact += diff == 0;
        ++checked;
      }
  }
  if (checked == 0) {
    std::fprintf(stderr, "no preview cell lies wholly inside a display\n");
    return 1;
  }
  std::printf(
      "%d preview cells (%d exact) equal the single-process render's box filter "
      "within %d\n",
      checked, exact, worst);
  return 0;
}

// Every display's capture of `frame` in `dir` (and the wall preview, unless `only` names one
// display) against its rectangle of `full`, a single-process render of `layout`'s canvas.
// `preview`: the folder holds the wall preview too (a job's captures, not the wall's own).
int compareCaptures(const wall::Layout& layout, const std::string& dir, const wall::Image& full,
                    std::uint32_t frame, const std::string& only, bool preview = true) {
  if (full.width != layout.canvasWidth || full.height != layout.canvasHeight) {
    std::fprintf(stderr, "reference is %dx%d, the canvas %dx%d\n", full.width, full.height,
                 layout.canvasWidth, layout.canvasHeight);
    return 1;
  }
  const bool withPreview = preview && only.empty();
  const wall::Image wallPreview =
      withPreview ? wall::readPng(wall::wallPreviewPath(dir, frame)) : wall::Image(1, 1);
  bool found = false;
  for (const wall::Display& d : layout.displays) {
    if (!only.empty() && d.name != only) continue;
    found = true;
    const wall::Image expected = wall::crop(full, d.rect);
    const wall::Image got = wall::readPng(wall::displayCapturePath(dir, d.name, frame));
    const wall::Image shown = withPreview ? wall::crop(wallPreview, d.rect) : got;
    for (const auto* image : {&got, &shown}) {
      if (image->width != expected.width || image->height != expected.height) {
        std::fprintf(stderr, "display %s: capture is %dx%d, its rectangle %dx%d\n", d.name.c_str(),
                     image->width, image->height, expected.width, expected.height);
        return 1;
      }
      for (int y = 0; y < expected.height; ++y)
        for (int x = 0; x < expected.width; ++x)
          if (image->at(x, y) != expected.at(x, y)) {
            std::fprintf(stderr, "display %s (%s), pixel (%d, %d): 0x%08x, single process 0x%08x\n",
                         d.name.c_str(), image == &got ? "capture" : "wall preview", x, y,
                         image->at(x, y), expected.at(x, y));
            return 1;
          }
    }
  }
  if (!found) {
    std::fprintf(stderr, "the layout has no display '%s'\n", only.c_str());
    return 1;
  }
  if (only.empty())
    std::printf("%zu displays of frame %u equal the single-process render\n",
                layout.displays.size(), frame);
  else
    std::printf("display %s of frame %u equals the single-process render\n", only.c_str(), frame);
  return 0;
}

// --composite with FRAME `any`: per display, some capture in its folder equals its rectangle of
// `full`. Prints which frame matched per display.
int compareAnyCapture(const wall::Layout& layout, const std::string& dir, const wall::Image& full) {
  for (const wall::Display& d : layout.displays) {
    const wall::Image expected = wall::crop(full, d.rect);
    std::set<std::string> names;
    const std::filesystem::path folder = std::filesystem::path(dir) / d.name;
    if (std::filesystem::is_directory(folder))
      for (const auto& entry : std::filesystem::directory_iterator(folder)) {
        const std::string name = entry.path().filename().string();
        if (name.rfind("frame-", 0) == 0 && name.size() > 4 &&
            name.substr(name.size() - 4) == ".png")
          names.insert(name);
      }
    std::string matched, lastMismatch;
    for (const std::string& name : names) {
      const wall::Image got = wall::readPng((folder / name).string());
      if (got == expected) {
        matched = name;
        break;
      }
      if (got.width != expected.width || got.height != expected.height) {
        lastMismatch = name + " is " + std::to_string(got.width) + "x" + std::to_string(got.height);
        continue;
      }
      for (int y = 0; y < expected.height && lastMismatch.rfind(name, 0) != 0; ++y)
        for (int x = 0; x < expected.width; ++x)
          if (got.at(x, y) != expected.at(x, y)) {
            char text[160];
            std::snprintf(text, sizeof text, ", pixel (%d, %d): 0x%08x, expected 0x%08x", x, y,
                          got.at(x, y), expected.at(x, y));
            lastMismatch = name + text;
            break;
          }
    }
    if (matched.empty()) {
      std::fprintf(stderr, "display %s: none of its %zu captures equals the composite (last: %s)\n",
                   d.name.c_str(), names.size(), lastMismatch.c_str());
      return 1;
    }
    std::printf("display %s: %s equals the composite (%zu captures)\n", d.name.c_str(),
                matched.c_str(), names.size());
  }
  return 0;
}

std::vector<std::string> splitPlus(const std::string& text) {
  std::vector<std::string> out;
  std::size_t from = 0;
  while (true) {
    const std::size_t at = text.find('+', from);
    out.push_back(text.substr(from, at == std::string::npos ? std::string::npos : at - from));
    if (at == std::string::npos) return out;
    from = at + 1;
  }
}

}  // namespace

// --thumbnail: the expected thumbnail, pixel by pixel, and the comparison (exact).
int compareThumbnail(const wall::Layout& layout, const dfb::Region& window,
                     const wall::Image& thumbnail, const wall::Image& render, int side) {
  if (render.width != window.width() || render.height != window.height())
    throw std::runtime_error("the render is not the window's size");
  const int f = (std::max(window.width(), window.height()) + side - 1) / side;
  const int w = (window.width() + f - 1) / f, h = (window.height() + f - 1) / f;
  if (thumbnail.width != w || thumbnail.height != h) {
    std::fprintf(stderr, "thumbnail is %dx%d, expected %dx%d (factor %d)\n", thumbnail.width,
                 thumbnail.height, w, h, f);
    return 1;
  }
  const auto shown = [&](int x, int y) {  // canvas pixel on a display
    for (const wall::Display& d : layout.displays)
      if (x >= d.rect.x0 && x < d.rect.x1 && y >= d.rect.y0 && y < d.rect.y1) return true;
    return false;
  };
  int mismatches = 0, empty = 0;
  for (int cy = 0; cy < h; ++cy)
    for (int cx = 0; cx < w; ++cx) {
      std::uint64_t sum[4] = {0, 0, 0, 0}, n = 0;
      for (int y = cy * f; y < std::min((cy + 1) * f, window.height()); ++y)
        for (int x = cx * f; x < std::min((cx + 1) * f, window.width()); ++x) {
          if (!shown(window.x0 + x, window.y0 + y)) continue;
          const std::uint32_t p = render.at(x, y);
          for (int c = 0; c < 4; ++c) sum[c] += (p >> (8 * c)) & 0xffu;
          ++n;
        }
      std::uint32_t expected = 0;
      if (n == 0) ++empty;
      for (int c = 0; n > 0 && c < 4; ++c)
        expected |= static_cast<std::uint32_t>((sum[c] + n / 2) / n) << (8 * c);
      if (thumbnail.at(cx, cy) != expected && mismatches++ < 5)
        std::fprintf(stderr, "thumbnail cell (%d, %d) is %08x, expected %08x (%d pixels)\n", cx, cy,
                     thumbnail.at(cx, cy), expected, static_cast<int>(n));
    }
  if (mismatches) {
    std::fprintf(stderr, "%d of %d thumbnail cells differ\n", mismatches, w * h);
    return 1;
  }
  std::printf("thumbnail %dx%d (factor %d) equals the render's box filter, %d cells on bezels\n", w,
              h, f, empty);
  return 0;
}

int main(int argc, char** argv) {
  // "W WIDTHxHEIGHT" for the test scripts; --displays: a line "NAME X Y WIDTH HEIGHT" per display.
  if (argc == 3 && (std::string(argv[1]) == "--info" || std::string(argv[1]) == "--displays")) {
    try {
      const wall::Layout layout = wall::loadLayout(argv[2]);
      if (std::string(argv[1]) == "--info")
        std::printf("%d %dx%d\n", layout.processCount, layout.canvasWidth, layout.canvasHeight);
      else
        for (const wall::Display& d : layout.displays)
          std::printf("%s %d %d %d %d\n", d.name.c_str(), d.rect.x0, d.rect.y0, d.rect.width(),
                      d.rect.height());
      return 0;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "compare_captures: %s\n", e.what());
      return 1;
    }
  }
  if ((argc == 5 || argc == 6) && std::string(argv[1]) == "--preview") {
    try {
      wall::Layout layout = wall::loadLayout(argv[2]);
      if (argc == 6)
        layout = wall::windowLayout(layout,
                                    wall::resolveWindow(layout, wall::parseWindowRequest(argv[5])));
      return comparePreview(layout, wall::readPng(argv[3]), wall::readPng(argv[4]));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "compare_captures: %s\n", e.what());
      return 1;
    }
  }
  if (argc == 4 && std::string(argv[1]) == "--raw") {
    try {
      const wall::Image image = wall::readPng(argv[2]);
      FILE* out = std::fopen(argv[3], "wb");
      if (!out) throw std::runtime_error(std::string(argv[3]) + ": cannot write it");
      std::fwrite(image.pixels.data(), sizeof(std::uint32_t), image.pixels.size(), out);
      std::fclose(out);
      std::printf("%d %d\n", image.width, image.height);
      return 0;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "compare_captures: %s\n", e.what());
      return 1;
    }
  }
  if (argc == 3 && std::string(argv[1]) == "--colors") {
    try {
      const wall::Image image = wall::readPng(argv[2]);
      std::set<std::uint32_t> colors(image.pixels.begin(), image.pixels.end());
      std::printf("%zu\n", colors.size());
      return 0;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "compare_captures: %s\n", e.what());
      return 1;
    }
  }
  if (argc == 7 && std::string(argv[1]) == "--window") {
    try {
      const wall::Layout wall = wall::loadLayout(argv[3]);
      const wall::WindowRequest request = wall::parseWindowRequest(argv[2]);
      const wall::Layout seen = wall::windowLayout(wall, wall::resolveWindow(wall, request));
      return compareCaptures(seen, argv[4], wall::readPng(argv[5]),
                             static_cast<std::uint32_t>(std::stoul(argv[6])), "");
    } catch (const std::exception& e) {
      std::fprintf(stderr, "compare_captures: %s\n", e.what());
      return 1;
    }
  }
  if (argc == 7 && std::string(argv[1]) == "--thumbnail") {
    try {
      const wall::Layout wall = wall::loadLayout(argv[3]);
      const dfb::Region window = wall::resolveWindow(wall, wall::parseWindowRequest(argv[2]));
      return compareThumbnail(wall, window, wall::readPng(argv[4]), wall::readPng(argv[5]),
                              std::stoi(argv[6]));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "compare_captures: %s\n", e.what());
      return 1;
    }
  }
  if (argc == 8 && std::string(argv[1]) == "--composite") {
    try {
      const wall::Layout wall = wall::loadLayout(argv[3]);
      const std::vector<std::string> windows = splitPlus(argv[2]), pngs = splitPlus(argv[5]);
      if (windows.size() != pngs.size())
        throw std::runtime_error("as many renders as windows, please");
      const std::string b = argv[7];
      if (b.size() != 7 || b[0] != '#') throw std::runtime_error("background: #rrggbb");
      const auto rgb = static_cast<std::uint32_t>(std::stoul(b.substr(1), nullptr, 16));
      wall::Image canvas(
          wall.canvasWidth, wall.canvasHeight,
          wall::rgba8(static_cast<std::uint8_t>(rgb >> 16), static_cast<std::uint8_t>(rgb >> 8),
                      static_cast<std::uint8_t>(rgb)));
      for (std::size_t i = 0; i < windows.size(); ++i) {
        const dfb::Region window = wall::resolveWindow(wall, wall::parseWindowRequest(windows[i]));
        const wall::Image part = wall::readPng(pngs[i]);
        if (part.width != window.width() || part.height != window.height())
          throw std::runtime_error(pngs[i] + " is not the window's size");
        wall::blit(canvas, window.x0, window.y0, part.pixels.data(), part.width, part.height);
      }
      if (std::string(argv[6]) == "any") return compareAnyCapture(wall, argv[4], canvas);
      return compareCaptures(wall, argv[4], canvas, static_cast<std::uint32_t>(std::stoul(argv[6])),
                             "", false);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "compare_captures: %s\n", e.what());
      return 1;
    }
  }
  if (argc != 5 && argc != 6) {
    std::fprintf(stderr, "usage: %s LAYOUT CAPTURE_DIR FULL_CANVAS_PNG FRAME [DISPLAY]\n", argv[0]);
    return 2;
  }
  try {
    return compareCaptures(wall::loadLayout(argv[1]), argv[2], wall::readPng(argv[3]),
                           static_cast<std::uint32_t>(std::stoul(argv[4])),
                           argc == 6 ? argv[5] : "");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "compare_captures: %s\n", e.what());
    return 1;
  }
}
