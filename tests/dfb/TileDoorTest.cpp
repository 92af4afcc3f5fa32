// The DFB's door (dfb/TileDoor.h) on its own: every kind of malformed input, for every tile
// operation, is refused with an error that says what is wrong, before the operation sees it;
// what the door admits, the operation takes.
#include "dfb/TileDoor.h"

#include <gtest/gtest.h>

#include <string>

#include "base/Error.h"
#include "dfb/TileOperation.h"

namespace dfb {
namespace {

const Region kRegion{64, 0, 100, 20};  // a partial tile at an image edge
constexpr std::uint32_t kFrame = 7, kEpoch = 3, kPass = 2;

struct Operation {
  const char* name;
  TileOperationFactory factory;
};

const Operation kOperations[] = {
    {"write", writeOperation()},
    {"accumulate", accumulateOperation()},
    {"alpha-blend", alphaBlendOperation()},
    {"composite-accumulate", compositeAccumulateOperation()},
};

TileState stateFor(const TileOperation& op) {
  TileState s;
  s.region = kRegion;
  s.needs = op.needs();
  s.frame = {kFrame, kEpoch};
  s.accumulationId = kPass;
  s.active = true;
  return s;
}

Tile goodInput() {
  Tile t;
  t.reset(kRegion, true);
  for (float& c : t.color) c = 0.25f;
  t.accumulationId = kPass;
  return t;
}

// The door's message for `input`, or "" when it admits it.
std::string refusal(const Tile& input, const TileState& state, FrameInfo label = {kFrame, kEpoch}) {
  try {
    admitInput(input, label, state);
    return {};
  } catch (const base::Error& e) {
    return e.what();
  }
}

class Door : public ::testing::TestWithParam<Operation> {
 protected:
  std::unique_ptr<TileOperation> op = GetParam().factory(kRegion);
  TileState state = stateFor(*op);
};

TEST_P(Door, AdmitsAGoodInputAndTheOperationTakesIt) {
  op->newFrame(state.frame, kPass, 1);
  Tile input = goodInput();
  ASSERT_EQ(refusal(input, state), "");
  EXPECT_TRUE(op->process(std::move(input)));
  EXPECT_EQ(op->finished().color.size(), 4 * static_cast<size_t>(kRegion.pixelCount()));
}

TEST_P(Door, RefusesARegionThatIsNotTheTile) {
  Tile input = goodInput();
  input.region.x1 -= 1;  // one column short: every channel is sized for the short region
  input.reset(input.region, true);
  input.accumulationId = kPass;
  EXPECT_NE(refusal(input, state).find("is not the tile's [64, 100) x [0, 20)"), std::string::npos)
      << refusal(input, state);
}

TEST_P(Door, RefusesAnInputWithoutColorUnlessDisplayPixelsMayStandIn) {
  Tile input = goodInput();
  input.color.clear();
  EXPECT_NE(refusal(input, state).find("color has 0 floats, the tile needs 2880"),
            std::string::npos);
  // Display pixels (a kNoColor | kHasRgba8 message): only the write operation takes them.
  input.rgba8.assign(static_cast<size_t>(kRegion.pixelCount()), 0xff00ff00u);
  const std::string why = refusal(input, state);
  if (state.needs.displayPixelsForColor) {
    EXPECT_EQ(why, "");
    op->newFrame(state.frame, kPass, 1);
    EXPECT_TRUE(op->process(std::move(input)));
    EXPECT_EQ(op->takeDisplayPixels().size(), static_cast<size_t>(kRegion.pixelCount()));
  } else {
    EXPECT_NE(why.find("color has 0 floats"), std::string::npos) << why;
  }
  // A short color is no color.
  input = goodInput();
  input.color.resize(5);
  EXPECT_NE(refusal(input, state).find("color has 5 floats"), std::string::npos);
}

TEST_P(Door, RefusesOptionalChannelsOfTheWrongSize) {
  const std::pair<const char*, std::vector<float> Tile::*> channels[] = {
      {"depth has 3 values", &Tile::depth},
      {"normal has 3 values", &Tile::normal},
      {"albedo has 3 values", &Tile::albedo}};
  for (const auto& [what, channel] : channels) {
    Tile input = goodInput();
    (input.*channel).assign(3, 1.0f);
    EXPECT_NE(refusal(input, state).find(what), std::string::npos) << refusal(input, state);
  }
  Tile input = goodInput();
  input.rgba8.assign(2, 0u);
  EXPECT_NE(refusal(input, state).find("display pixels has 2 values"), std::string::npos);
}

TEST_P(Door, RefusesAnotherEpochAndALaterFrameAndDropsAnEarlierOne) {
  const Tile input = goodInput();
  EXPECT_NE(refusal(input, state, {kFrame, kEpoch + 1})
                .find("input of accumulation epoch 4, but frame 7 is epoch 3"),
            std::string::npos);
  EXPECT_NE(refusal(input, state, {kFrame + 1, kEpoch}).find("input for frame 8"),
            std::string::npos);
  // A surplus input of a frame the tile has left: dropped (and counted), never applied.
  EXPECT_EQ(admitInput(input, {kFrame - 1, kEpoch}, state), Admission::Stale);
}

TEST_P(Door, RefusesAnInputForATileThatExpectsNoneOrIsComplete) {
  TileState s = state;
  s.active = false;
  s.complete = true;
  EXPECT_NE(refusal(goodInput(), s).find("expects none"), std::string::npos);
  s.active = true;
  EXPECT_NE(refusal(goodInput(), s).find("after the tile was complete"), std::string::npos);
}

TEST_P(Door, BoundsTheDependencyTree) {
  const std::pair<int, int> bad[] = {
      {-1, 0}, {kMaxGeneration + 1, 0}, {0, -1}, {0, kMaxChildren + 1}, {1 << 30, 1 << 30}};
  for (const auto& [generation, children] : bad) {
    Tile input = goodInput();
    input.generation = generation;
    input.children = children;
    const std::string why = refusal(input, state);
    EXPECT_TRUE(why.find("generation") != std::string::npos ||
                why.find("children count") != std::string::npos)
        << generation << " " << children << ": " << why;
  }
  Tile child = goodInput();
  child.generation = 1;
  const std::string why = refusal(child, state);
  if (state.needs.tree)
    EXPECT_EQ(why, "");
  else
    EXPECT_NE(why.find("takes no dependency tree"), std::string::npos) << why;
}

TEST_P(Door, AccumulatingOperationsRefuseAnotherPassAndWeightZero) {
  Tile input = goodInput();
  input.accumulationId = kPass + 1;
  const std::string pass = refusal(input, state);
  input = goodInput();
  input.weight = 0;
  const std::string weight = refusal(input, state);
  if (state.needs.accumulation) {
    EXPECT_NE(pass.find("accumulation pass 3, but this frame is pass 2"), std::string::npos);
    EXPECT_NE(weight.find("weight 0"), std::string::npos);
  } else {
    EXPECT_EQ(pass, "");
    EXPECT_EQ(weight, "");
  }
}

// Samples carried apart (Tile::samples): only into a tree, 1 to kMaxTileSamples of them, color
// and depth sized for all, and nothing else beside them.
TEST_P(Door, TakesSamplesApartOnlyIntoATreeAndBounded) {
  const size_t n = static_cast<size_t>(kRegion.pixelCount());
  auto apart = [&](std::uint32_t samples) {
    Tile input = goodInput();
    input.samples = samples;
    input.color.assign(4 * n * samples, 0.25f);
    input.depth.assign(n * samples, 1.0f);
    return input;
  };
  for (const std::uint32_t bad : {0u, kMaxTileSamples + 1})
    EXPECT_NE(refusal(apart(bad), state).find("samples apart (1 to 16)"), std::string::npos)
        << bad << ": " << refusal(apart(bad), state);
  const std::string why = refusal(apart(3), state);
  if (state.needs.tree) {
    EXPECT_EQ(why, "");
    Tile shortColor = apart(3);
    shortColor.color.resize(4 * n);
    EXPECT_NE(refusal(shortColor, state).find("the tile needs 8640 (4 per pixel and sample)"),
              std::string::npos)
        << refusal(shortColor, state);
    Tile shortDepth = apart(3);
    shortDepth.depth.resize(n);
    EXPECT_NE(refusal(shortDepth, state).find("depth has 720 values, the tile needs 2160"),
              std::string::npos)
        << refusal(shortDepth, state);
    Tile withNormals = apart(3);
    withNormals.normal.assign(3 * n, 0.0f);
    EXPECT_NE(refusal(withNormals, state).find("color and depth only"), std::string::npos);
  } else {
    EXPECT_NE(why.find("composites no tree (1 only)"), std::string::npos) << why;
  }
}

INSTANTIATE_TEST_SUITE_P(EveryOperation, Door, ::testing::ValuesIn(kOperations), [](const auto& p) {
  std::string name = p.param.name;
  for (char& c : name)
    if (c == '-') c = '_';
  return name;
});

}  // namespace
}  // namespace dfb
