// Brick seams: rays that cross from brick to brick give the unbricked image. A synthetic volume
// made like the ocean (anisotropic spacing, missing values in a continent across the seams and
// scattered over the ghost layers, viewed at a slant) and configs/scenes/ocean.toml itself render
// with 4 bricks on every rank within 1e-4 of 1 brick, at 1 sample a frame and at several (whose
// samples the DFB composites one by one: a composite of each brick's mean was up to 0.13 off),
// and the same bytes on 1 rank as on all.
#include <gtest/gtest.h>
#include <mpi.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "renderers/SceneToml.h"
#include "renderers/scivis/bricks/BrickFrameDriver.h"
#include "tests/MpiTestUtil.h"
#include "tests/renderers/BrickTestUtil.h"

namespace renderers::scivis {
namespace {

namespace fs = std::filesystem;

constexpr int kTile = 16;

// The canvas and seed of a check.
struct View {
  int width = 64, height = 48;
  std::uint64_t seed = 5;
};

// `bricks` bricks on the first `ranks` ranks of the world, `spp` samples a pixel in one frame
// (rank 0's image; empty elsewhere). 0 bricks: the whole scene unbounded (wholeScene, as
// --bricks 0 holds it), whose rays no brick face cuts.
std::vector<float> renderBricks(const std::shared_ptr<SceneDesc>& desc, int ranks, int bricks,
                                std::uint32_t spp, const View& view) {
  return test::onFirstRanks(ranks, [&](MPI_Comm comm, int rank) {
    RenderSettings settings;
    settings.width = view.width, settings.height = view.height, settings.seed = view.seed;
    std::vector<HeldBrick> held;
    if (bricks == 0)
      held.push_back({0, wholeScene(*desc)});
    else
      held = loadOwnBricks(*desc, bricks, 1, rank, ranks);
    return test::renderHeldBricks(desc, settings, std::move(held), comm, kTile, 1,
                                  std::chrono::milliseconds(60000), true, nullptr, FirstHits::Auto,
                                  spp);
  });
}

// 4 bricks on every rank of the world within 1e-4 of 1 brick on one, at `spp` samples a frame,
// and the same bytes as 4 bricks on one rank (where every tile of one brick is a lone root that
// blends its background itself, sample by sample as the DFB does).
void checkSeams(const std::string& name, const std::shared_ptr<SceneDesc>& desc, std::uint32_t spp,
                const View& view = {}) {
  const int width = view.width, height = view.height;
  const std::vector<float> many = renderBricks(desc, testutil::worldSize(), 4, spp, view);
  const std::vector<float> one = renderBricks(desc, 1, 4, spp, view);
  const std::vector<float> whole = renderBricks(desc, 1, 1, spp, view);
  const std::vector<float> unbounded = renderBricks(desc, 1, 0, spp, view);
  if (testutil::worldRank() != 0) return;
  ASSERT_EQ(unbounded.size(), many.size());
  float worstUnbounded = 0;
  for (std::size_t i = 0; i < many.size(); ++i)
    worstUnbounded = std::max(worstUnbounded, std::abs(many[i] - unbounded[i]));
  EXPECT_LE(worstUnbounded, 1e-4f) << name << " at " << spp << " spp: 4 bricks vs unbounded";
  ASSERT_EQ(many.size(), static_cast<std::size_t>(4 * width * height));
  ASSERT_EQ(one.size(), many.size());
  ASSERT_EQ(whole.size(), many.size());
  EXPECT_EQ(0, std::memcmp(one.data(), many.data(), many.size() * sizeof(float)))
      << name << " at " << spp << " spp: 4 bricks on " << testutil::worldSize()
      << " ranks differ from 1 rank";
  float worst = 0;
  std::size_t at = 0;
  int lit = 0;
  for (std::size_t i = 0; i < many.size(); ++i) {
    const float d = std::abs(many[i] - whole[i]);
    if (!(d <= worst)) worst = d, at = i;  // a NaN is the worst
    if (i % 4 == 3 && whole[i] > 0.05f) ++lit;
  }
  EXPECT_LE(worst, 1e-4f) << name << " at " << spp << " spp: 4 bricks vs 1 brick at pixel ("
                          << at / 4 % width << ", " << at / 4 / width << ") channel " << at % 4
                          << ": " << many[at] << " vs " << whole[at];
  EXPECT_GT(lit, width * height / 8) << name << ": the volume should cover much of the image";
  std::printf(
      "%s at %u spp: 4 bricks on %d ranks vs 1 brick: largest difference %.3g, vs the whole "
      "scene unbounded %.3g\n",
      name.c_str(), spp, testutil::worldSize(), worst, worstUnbounded);
}

// The synthetic ocean: 40 x 32 x 12 float voxels 1 x 1 x 5 apart, a smooth field cooling with
// depth, a NaN continent across the middle (where the bricks meet) and NaN voxels scattered
// through (some in every brick's ghost layer), a transfer function dense enough that rays
// through it composite much, early termination off (its own difference is bounded by
// min_transmittance, docs/scivis.md), a camera that looks across the seams at a slant.
std::shared_ptr<SceneDesc> syntheticOcean() {
  const fs::path folder =
      fs::temp_directory_path() / ("dfbwall-seams-" + std::to_string(::getpid()));
  fs::create_directories(folder);
  constexpr int nx = 40, ny = 32, nz = 12;
  std::vector<float> voxels;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const float dx = static_cast<float>(i - 20) / 7.0f, dy = static_cast<float>(j - 16) / 5.0f;
        const bool continent = dx * dx + dy * dy < 1.0f && k < 9;
        const bool scattered = (i * 73 + j * 151 + k * 311) % 29 == 0;
        voxels.push_back(continent || scattered
                             ? std::numeric_limits<float>::quiet_NaN()
                             : 24.0f - 2.0f * static_cast<float>(k) +
                                   3.0f * std::sin(0.4f * static_cast<float>(i)) *
                                       std::cos(0.3f * static_cast<float>(j)));
      }
  std::ofstream(folder / "sea.raw", std::ios::binary)
      .write(reinterpret_cast<const char*>(voxels.data()),
             static_cast<std::streamsize>(voxels.size() * sizeof(float)));
  std::ofstream(folder / "sea.toml") << R"([camera]
position = [58.0, -34.0, 120.0]
look_at = [19.5, 15.5, 27.5]
up = [0.0, 1.0, 0.0]
fov = 40.0

[environment]
type = "gradient"
bottom = [0.02, 0.02, 0.03]
top = [0.15, 0.16, 0.2]

[[volumes]]
name = "sea"
source = "raw"
file = "sea.raw"
type = "float32"
dims = [40, 32, 12]
origin = [0.0, 0.0, 0.0]
spacing = [1.0, 1.0, 5.0]
transfer_function = { preset = "cool-warm", range = [-2.0, 28.0], opacity = [[-2.0, 0.02], [10.0, 0.1], [28.0, 0.6]], opacity_unit = 5.0 }

[[lights]]
type = "ambient"
intensity = 1.0

[scivis]
ao_samples = 0
sampling_rate = 1.0
min_transmittance = 0.0
)";
  return std::make_shared<SceneDesc>(readSceneToml((folder / "sea.toml").string()));
}

std::shared_ptr<SceneDesc> ocean() {
  return std::make_shared<SceneDesc>(readSceneToml(std::string(DFBWALL_SCENES) + "/ocean.toml"));
}

TEST(BrickSeamsMpi, AnisotropicVolumeWithMissingValuesAcrossTheSeams) {
  const auto desc = syntheticOcean();
  checkSeams("synthetic ocean", desc, 1);
  checkSeams("synthetic ocean", desc, 4);
}

TEST(BrickSeamsMpi, OceanSceneOneSampleAFrame) { checkSeams("ocean.toml", ocean(), 1); }

TEST(BrickSeamsMpi, OceanSceneSeveralSamplesAFrame) { checkSeams("ocean.toml", ocean(), 4); }

// At 400x300 and seed 0 one ray of ocean.toml has a sample exactly on the domain's far face:
// bricks that clipped rays there (1 as 4) left it out, 1.7e-3 off the whole scene.
TEST(BrickSeamsMpi, OceanSceneSampleOnTheDomainBoundary) {
  checkSeams("ocean.toml", ocean(), 1, {400, 300, 0});
}

}  // namespace
}  // namespace renderers::scivis
