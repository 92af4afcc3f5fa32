#include <gtest/gtest.h>

#include "base/Error.h"
#include "renderers/BuiltinScenes.h"
#include "renderers/PatternRenderer.h"
#include "renderers/Scene.h"
#include "tests/renderers/RenderTestUtil.h"

namespace renderers {
namespace {

const float* pixel(const std::vector<float>& img, int w, int x, int y) {
  return &img[4 * (static_cast<std::size_t>(y) * w + x)];
}

TEST(PatternRenderer, GridBorderBarsAndAMovingMarker) {
  const int w = 320, h = 256;
  PatternRenderer p({w, h, 0, 1});
  p.beginFrame({0, 0}, {});
  const auto f0 = test::renderImage(p, w, h, 64, 2, 1);
  const auto tiled = test::renderImage(p, w, h, 48, 1, 1);
  EXPECT_EQ(f0, tiled);                        // a pure function of canvas coordinates
  EXPECT_EQ(pixel(f0, w, 0, 100)[0], 1.0f);    // red border
  EXPECT_EQ(pixel(f0, w, 128, 100)[1], 0.8f);  // grid line at x = 128
  EXPECT_EQ(pixel(f0, w, 130, 100)[1], pixel(f0, w, 131, 100)[1]);
  EXPECT_EQ(pixel(f0, w, 10, h - 10)[0], 0.75f);     // white bar bottom left
  EXPECT_EQ(pixel(f0, w, w - 20, h - 10)[2], 0.0f);  // black bar bottom right
  // Label "0.0" at the top-left of cell 0: ink in the first glyph's top row.
  EXPECT_EQ(pixel(f0, w, 8 + 1, 8 + 1)[0], 1.0f);
  EXPECT_EQ(pixel(f0, w, 8 + 1, 8 + 1)[2], 0.2f);
  // The marker sits at x = 16 * frame, mid-height, and moves.
  EXPECT_EQ(pixel(f0, w, 10, h / 2)[1], 1.0f);
  p.beginFrame({5, 0}, {});
  const auto f5 = test::renderImage(p, w, h, 64, 2, 1);
  EXPECT_NE(pixel(f5, w, 10, h / 2)[1], 1.0f);
  EXPECT_EQ(pixel(f5, w, 90, h / 2)[1], 1.0f);
}

// Asked for display pixels, the pattern writes RGBA8 only, each pixel exactly what the DFB's
// tone mapping of its float pixel gives, so both paths show the same wall bit for bit.
TEST(PatternRenderer, DisplayPixelsEqualToneMappedFloatPixels) {
  const int w = 300, h = 200;
  dfb::ToneMapSettings toneMap;
  toneMap.exposure = 1.3f;
  toneMap.filmic = true;
  RenderSettings floats{w, h, 0, 1};
  RenderSettings display = floats;
  display.displayPixels = toneMap;
  PatternRenderer linear(floats), direct(display);
  linear.beginFrame({3, 0}, {});
  direct.beginFrame({3, 0}, {});
  const dfb::Region region{40, 60, 104, 124};  // covers grid lines, a ring and a label
  dfb::Tile a, b;
  linear.render(region, 0, 0, 1, a);
  direct.render(region, 0, 0, 1, b);
  EXPECT_TRUE(b.color.empty());
  ASSERT_EQ(b.rgba8.size(), static_cast<std::size_t>(region.pixelCount()));
  for (std::size_t i = 0; i < b.rgba8.size(); ++i)
    ASSERT_EQ(b.rgba8[i], dfb::toneMapPixel(&a.color[4 * i], toneMap)) << "pixel " << i;
}

TEST(Renderers, MakeByNameAndPrimaryShading) {
  const Scene scene(cornellBox());
  const RenderSettings s{32, 32, 1, 8};
  EXPECT_NE(makeRenderer("pattern", scene, s), nullptr);
  EXPECT_NE(makeRenderer("pathtracer", scene, s), nullptr);
  auto primary = makeRenderer("primary", scene, s);
  const auto img = test::renderImage(*primary, 32, 32, 16, 2, 1);
  // Left edge: the red wall; right edge: the green one; top centre: the light.
  EXPECT_GT(pixel(img, 32, 1, 16)[0], 3 * pixel(img, 32, 1, 16)[1]);
  EXPECT_GT(pixel(img, 32, 30, 16)[1], 2 * pixel(img, 32, 30, 16)[0]);
  float brightest = 0;
  for (int y = 0; y < 8; ++y) brightest = std::max(brightest, pixel(img, 32, 16, y)[0]);
  EXPECT_EQ(brightest, 17.0f);
  try {
    makeRenderer("raster", scene, s);
    FAIL();
  } catch (const base::Error& e) {
    EXPECT_STREQ(e.what(),
                 "unknown renderer 'raster' (choose pathtracer, primary, pattern or scivis)");
  }
}

}  // namespace
}  // namespace renderers
