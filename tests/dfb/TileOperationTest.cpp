// Tile operations and tone mapping on their own, without MPI.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "base/Error.h"
#include "dfb/PixelOp.h"
#include "dfb/TileMessage.h"
#include "dfb/TileOperation.h"

namespace dfb {
namespace {

const Region kRegion{64, 0, 100, 20};  // a partial tile at an image edge

Tile constantTile(float value, std::uint32_t accumulationId = 0) {
  Tile t;
  t.reset(kRegion);
  std::fill(t.color.begin(), t.color.end(), value);
  t.accumulationId = accumulationId;
  return t;
}

TEST(WriteOperation, TakesExactlyOneInput) {
  auto op = writeOperation()(kRegion);
  op->newFrame({}, 0, 1);
  EXPECT_TRUE(op->process(constantTile(0.5f)));
  EXPECT_EQ(op->finished().color[7], 0.5f);
  EXPECT_THROW(op->process(constantTile(0.5f)), base::Error);
}

TEST(AccumulateOperation, IsTheRunningMeanAndResetsWithTheEpoch) {
  auto op = accumulateOperation()(kRegion);
  const float values[] = {1.0f, 2.0f, 6.0f, 3.0f};
  float sum = 0;
  for (std::uint32_t f = 0; f < 4; ++f) {
    op->newFrame({f, 0}, f, 1);
    ASSERT_TRUE(op->process(constantTile(values[f], f)));
    sum += values[f];
    EXPECT_FLOAT_EQ(op->finished().color[0], sum / static_cast<float>(f + 1)) << "frame " << f;
  }
  EXPECT_GT(op->error(), 0.0f);
  op->newFrame({4, 1}, 0, 1);  // new epoch: pass 0 again
  ASSERT_TRUE(op->process(constantTile(9.0f, 0)));
  EXPECT_FLOAT_EQ(op->finished().color[0], 9.0f);
  EXPECT_TRUE(std::isinf(op->error())) << "one frame gives no error estimate";
}

// The first frame of an epoch skips the double sums (they are derived later when the epoch goes
// on): the finished tiles and the error must be the bits of the running double sums, frame after
// frame, over random colours with the awkward ones mixed in (-0, denormals, huge; NaN in the
// second epoch only, where it makes every error estimate NaN).
TEST(AccumulateOperation, DeferredSumsGiveTheBitsOfTheRunningSums) {
  auto op = accumulateOperation()(kRegion);
  const size_t n = static_cast<size_t>(kRegion.pixelCount());
  std::mt19937 random(7);
  std::uniform_real_distribution<float> radiance(0.0f, 4.0f);
  const float awkward[] = {-0.0f, 0.0f, std::numeric_limits<float>::denorm_min(), 1e30f,
                           std::numeric_limits<float>::quiet_NaN()};
  const auto luminance = [](const float* c) {
    return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
  };
  for (std::uint32_t epoch = 0; epoch < 2; ++epoch) {
    std::vector<double> sum(4 * n, 0.0), lumSum(n, 0.0), lumSquare(n, 0.0);
    for (std::uint32_t pass = 0; pass < 4; ++pass) {
      Tile input;
      input.reset(kRegion);
      input.accumulationId = pass;
      for (float& v : input.color)
        v = random() % 16 == 0 ? awkward[random() % (epoch == 0 ? 4 : 5)] : radiance(random);
      op->newFrame({epoch * 4 + pass, epoch}, pass, 1);
      ASSERT_TRUE(op->process(Tile(input)));
      const double invTotal = 1.0 / static_cast<double>(pass + 1);
      double relativeError = 0;
      for (size_t p = 0; p < n; ++p) {
        float frame[4];
        for (int c = 0; c < 4; ++c) frame[c] = 1.0f * input.color[4 * p + static_cast<size_t>(c)];
        for (int c = 0; c < 4; ++c) {
          double& s = sum[4 * p + static_cast<size_t>(c)];
          s = (pass == 0 ? 0.0 : s) + static_cast<double>(frame[c]);
          const float expected = static_cast<float>(s * invTotal);
          const float got = op->finished().color[4 * p + static_cast<size_t>(c)];
          ASSERT_EQ(std::bit_cast<std::uint32_t>(got), std::bit_cast<std::uint32_t>(expected))
              << "epoch " << epoch << ", pass " << pass << ", pixel " << p << " channel " << c
              << ": " << got << " vs " << expected;
        }
        const double lum = static_cast<double>(luminance(frame) * 1.0f);
        lumSum[p] = (pass == 0 ? 0.0 : lumSum[p]) + lum;
        lumSquare[p] = (pass == 0 ? 0.0 : lumSquare[p]) + lum * lum;
        if (pass > 0) {
          const double k = pass + 1.0, mean = lumSum[p] / k;
          const double variance = std::max(0.0, lumSquare[p] / k - mean * mean);
          relativeError += std::sqrt(variance / k) / std::sqrt(std::max(mean, 1e-3));
        }
      }
      const float error = pass > 0 ? static_cast<float>(relativeError / static_cast<double>(n))
                                   : std::numeric_limits<float>::infinity();
      if (std::isnan(error))
        EXPECT_TRUE(std::isnan(op->error())) << "pass " << pass;
      else
        EXPECT_EQ(op->error(), error) << "pass " << pass;
    }
  }
}

TEST(AccumulateOperation, RedundantInputsGiveTheSameBytesInAnyOrder) {
  std::mt19937 random(5);
  std::uniform_real_distribution<float> value(0.0f, 10.0f);
  std::vector<Tile> inputs;
  for (std::uint32_t s = 0; s < 5; ++s) {
    Tile t;
    t.reset(kRegion);
    for (float& c : t.color) c = value(random);
    t.sequence = s * 16;
    t.weight = 1 + s % 3;
    inputs.push_back(t);
  }
  std::vector<float> reference;
  for (int trial = 0; trial < 20; ++trial) {
    std::shuffle(inputs.begin(), inputs.end(), random);
    auto op = accumulateOperation()(kRegion);
    op->newFrame({}, 0, static_cast<int>(inputs.size()));
    for (size_t i = 0; i < inputs.size(); ++i)
      EXPECT_EQ(op->process(Tile(inputs[i])), i + 1 == inputs.size());
    if (trial == 0) {
      reference = op->finished().color;
      // And it is the weighted mean.
      double expected = 0, weight = 0;
      for (const Tile& t : inputs) expected += t.weight * t.color[0], weight += t.weight;
      EXPECT_NEAR(reference[0], expected / weight, 1e-5);
    } else {
      EXPECT_EQ(op->finished().color, reference) << "trial " << trial;
    }
  }
}

TEST(AlphaBlendOperation, WaitsForTheWholeTreeAndBlendsByDepth) {
  auto op = alphaBlendOperation()(kRegion);
  op->newFrame({}, 0, 1);
  auto fragment = [](int generation, int children, float depth, float r, float a,
                     std::uint32_t seq) {
    Tile t;
    t.reset(kRegion, true);
    for (size_t p = 0; p < t.depth.size(); ++p) {
      t.depth[p] = depth;
      t.color[4 * p + 0] = r * a;  // premultiplied
      t.color[4 * p + 3] = a;
    }
    t.generation = generation;
    t.children = children;
    t.sequence = seq;
    return t;
  };
  // Children first, the root last: the tree is only known when the root arrives.
  EXPECT_FALSE(op->process(fragment(1, 0, 5.0f, 1.0f, 0.5f, 1)));
  EXPECT_FALSE(op->process(fragment(1, 0, 2.0f, 0.0f, 0.5f, 2)));
  EXPECT_TRUE(op->process(fragment(0, 2, 9.0f, 1.0f, 1.0f, 0)));
  // Front to back: depth 2 (r 0, a .5), depth 5 (r 1, a .5), depth 9 (r 1, a 1).
  const float r = 0.0f + 0.5f * (0.5f + 0.5f * 1.0f);
  EXPECT_FLOAT_EQ(op->finished().color[0], r);
  EXPECT_FLOAT_EQ(op->finished().color[3], 1.0f);
  EXPECT_FLOAT_EQ(op->finished().depth[0], 2.0f);
}

// A tree of two tiles (the background and one brick: the common case) takes a path of its own;
// it must give the bits of the front-to-back composite, ties in depth to the root, empty depth
// as infinitely far, -0 colours as +0 (the blend adds to 0).
TEST(AlphaBlendOperation, TwoTilesBlendAsTheSerialCompositeBitForBit) {
  std::mt19937 random(11);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const float inf = std::numeric_limits<float>::infinity();
  for (int trial = 0; trial < 3; ++trial) {
    Tile root, child;
    root.reset(kRegion, true), child.reset(kRegion, true);
    if (trial == 0) root.depth.clear();  // a background tile: no depth
    for (Tile* t : {&root, &child})
      for (size_t p = 0; p < t->color.size() / 4; ++p) {
        const float a = unit(random) < 0.3f ? 1.0f : unit(random);
        for (int c = 0; c < 3; ++c)
          t->color[4 * p + static_cast<size_t>(c)] = unit(random) < 0.1f ? -0.0f : a * unit(random);
        t->color[4 * p + 3] = a;
        if (!t->depth.empty()) {
          const float d = unit(random);
          t->depth[p] = d < 0.3f ? 1.0f : (d < 0.6f ? 2.0f : (d < 0.8f ? inf : d));
        }
      }
    root.generation = 0, root.children = 1;
    child.generation = 1, child.children = 0;
    auto op = alphaBlendOperation()(kRegion);
    op->newFrame({}, 0, 1);
    EXPECT_FALSE(op->process(Tile(child)));
    ASSERT_TRUE(op->process(Tile(root)));
    const Tile& got = op->finished();
    for (size_t p = 0; p < got.depth.size(); ++p) {
      // The definition: the fragments in tree order, stably sorted by depth, composited front
      // to back onto nothing.
      std::vector<std::pair<float, const float*>> fragments = {
          {root.depth.empty() ? inf : root.depth[p], &root.color[4 * p]},
          {child.depth[p], &child.color[4 * p]}};
      std::stable_sort(fragments.begin(), fragments.end(),
                       [](const auto& a, const auto& b) { return a.first < b.first; });
      float want[4] = {0, 0, 0, 0};
      for (const auto& fragment : fragments) {
        const float transmitted = 1.0f - want[3];
        for (int k = 0; k < 4; ++k) want[k] += transmitted * fragment.second[k];
      }
      ASSERT_EQ(std::memcmp(want, &got.color[4 * p], sizeof want), 0)
          << "trial " << trial << " pixel " << p;
      ASSERT_EQ(std::memcmp(&fragments.front().first, &got.depth[p], sizeof(float)), 0);
    }
  }
}

// A lone root (a tile with one brick that blended the background in itself): its colours added
// to 0 (-0 becomes +0), its depth as it is, or infinity where it has none.
TEST(AlphaBlendOperation, ALoneRootIsItsOwnBlend) {
  for (const bool withDepth : {true, false}) {
    Tile root;
    root.reset(kRegion, true);
    for (size_t i = 0; i < root.color.size(); ++i)
      root.color[i] = i % 7 == 0 ? -0.0f : 0.25f * static_cast<float>(i % 5);
    for (size_t p = 0; p < root.depth.size(); ++p) root.depth[p] = static_cast<float>(p % 3);
    if (!withDepth) root.depth.clear();
    auto op = alphaBlendOperation()(kRegion);
    op->newFrame({}, 0, 1);
    ASSERT_TRUE(op->process(Tile(root)));
    const Tile& got = op->finished();
    ASSERT_EQ(got.color.size(), root.color.size());
    for (size_t i = 0; i < root.color.size(); ++i) {
      const float want = 0.0f + root.color[i];
      ASSERT_EQ(std::memcmp(&want, &got.color[i], sizeof want), 0) << i;
    }
    for (size_t p = 0; p < got.depth.size(); ++p)
      EXPECT_EQ(got.depth[p], withDepth ? root.depth[p] : std::numeric_limits<float>::infinity());
  }
}

// Tiles that carry a pixel's samples apart (a brick's samples of one frame) blend sample by
// sample, then average: bit for bit the per-sample composite (a tile of 1 sample standing for
// every sample) and meanOfComposites, with sample 0's depth. Two tiles blend as blendPixelPair
// per sample (what a renderer blending a lone root itself does). Mixed counts are an error.
TEST(AlphaBlendOperation, SamplesApartBlendOneByOneThenAverage) {
  constexpr std::uint32_t kSamples = 3;
  std::mt19937 random(5);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  const float inf = std::numeric_limits<float>::infinity();
  const size_t n = static_cast<size_t>(kRegion.pixelCount());
  auto fragments = [&](std::uint32_t samples, bool depth) {
    Tile t;
    t.reset(kRegion);
    t.samples = samples;
    t.color.resize(4 * n * samples);
    for (size_t i = 0; i < t.color.size(); i += 4) {
      const float a = unit(random) < 0.3f ? 1.0f : unit(random);
      for (size_t c = 0; c < 3; ++c) t.color[i + c] = a * unit(random);
      t.color[i + 3] = a;
    }
    if (depth)
      for (size_t i = 0; i < n * samples; ++i)
        t.depth.push_back(unit(random) < 0.2f ? 1.0f : unit(random));
    return t;
  };
  for (const int bricks : {1, 2}) {
    Tile background = fragments(1, false);  // one fragment for every sample, infinitely far
    background.children = bricks;
    std::vector<Tile> tree = {background};
    for (int b = 0; b < bricks; ++b) {
      tree.push_back(fragments(kSamples, true));
      tree.back().generation = 1, tree.back().sequence = static_cast<std::uint32_t>(b + 1);
    }
    auto op = alphaBlendOperation()(kRegion);
    op->newFrame({}, 0, 1);
    for (size_t i = tree.size(); i-- > 0;) EXPECT_EQ(op->process(Tile(tree[i])), i == 0);
    const Tile& got = op->finished();
    ASSERT_EQ(got.color.size(), 4 * n);
    for (size_t p = 0; p < n; ++p) {
      float composites[4 * kSamples];
      float front = inf;
      for (std::uint32_t s = 0; s < kSamples; ++s) {
        auto at = [&](const Tile& t) { return (t.samples == 1 ? 0 : s * n) + p; };
        std::vector<std::pair<float, const float*>> list;
        for (const Tile& t : tree)
          list.push_back({t.depth.empty() ? inf : t.depth[at(t)], &t.color[4 * at(t)]});
        std::stable_sort(list.begin(), list.end(),
                         [](const auto& a, const auto& b) { return a.first < b.first; });
        float* want = &composites[4 * s];
        for (int k = 0; k < 4; ++k) want[k] = 0;
        for (const auto& fragment : list) {
          const float transmitted = 1.0f - want[3];
          for (int k = 0; k < 4; ++k) want[k] += transmitted * fragment.second[k];
        }
        if (s == 0) front = list.front().first;
      }
      float want[4];
      meanOfComposites(composites, kSamples, want);
      ASSERT_EQ(std::memcmp(want, &got.color[4 * p], sizeof want), 0) << bricks << " " << p;
      ASSERT_EQ(got.depth[p], front);
    }
  }
  auto op = alphaBlendOperation()(kRegion);
  op->newFrame({}, 0, 1);
  Tile root = fragments(2, true), child = fragments(3, true);
  root.children = 1, child.generation = 1;
  EXPECT_FALSE(op->process(std::move(child)));
  try {
    op->process(std::move(root));
    ADD_FAILURE() << "a tree of 2 and 3 samples was blended";
  } catch (const base::Error& e) {
    EXPECT_NE(std::string(e.what()).find("a tile of 2 samples in a tree of 3"), std::string::npos)
        << e.what();
  }
}

// CompositeAccumulateOperation hands the blended tile on by exchanging buffers with its parts
// (exchangeFinished) instead of copying it: over frames of new and continued epochs its result
// must stay, bit for bit, the blend's result accumulated as a copy.
TEST(CompositeAccumulateOperation, EqualsTheBlendAccumulatedOverFrames) {
  auto op = compositeAccumulateOperation()(kRegion);
  auto blend = alphaBlendOperation()(kRegion);
  auto accumulate = accumulateOperation()(kRegion);
  std::mt19937 random(7);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  auto fragment = [&](int generation, int children, std::uint32_t id) {
    Tile t;
    t.reset(kRegion, true);
    for (size_t p = 0; p < t.depth.size(); ++p) {
      const float a = unit(random) < 0.3f ? 1.0f : unit(random);
      t.depth[p] = unit(random) < 0.2f ? std::numeric_limits<float>::infinity() : unit(random);
      for (int c = 0; c < 3; ++c) t.color[4 * p + static_cast<size_t>(c)] = a * unit(random);
      t.color[4 * p + 3] = a;
    }
    t.generation = generation, t.children = children, t.accumulationId = id, t.sequence = 0;
    return t;
  };
  // Epochs: a moving camera (a new epoch every frame), then a still one accumulating.
  const std::uint32_t ids[] = {0, 0, 0, 1, 2, 0, 1};
  std::uint32_t epoch = 0;
  for (std::uint32_t id : ids) {
    if (id == 0) ++epoch;
    const FrameInfo frame{epoch * 10 + id, epoch};
    op->newFrame(frame, id, 1);
    blend->newFrame(frame, id, 1);
    accumulate->newFrame(frame, id, 1);
    std::vector<Tile> inputs;
    inputs.push_back(fragment(1, 0, id));
    inputs.push_back(fragment(1, 0, id));
    inputs.back().sequence = 1;
    inputs.push_back(fragment(0, 2, id));
    for (size_t i = 0; i < inputs.size(); ++i) {
      Tile copy = inputs[i];
      EXPECT_EQ(op->process(std::move(copy)), i + 1 == inputs.size());
      EXPECT_EQ(blend->process(std::move(inputs[i])), i + 1 == inputs.size());
    }
    Tile composited = blend->finished();
    composited.accumulationId = id;
    composited.generation = composited.children = 0;
    composited.sequence = 0;
    ASSERT_TRUE(accumulate->process(std::move(composited)));
    const Tile& got = op->finished();
    const Tile& want = accumulate->finished();
    ASSERT_EQ(got.color.size(), want.color.size());
    EXPECT_EQ(std::memcmp(got.color.data(), want.color.data(), got.color.size() * sizeof(float)), 0)
        << "frame " << frame.frameId;
    ASSERT_EQ(got.depth.size(), want.depth.size());
    EXPECT_EQ(std::memcmp(got.depth.data(), want.depth.data(), got.depth.size() * sizeof(float)), 0)
        << "frame " << frame.frameId;
  }
}

TEST(AlphaBlendOperation, TooManyTilesInAGenerationIsAnError) {
  auto op = alphaBlendOperation()(kRegion);
  op->newFrame({}, 0, 1);
  Tile root;
  root.reset(kRegion);
  root.children = 1;
  Tile child = root;
  child.generation = 1;
  child.children = 0;
  EXPECT_FALSE(op->process(Tile(child)));
  EXPECT_THROW(
      {
        op->process(Tile(child));
        op->process(Tile(root));
      },
      base::Error);
}

TEST(TileMessage, PacksAndUnpacksEveryChannel) {
  Tile t;
  t.reset(kRegion, true);
  t.normal.assign(3 * static_cast<size_t>(kRegion.pixelCount()), 0.25f);
  for (size_t i = 0; i < t.color.size(); ++i) t.color[i] = static_cast<float>(i);
  t.generation = 2;
  t.children = 3;
  t.sequence = 40;
  t.weight = 7;
  t.accumulationId = 11;
  const messaging::Bytes bytes = packTile(t, 5, 99, 4);
  TileMessageHeader header;
  const Tile back = unpackTile(bytes, header);
  EXPECT_EQ(header.frameId, 99u);
  EXPECT_EQ(header.epoch, 4u);
  EXPECT_EQ(header.tileIndex, 5);
  EXPECT_EQ(back.region, kRegion);
  EXPECT_EQ(back.color, t.color);
  EXPECT_EQ(back.depth, t.depth);
  EXPECT_EQ(back.normal, t.normal);
  EXPECT_TRUE(back.albedo.empty());
  EXPECT_EQ(back.generation, 2);
  EXPECT_EQ(back.children, 3);
  EXPECT_EQ(back.sequence, 40u);
  EXPECT_EQ(back.weight, 7u);
  EXPECT_EQ(back.accumulationId, 11u);

  messaging::Bytes truncated(bytes.begin(), bytes.end() - 4);
  EXPECT_THROW(unpackTile(truncated, header), base::Error);

  // Display pixels only (the pattern renderer's RGBA8 path): no color floats on the wire.
  Tile d;
  d.region = kRegion;
  for (int i = 0; i < kRegion.pixelCount(); ++i) d.rgba8.push_back(0xff000000u + i);
  const messaging::Bytes small = packTile(d, 5, 99, 4);
  EXPECT_EQ(small.size(), sizeof(TileMessageHeader) + 4 * d.rgba8.size());
  const Tile dback = unpackTile(small, header);
  EXPECT_TRUE(dback.color.empty());
  EXPECT_EQ(dback.rgba8, d.rgba8);
  d.rgba8.pop_back();
  EXPECT_THROW(packTile(d, 5, 99, 4), base::Error);
}

// A tile with samples apart travels with its count, color and depth for each; a header that
// says 0 samples or more than kMaxTileSamples is refused.
TEST(TileMessage, PacksAndUnpacksSamplesApart) {
  const size_t n = static_cast<size_t>(kRegion.pixelCount());
  Tile t;
  t.region = kRegion;
  t.samples = 4;
  for (size_t i = 0; i < 4 * n * 4; ++i) t.color.push_back(static_cast<float>(i));
  for (size_t i = 0; i < n * 4; ++i) t.depth.push_back(static_cast<float>(i) * 0.5f);
  messaging::Bytes bytes = packTile(t, 2, 9, 1);
  TileMessageHeader header;
  const Tile back = unpackTile(bytes, header);
  EXPECT_EQ(back.samples, 4u);
  EXPECT_EQ(back.color, t.color);
  EXPECT_EQ(back.depth, t.depth);
  for (const std::uint32_t bad : {0u, kMaxTileSamples + 1}) {
    header.samples = bad;
    std::memcpy(bytes.data(), &header, sizeof header);
    EXPECT_THROW(unpackTile(bytes, header), base::Error) << bad;
  }
  t.samples = 0;
  EXPECT_THROW(packTile(t, 2, 9, 1), base::Error);
}

// Found by fuzz_tile_message: a header whose region's width times height overflowed an int
// (UBSan) and could then match the message's size. Now refused before any arithmetic.
TEST(TileMessage, RejectsARegionWhoseSizeOverflows) {
  Tile t;
  t.reset(Region{0, 0, 2, 2});
  messaging::Bytes bytes = packTile(t, 0, 1, 0);
  TileMessageHeader header;
  std::memcpy(&header, bytes.data(), sizeof header);
  header.x0 = -2000000000;
  header.x1 = 2000000000;
  std::memcpy(bytes.data(), &header, sizeof header);
  EXPECT_THROW(unpackTile(bytes, header), base::Error);
}

TEST(ToneMap, EncodesSrgbAndClamps) {
  const ToneMapSettings plain;
  const float black[4] = {0, 0, 0, 1}, white[4] = {1, 1, 1, 1}, hot[4] = {50, -1, 0.5f, 0.5f};
  EXPECT_EQ(toneMapPixel(black, plain), 0xff000000u);
  EXPECT_EQ(toneMapPixel(white, plain), 0xffffffffu);
  const std::uint32_t p = toneMapPixel(hot, plain);
  EXPECT_EQ(p & 0xff, 255u);
  EXPECT_EQ((p >> 8) & 0xff, 0u);
  EXPECT_EQ((p >> 16) & 0xff, 188u) << "sRGB of 0.5 is 0.735";
  EXPECT_EQ(p >> 24, 128u);
  ToneMapSettings filmic;
  filmic.filmic = true;
  const float bright[4] = {4, 4, 4, 1};
  EXPECT_EQ(toneMapPixel(bright, plain) & 0xff, 255u);
  EXPECT_LT(toneMapPixel(bright, filmic) & 0xff, 255u) << "the filmic curve rolls off, not clips";
  EXPECT_EQ((toneMapPixel(hot, filmic) >> 16) & 0xff, 206u) << "ACES fit: 0.5 -> 0.616";
}

// The table encoder must equal the pow formula for every float, or a wall and a single process
// could differ. All 1.07e9 floats of [0, 1] take seconds, so: every 61st bit pattern, plus a few
// ulps around each of the 255 steps, where a table mistake would show.
TEST(ToneMap, TableEncoderEqualsThePowFormula) {
  constexpr std::uint32_t kOne = 0x3F800000;
  for (std::uint32_t b = 0; b <= kOne; b += 61) {
    const float v = std::bit_cast<float>(b);
    ASSERT_EQ(encodeSrgb8(v), encodeSrgb8Reference(v)) << "at " << v;
  }
  std::uint32_t b = 0;
  for (std::uint32_t k = 1; k < 256; ++k) {
    while (encodeSrgb8Reference(std::bit_cast<float>(b)) < k) b += 1 << 12;
    for (std::uint32_t x = b > (1 << 13) ? b - (1 << 13) : 0; x <= std::min(kOne, b + 64); ++x)
      ASSERT_EQ(encodeSrgb8(std::bit_cast<float>(x)), encodeSrgb8Reference(std::bit_cast<float>(x)))
          << "near step " << k;
  }
  for (float v : {-1.0f, -0.0f, 1.0f, 1.5f, 1e30f, std::numeric_limits<float>::infinity(),
                  std::numeric_limits<float>::quiet_NaN()})
    EXPECT_EQ(encodeSrgb8(v), encodeSrgb8Reference(v)) << "at " << v;
}

}  // namespace
}  // namespace dfb
