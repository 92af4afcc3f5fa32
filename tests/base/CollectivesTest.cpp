// The bounded collectives (base/Collectives.h) on however many ranks the test runs: every rank
// gets what MPI's own collectives would give it, with uneven counts and a rank that gives
// nothing, and a rank that does not join is a base::DeadlineError with its text on the others.
#include "base/Collectives.h"

#include <gtest/gtest.h>
#include <mpi.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "base/Error.h"
#include "tests/MpiTestUtil.h"
#include "tests/Stopwatch.h"

namespace base {
namespace {

using namespace std::chrono_literals;
using testutil::Clock;
using testutil::secondsSince;
using testutil::worldRank;
using testutil::worldSize;

const Bound kGenerous{.until = 20s, .late = "a collective of the test did not complete"};

// Not a multiple of 4 bytes wide: values travel as their bytes, whatever their size.
struct Odd {
  std::int32_t rank;
  std::int16_t index;
  char tag;

  bool operator==(const Odd&) const = default;
};

// What rank `rank` gives to the v-variants: `rank` values, so rank 0 gives none.
std::vector<Odd> valuesOf(int rank) {
  std::vector<Odd> out;
  for (int i = 0; i < rank; ++i)
    out.push_back({rank, static_cast<std::int16_t>(i), static_cast<char>('a' + i)});
  return out;
}

TEST(Collectives, BarrierBcastAndAllreduceAgreeOnEveryRank) {
  const int rank = worldRank(), size = worldSize();
  barrier(MPI_COMM_WORLD, kGenerous);

  // From the last rank, so the root is not always rank 0.
  std::array<char, 6> word{};
  if (rank == size - 1) word = {'h', 'e', 'l', 'l', 'o', '\0'};
  bcast(word.data(), static_cast<int>(word.size()), size - 1, MPI_COMM_WORLD, kGenerous);
  EXPECT_STREQ(word.data(), "hello");

  const std::int64_t mine[2] = {rank, 1};
  std::int64_t sum[2] = {};
  allreduce(mine, sum, 2, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD, kGenerous);
  EXPECT_EQ(sum[0], std::int64_t{size} * (size - 1) / 2);
  EXPECT_EQ(sum[1], size);

  // Started, then finished after other work: the same result.
  std::int64_t max[2] = {};
  Pending pending = startAllreduce(mine, max, 2, MPI_INT64_T, MPI_MAX, MPI_COMM_WORLD);
  pending.finish({.until = Clock::now() + 20s, .late = "never said"});
  EXPECT_EQ(max[0], size - 1);
}

TEST(Collectives, GatherAndAllgatherGiveOneValuePerRankInRankOrder) {
  const int rank = worldRank(), size = worldSize();
  const Odd mine{rank, static_cast<std::int16_t>(10 * rank), 'x'};
  const std::vector<Odd> every = allgather(mine, MPI_COMM_WORLD, kGenerous);
  ASSERT_EQ(every.size(), static_cast<size_t>(size));
  for (int r = 0; r < size; ++r)
    EXPECT_EQ(every[static_cast<size_t>(r)], (Odd{r, static_cast<std::int16_t>(10 * r), 'x'}));

  const int root = size - 1;
  const std::vector<Odd> atRoot = gather(mine, root, MPI_COMM_WORLD, kGenerous);
  EXPECT_EQ(atRoot, rank == root ? every : std::vector<Odd>{});
}

TEST(Collectives, AllgathervLaysOutUnevenCountsAndARankWithNothing) {
  const int size = worldSize();
  std::vector<int> counts;
  const std::vector<Odd> all =
      allgatherv(valuesOf(worldRank()), MPI_COMM_WORLD, kGenerous, &counts);
  std::vector<Odd> expected;
  std::vector<int> expectedCounts;
  for (int r = 0; r < size; ++r) {
    const std::vector<Odd> of = valuesOf(r);
    expected.insert(expected.end(), of.begin(), of.end());
    expectedCounts.push_back(r);
  }
  EXPECT_EQ(all, expected);
  EXPECT_EQ(counts, expectedCounts);
}

TEST(Collectives, GathervGivesTheRootOneVectorPerRank) {
  const int rank = worldRank(), size = worldSize(), root = size - 1;
  const std::vector<std::vector<Odd>> parts =
      gatherv(valuesOf(rank), root, MPI_COMM_WORLD, kGenerous);
  if (rank != root) {
    EXPECT_TRUE(parts.empty());
    return;
  }
  ASSERT_EQ(parts.size(), static_cast<size_t>(size));
  for (int r = 0; r < size; ++r) EXPECT_EQ(parts[static_cast<size_t>(r)], valuesOf(r));
}

// A gather every frame reuses the memory of the one before: a smaller frame keeps the buffer.
TEST(Collectives, StartGathervReusesItsBuffersFromOneCallToTheNext) {
  const int rank = worldRank(), size = worldSize();
  Gathered<std::uint8_t> gathered;
  const std::byte* first = nullptr;
  for (const int scale : {3, 2}) {
    const std::vector<std::uint8_t> mine(static_cast<size_t>(scale * rank),
                                         static_cast<std::uint8_t>(scale + rank));
    Pending pending =
        startGatherv(std::span<const std::uint8_t>(mine), 0, MPI_COMM_WORLD, kGenerous, gathered);
    pending.finish(kGenerous);
    if (rank != 0) {
      EXPECT_TRUE(gathered.all.empty());
      continue;
    }
    ASSERT_EQ(gathered.counts.size(), static_cast<size_t>(size));
    for (int r = 0; r < size; ++r) {
      const std::span<const std::uint8_t> part = gathered.of(r);
      EXPECT_EQ(std::vector<std::uint8_t>(part.begin(), part.end()),
                std::vector<std::uint8_t>(static_cast<size_t>(scale * r),
                                          static_cast<std::uint8_t>(scale + r)));
    }
    const auto* at = reinterpret_cast<const std::byte*>(gathered.all.data());
    if (scale == 3) first = at;
    if (scale == 2) {
      EXPECT_EQ(at, first);
    }
  }
}

TEST(Collectives, MoreThanAnMpiCountReachesIsAnErrorWithTheGivenText) {
  std::vector<int> offsets;
  const int most = std::numeric_limits<int>::max();
  EXPECT_EQ(collectives::layOut({most - 1, 0, 1}, offsets, kGenerous), std::size_t(most));
  EXPECT_EQ(offsets, (std::vector<int>{0, most - 1, most - 1}));
  try {
    collectives::layOut({most, 1}, offsets, {.until = 1s, .tooLarge = "the image is too large"});
    ADD_FAILURE() << "laid out more than 2^31-1 values";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "the image is too large");
  }
  EXPECT_THROW(collectives::countOf(std::size_t(most) + 1, kGenerous), Error);
}

void expectLate(const std::function<void()>& collective, const std::string& text) {
  const auto start = Clock::now();
  try {
    collective();
    ADD_FAILURE() << "completed without rank 1";
  } catch (const DeadlineError& e) {
    EXPECT_STREQ(e.what(), text.c_str());
  }
  EXPECT_GE(secondsSince(start), 0.3);
  EXPECT_LT(secondsSince(start), 10.0) << "the bound was 0.3 s";
}

TEST(Collectives, ARankThatDoesNotJoinIsADeadlineErrorWithItsTextOnTheOthers) {
  if (worldSize() < 2) GTEST_SKIP() << "needs a rank to stay away";
  MPI_Comm comm;
  MPI_Comm_dup(MPI_COMM_WORLD, &comm);
  const bool away = worldRank() == 1;
  if (!away) {
    expectLate([&] { barrier(comm, {.until = 300ms, .late = "start-up: rank 1 is away"}); },
               "start-up: rank 1 is away");
    expectLate(
        [&] {
          allgatherv(valuesOf(worldRank()), comm,
                     {.until = Clock::now() + 300ms, .late = "brick bounds: rank 1 is away"});
        },
        "brick bounds: rank 1 is away");
  }
  MPI_Barrier(MPI_COMM_WORLD);  // the others have given up
  if (away) {
    // Joins late, as far as the others went (the counts of the allgatherv), so that nothing
    // stays posted.
    barrier(comm, kGenerous);
    allgather(0, comm, kGenerous);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  MPI_Comm_free(&comm);
}

}  // namespace
}  // namespace base
