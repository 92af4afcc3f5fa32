#include "renderers/PatternRenderer.h"

#include <array>
#include <cmath>
#include <cstdlib>
#include <string>

#include "renderers/Math.h"

namespace renderers {
namespace {

// 3x5 glyphs, one row per 3 bits, top row first: digits, then '.'.
constexpr std::array<std::array<unsigned char, 5>, 11> kGlyphs{{
    {7, 5, 5, 5, 7},
    {2, 6, 2, 2, 7},
    {7, 1, 7, 4, 7},
    {7, 1, 7, 1, 7},
    {5, 5, 7, 1, 1},
    {7, 4, 7, 1, 7},
    {7, 4, 7, 5, 7},
    {7, 1, 1, 1, 1},
    {7, 5, 7, 5, 7},
    {7, 5, 7, 1, 7},
    {0, 0, 0, 0, 2},
}};
constexpr int kScale = 4, kAdvance = 4 * kScale, kMargin = 8;

// Whether (x, y), relative to the label's top-left corner, is ink of `text`.
bool labelInk(const std::string& text, int x, int y) {
  if (x < 0 || y < 0 || y >= 5 * kScale) return false;
  const int i = x / kAdvance, gx = (x % kAdvance) / kScale, gy = y / kScale;
  if (i >= static_cast<int>(text.size()) || gx >= 3) return false;
  const char c = text[i];
  const auto& glyph = kGlyphs[c == '.' ? 10 : c - '0'];
  return (glyph[gy] >> (2 - gx)) & 1;
}

// Every colour the pattern uses: a pixel is an index into this palette.
enum Colour : std::uint8_t { kDark, kLight, kRing, kGrid, kInk, kBorder, kMarker, kBar0 };
const Vec3 kPalette[kBar0 + 8] = {Vec3{0.05f},        Vec3{0.10f},           {0.3f, 0.3f, 0.6f},
                                  Vec3{0.8f},         {1.0f, 0.9f, 0.2f},    {1.0f, 0.1f, 0.1f},
                                  {0.1f, 1.0f, 0.1f}, {0.75f, 0.75f, 0.75f}, {0.75f, 0.75f, 0},
                                  {0, 0.75f, 0.75f},  {0, 0.75f, 0},         {0.75f, 0, 0.75f},
                                  {0.75f, 0, 0},      {0, 0, 0.75f},         {0, 0, 0}};
constexpr int kColours = kBar0 + 8;

}  // namespace

PatternRenderer::PatternRenderer(const RenderSettings& settings)
    : width_(settings.width), height_(settings.height) {
  // Display pixels: each palette colour tone-mapped once, exactly as the DFB would per pixel.
  if (settings.displayPixels)
    for (int i = 0; i < kColours; ++i) {
      const float rgba[4] = {kPalette[i].x, kPalette[i].y, kPalette[i].z, 1.0f};
      displayPalette_.push_back(dfb::toneMapPixel(rgba, *settings.displayPixels));
    }
}

void PatternRenderer::beginFrame(const dfb::FrameInfo& frame, const CameraDesc& /*camera*/) {
  frameId_ = frame.frameId;
}

void PatternRenderer::render(const dfb::Region& region, std::uint32_t accumulationId,
                             std::uint32_t firstSample, std::uint32_t samples,
                             dfb::Tile& out) const {
  prepareTile(region, accumulationId, firstSample, samples, out);
  const bool display = !displayPalette_.empty();
  if (display) {  // RGBA8 only: no float pixels to write, none to tone-map
    out.color.clear();
    out.rgba8.resize(static_cast<std::size_t>(region.pixelCount()));
  }
  const int barTop = height_ - height_ / 8;
  const int markerSize = 32;
  const int markerX = static_cast<int>((frameId_ * 16u) % static_cast<unsigned>(width_));
  const int markerY = height_ / 2 - markerSize / 2;
  float* px = out.color.data();
  std::uint32_t* px8 = out.rgba8.data();
  // The cell label, rebuilt only when the cell changes: a string per pixel made this renderer,
  // meant to cost nothing next to delivery, slower than tone mapping the whole canvas.
  std::string label;
  int labelCx = -1, labelCy = -1;
  for (int y = region.y0; y < region.y1; ++y) {
    for (int x = region.x0; x < region.x1; ++x) {
      const int cx = x / kCell, cy = y / kCell, lx = x % kCell, ly = y % kCell;
      int c = ((cx + cy) & 1) ? kLight : kDark;
      const float dx = static_cast<float>(lx) - kCell / 2 + 0.5f;
      const float dy = static_cast<float>(ly) - kCell / 2 + 0.5f;
      if (std::abs(std::sqrt(dx * dx + dy * dy) - 0.35f * kCell) < 1.0f) c = kRing;
      if (lx < 2 || ly < 2) c = kGrid;
      if (ly >= kMargin && ly < kMargin + 5 * kScale && lx >= kMargin) {
        if (cx != labelCx || cy != labelCy) {
          label = std::to_string(cx) + "." + std::to_string(cy);
          labelCx = cx, labelCy = cy;
        }
        if (labelInk(label, lx - kMargin, ly - kMargin)) c = kInk;
      }
      if (y >= barTop) c = kBar0 + std::min(7, 8 * x / width_);
      if (x < 4 || y < 4 || x >= width_ - 4 || y >= height_ - 4) c = kBorder;
      if (x >= markerX && x < markerX + markerSize && y >= markerY && y < markerY + markerSize)
        c = kMarker;
      if (display) {
        *px8++ = displayPalette_[static_cast<std::size_t>(c)];
      } else {
        const Vec3& v = kPalette[c];
        px[0] = v.x, px[1] = v.y, px[2] = v.z, px[3] = 1.0f;
        px += 4;
      }
    }
  }
}

}  // namespace renderers
