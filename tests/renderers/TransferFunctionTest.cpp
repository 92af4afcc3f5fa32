// Transfer functions: interpolation between control points, the presets against the published
// maps, and the baked table (interpolation and a conservative maximum opacity).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "base/Error.h"
#include "renderers/TransferFunction.h"

namespace renderers {
namespace {

void expectColorNear(Vec3 a, Vec3 b, float tolerance) {
  EXPECT_NEAR(a.x, b.x, tolerance);
  EXPECT_NEAR(a.y, b.y, tolerance);
  EXPECT_NEAR(a.z, b.z, tolerance);
}

TEST(TransferFunction, LinearBetweenPointsConstantOutsideStepsAtEqualValues) {
  TransferFunction tf;
  tf.colors = {{10, {1, 0, 0}}, {20, {0, 0, 1}}};
  tf.opacities = {{10, 0}, {15, 0.5f}, {15, 0.9f}, {30, 0.1f}};
  expectColorNear(tf.color(12.5f), {0.75f, 0, 0.25f}, 1e-6f);
  EXPECT_EQ(tf.color(-100), (Vec3{1, 0, 0}));
  EXPECT_EQ(tf.color(1e9f), (Vec3{0, 0, 1}));
  EXPECT_NEAR(tf.opacity(12.5f), 0.25f, 1e-6f);
  EXPECT_NEAR(tf.opacity(14.999f), 0.5f, 1e-3f);
  EXPECT_EQ(tf.opacity(15), 0.9f);  // the step: the later point wins
  EXPECT_NEAR(tf.opacity(22.5f), 0.5f, 1e-6f);
  EXPECT_EQ(tf.opacity(31), 0.1f);
  EXPECT_EQ(tf.opacity(NAN), 0.0f);  // NaN: the first point
  const TransferFunction empty;
  EXPECT_EQ(empty.color(3), (Vec3{1, 1, 1}));
  EXPECT_EQ(empty.opacity(3), 1.0f);
}

TEST(TransferFunction, PresetsFollowThePublishedMaps) {
  EXPECT_EQ(transferFunctionPresetNames(),
            (std::vector<std::string>{"cool-warm", "viridis", "inferno", "grayscale", "rainbow"}));
  // Cool-warm: ParaView's "Cool to Warm" ends and Moreland's grey midpoint (as VTK's Msh
  // interpolation reproduces them: within 2e-4).
  const TransferFunction cw = transferFunctionPreset("cool-warm", 37, 277, 0.4f);
  expectColorNear(cw.color(37), {0.231373f, 0.298039f, 0.752941f}, 2e-4f);
  expectColorNear(cw.color(157), {0.865003f, 0.865003f, 0.865003f}, 2e-4f);
  expectColorNear(cw.color(277), {0.705882f, 0.0156863f, 0.14902f}, 2e-4f);
  // Between the preset's points, within 2.1/255 of VTK's own diverging interpolation
  // (vtkColorTransferFunction, SetColorSpaceToDiverging, at s = 0.3 and 0.51).
  expectColorNear(cw.color(37 + 0.3f * 240), {0.622445f, 0.746200f, 0.999145f}, 2.1f / 255);
  expectColorNear(cw.color(37 + 0.51f * 240), {0.876083f, 0.860334f, 0.851037f}, 2.1f / 255);
  EXPECT_EQ(cw.opacity(37), 0.0f);
  EXPECT_NEAR(cw.opacity(157), 0.2f, 1e-6f);
  EXPECT_EQ(cw.opacity(277), 0.4f);
  EXPECT_EQ(cw.valueMin, 37.0f);
  EXPECT_EQ(cw.valueMax, 277.0f);
  // Viridis and inferno: matplotlib's first, middle (entry 128 of 256) and last colours.
  const TransferFunction viridis = transferFunctionPreset("viridis", 0, 255);
  expectColorNear(viridis.color(0), {0.267004f, 0.004874f, 0.329415f}, 1e-6f);
  expectColorNear(viridis.color(128), {0.127568f, 0.566949f, 0.550556f}, 0.5f / 255);
  expectColorNear(viridis.color(255), {0.993248f, 0.906157f, 0.143936f}, 1e-6f);
  const TransferFunction inferno = transferFunctionPreset("inferno", 0, 1);
  expectColorNear(inferno.color(0), {0.001462f, 0.000466f, 0.013866f}, 1e-6f);
  expectColorNear(inferno.color(1), {0.988362f, 0.998364f, 0.644924f}, 1e-6f);
  const TransferFunction gray = transferFunctionPreset("grayscale", -1, 1);
  expectColorNear(gray.color(0), {0.5f, 0.5f, 0.5f}, 1e-6f);
  const TransferFunction rainbow = transferFunctionPreset("rainbow", 0, 4);
  expectColorNear(rainbow.color(0), {0, 0, 1}, 0);
  expectColorNear(rainbow.color(2), {0, 1, 0}, 0);
  expectColorNear(rainbow.color(3.5f), {1, 0.5f, 0}, 1e-6f);
  EXPECT_EQ(rainbow.opacity(4), 1.0f);  // default maxOpacity

  try {
    transferFunctionPreset("jet", 0, 1);
    ADD_FAILURE() << "no error for an unknown preset";
  } catch (const base::Error& e) {
    EXPECT_STREQ(e.what(),
                 "unknown transfer function preset 'jet' (presets: cool-warm, viridis, "
                 "inferno, grayscale, rainbow)");
  }
}

TEST(TransferTable, InterpolatesLinearlyAndClamps) {
  TransferFunction tf;
  tf.valueMin = 0;
  tf.valueMax = 10;
  tf.colors = {{0, {0, 0, 0}}, {10, {1, 0.5f, 0.25f}}};
  tf.opacities = {{0, 0}, {10, 1}};
  const TransferTable table(tf, 11);
  EXPECT_EQ(table.valueMin(), 0.0f);
  EXPECT_EQ(table.valueMax(), 10.0f);
  float rgba[4];
  table.lookup(2.5f, rgba);
  EXPECT_NEAR(rgba[0], 0.25f, 1e-6f);
  EXPECT_NEAR(rgba[1], 0.125f, 1e-6f);
  EXPECT_NEAR(rgba[2], 0.0625f, 1e-6f);
  EXPECT_NEAR(rgba[3], 0.25f, 1e-6f);
  table.lookup(-5, rgba);
  EXPECT_EQ(rgba[3], 0.0f);
  table.lookup(50, rgba);
  EXPECT_EQ(rgba[0], 1.0f);
  EXPECT_EQ(rgba[3], 1.0f);
  table.lookup(NAN, rgba);
  EXPECT_EQ(rgba[3], 0.0f);
  // The preset through the table stays within a table step of the function.
  const TransferFunction cw = transferFunctionPreset("cool-warm", 37, 277, 0.4f);
  const TransferTable cwTable(cw);
  for (float v = 37; v <= 277; v += 1.37f) {
    cwTable.lookup(v, rgba);
    expectColorNear({rgba[0], rgba[1], rgba[2]}, cw.color(v), 2e-3f);
    EXPECT_NEAR(rgba[3], cw.opacity(v), 1e-5f);
  }
  tf.valueMax = 0;
  EXPECT_THROW(TransferTable{tf}, base::Error);
  const TransferTable none;
  none.lookup(3, rgba);
  EXPECT_EQ(rgba[3], 0.0f);
  EXPECT_EQ(none.maxOpacity(0, 10), 0.0f);
}

TEST(TransferTable, MaxOpacityIsNeverBelowTheTrueMaximum) {
  // Narrow spikes between table entries: the table's own samples miss them, the maximum must not.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0, 1);
  for (int trial = 0; trial < 20; ++trial) {
    TransferFunction tf;
    tf.valueMin = -50;
    tf.valueMax = 150;
    float v = -60;
    while (v < 160) {
      tf.opacities.emplace_back(v, unit(rng) < 0.6f ? 0.0f : unit(rng));
      v += unit(rng) < 0.5f ? 0.05f * unit(rng) : 10 * unit(rng);
    }
    const TransferTable table(tf, 64 + trial * 13);
    for (int q = 0; q < 300; ++q) {
      float lo = -60 + 220 * unit(rng), hi = lo + (unit(rng) < 0.3f ? 0.1f : 40) * unit(rng);
      float truth = 0, tableMax = 0;
      const float clo = std::clamp(lo, tf.valueMin, tf.valueMax);
      const float chi = std::clamp(hi, tf.valueMin, tf.valueMax);
      for (int s = 0; s <= 400; ++s) {
        const float x = clo + (chi - clo) * static_cast<float>(s) / 400;
        float rgba[4];
        table.lookup(x, rgba);
        truth = std::max(truth, tf.opacity(x));
        tableMax = std::max(tableMax, rgba[3]);
      }
      for (const auto& [x, o] : tf.opacities)
        if (x >= clo && x <= chi) truth = std::max(truth, o);
      const float m = table.maxOpacity(lo, hi);
      ASSERT_GE(m, truth) << "[" << lo << ", " << hi << "] trial " << trial;
      ASSERT_GE(m, tableMax) << "[" << lo << ", " << hi << "] trial " << trial;
    }
  }
}

TEST(TransferTable, MaxOpacityIsZeroWhereNothingIsVisible) {
  // Transparent below 100: an interval well below it is empty space; one reaching it is not.
  TransferFunction tf = transferFunctionPreset("viridis", 0, 200);
  tf.opacities = {{100, 0}, {200, 0.8f}};
  const TransferTable table(tf, 1024);
  EXPECT_EQ(table.maxOpacity(0, 99), 0.0f);
  EXPECT_EQ(table.maxOpacity(-1e9f, 50), 0.0f);
  EXPECT_GT(table.maxOpacity(50, 101), 0.0f);
  // Conservative by at most two table segments (200 / 1023 wide) of the 0.008-per-unit slope.
  EXPECT_GE(table.maxOpacity(50, 150), 0.4f);
  EXPECT_LE(table.maxOpacity(50, 150), 0.4f + 2 * 0.008f * 200 / 1023);
  EXPECT_NEAR(table.maxOpacity(190, 1e9f), 0.8f, 1e-6f);
  EXPECT_NEAR(table.maxOpacity(150, 50), table.maxOpacity(50, 150), 0);  // either order
  EXPECT_EQ(table.maxOpacity(NAN, 3), 0.8f);                             // unknown: everything
}

}  // namespace
}  // namespace renderers
