#pragma once
// A test pattern that traces no rays: a grid of 128-pixel cells labelled "column.row", a ring in
// each cell (round rings mean the aspect ratio is right), a border, colour bars along the bottom
// and a marker that moves with the frame id. Each pixel is a pure function of its canvas
// coordinates and the frame, so a wall shows exactly where its displays and bezels cut the
// canvas, and benchmarks make pixel delivery the bottleneck. With RenderSettings::displayPixels
// it writes RGBA8 display pixels straight away (a palette tone-mapped once), so neither float
// pixels nor per-pixel tone mapping are spent on it.
#include <vector>

#include "renderers/Renderer.h"

namespace renderers {

class PatternRenderer final : public Renderer {
 public:
  explicit PatternRenderer(const RenderSettings& settings);
  void beginFrame(const dfb::FrameInfo& frame, const CameraDesc& camera) override;
  void render(const dfb::Region& region, std::uint32_t accumulationId, std::uint32_t firstSample,
              std::uint32_t samples, dfb::Tile& out) const override;

  static constexpr int kCell = 128;

 private:
  int width_, height_;
  std::uint32_t frameId_ = 0;
  std::vector<std::uint32_t> displayPalette_;  // with RenderSettings::displayPixels
};

}  // namespace renderers
