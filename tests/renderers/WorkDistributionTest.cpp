#include <gtest/gtest.h>

#include <set>

#include "base/Error.h"
#include "renderers/WorkDistribution.h"

namespace renderers {
namespace {

// Every input of every tile, checked for the invariants the DFB relies on.
void checkPlan(const WorkPlan& plan, int tiles, int ranks, std::uint32_t spp) {
  ASSERT_EQ(plan.perRank.size(), static_cast<std::size_t>(ranks));
  ASSERT_EQ(plan.inputsPerTile.size(), static_cast<std::size_t>(tiles));
  std::vector<std::set<int>> ranksOf(tiles);
  std::vector<std::set<std::uint32_t>> firstSamples(tiles);
  for (int r = 0; r < ranks; ++r)
    for (const Assignment& a : plan.perRank[r]) {
      ASSERT_GE(a.tile, 0);
      ASSERT_LT(a.tile, tiles);
      EXPECT_EQ(a.samples, spp);
      EXPECT_EQ(a.firstSample % spp, 0u);
      EXPECT_TRUE(ranksOf[a.tile].insert(r).second) << "tile " << a.tile << " twice on rank " << r;
      EXPECT_TRUE(firstSamples[a.tile].insert(a.firstSample).second) << "samples rendered twice";
    }
  for (int t = 0; t < tiles; ++t) {
    EXPECT_EQ(static_cast<int>(ranksOf[t].size()), plan.inputsPerTile[t]) << "tile " << t;
    EXPECT_TRUE(firstSamples[t].count(0)) << "tile " << t << " lacks its first samples";
  }
}

TEST(WorkDistribution, StaticAndRoundRobinCoverEveryTileOnce) {
  for (int ranks = 1; ranks <= 5; ++ranks)
    for (int tiles = 0; tiles <= 23; ++tiles)
      for (auto dist : {Distribution::Static, Distribution::RoundRobin}) {
        const WorkPlan p = planWork(tiles, ranks, 4, {}, dist);
        checkPlan(p, tiles, ranks, 4);
        std::size_t lo = tiles, hi = 0;
        for (const auto& list : p.perRank)
          lo = std::min(lo, list.size()), hi = std::max(hi, list.size());
        EXPECT_LE(hi - lo, 1u) << "unbalanced: " << tiles << " tiles on " << ranks << " ranks";
        for (int t = 0; t < tiles; ++t) EXPECT_EQ(p.inputsPerTile[t], 1);
      }
}

TEST(WorkDistribution, StaticGivesContiguousBlocksRoundRobinInterleaves) {
  const WorkPlan s = planWork(10, 3, 1, {}, Distribution::Static);
  EXPECT_EQ(s.perRank[0], (std::vector<Assignment>{{0, 0, 1}, {1, 0, 1}, {2, 0, 1}, {3, 0, 1}}));
  EXPECT_EQ(s.perRank[2].front().tile, 7);
  const WorkPlan r = planWork(10, 3, 1, {}, Distribution::RoundRobin);
  EXPECT_EQ(r.perRank[1], (std::vector<Assignment>{{1, 0, 1}, {4, 0, 1}, {7, 0, 1}}));
}

TEST(WorkDistribution, DynamicWithoutErrorsIsRoundRobin) {
  const std::vector<float> zeros(12, 0.0f);
  EXPECT_EQ(planWork(12, 3, 2, {}, Distribution::Dynamic).perRank,
            planWork(12, 3, 2, {}, Distribution::RoundRobin).perRank);
  EXPECT_EQ(planWork(12, 3, 2, zeros, Distribution::Dynamic).perRank,
            planWork(12, 3, 2, {}, Distribution::RoundRobin).perRank);
}

TEST(WorkDistribution, DynamicGivesNoisyTilesExtraRanksWithDistinctSamples) {
  std::vector<float> errors(16, 0.01f);
  errors[5] = 1.0f;  // the worst: maxInputs inputs
  errors[9] = 0.5f;
  const int ranks = 4;
  const WorkPlan p = planWork(16, ranks, 8, errors, Distribution::Dynamic, {0.25f, 4});
  checkPlan(p, 16, ranks, 8);
  EXPECT_EQ(p.inputsPerTile[5], 4);
  EXPECT_GT(p.inputsPerTile[9], 1);
  EXPECT_LT(p.inputsPerTile[9], 4);
  int extras = 0;
  for (int t = 0; t < 16; ++t) extras += p.inputsPerTile[t] - 1;
  EXPECT_LE(extras, 4 * 3);  // at most 25% of tiles, each at most 3 extra inputs
  // The extra work goes to the least-loaded ranks: loads differ by at most two tiles.
  std::size_t lo = 99, hi = 0;
  for (const auto& list : p.perRank) lo = std::min(lo, list.size()), hi = std::max(hi, list.size());
  EXPECT_LE(hi - lo, 2u);
  // The same inputs give the same plan (every rank computes it alone).
  EXPECT_EQ(p.perRank, planWork(16, ranks, 8, errors, Distribution::Dynamic, {0.25f, 4}).perRank);
}

TEST(WorkDistribution, DynamicNeverExceedsTheRankCount) {
  std::vector<float> errors(6, 1.0f);
  const WorkPlan two = planWork(6, 2, 1, errors, Distribution::Dynamic, {1.0f, 8});
  checkPlan(two, 6, 2, 1);
  for (int n : two.inputsPerTile) EXPECT_EQ(n, 2);
  const WorkPlan one = planWork(6, 1, 1, errors, Distribution::Dynamic, {1.0f, 8});
  for (int n : one.inputsPerTile) EXPECT_EQ(n, 1);
}

TEST(WorkDistribution, NamesAndErrors) {
  EXPECT_EQ(distributionFromName("static"), Distribution::Static);
  EXPECT_EQ(distributionFromName("roundrobin"), Distribution::RoundRobin);
  EXPECT_EQ(distributionFromName("dynamic"), Distribution::Dynamic);
  try {
    distributionFromName("random");
    FAIL() << "no error for an unknown name";
  } catch (const base::Error& e) {
    EXPECT_NE(std::string(e.what()).find("'random'"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("roundrobin"), std::string::npos);
  }
  EXPECT_THROW(planWork(4, 0, 1, {}, Distribution::Static), base::Error);
}

}  // namespace
}  // namespace renderers
