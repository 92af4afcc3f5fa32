// A service wall head's swap barriers and capture gathers among processes that come and go
// (wall/service/server/FrameAgreements.h).
#include <gtest/gtest.h>

#include "wall/service/server/FrameAgreements.h"

namespace wall::service {
namespace {

using Clock = FrameAgreements::Clock;
using namespace std::chrono_literals;

TEST(FrameAgreements, ABarrierWaitsForExactlyTheProcessesTakingPart) {
  FrameAgreements board(3);
  const auto t = Clock::now();
  bool twoTakesPart = true;
  const auto takesPart = [&](int p, std::uint32_t) { return p != 2 || twoTakesPart; };
  ASSERT_TRUE(board.arrive(0, 7, {1, -5}, t));
  ASSERT_TRUE(board.arrive(1, 7, {3, -9}, t));
  EXPECT_TRUE(board.complete(takesPart).empty());  // process 2 is still awaited
  twoTakesPart = false;                            // dropped
  const auto released = board.complete(takesPart);
  ASSERT_EQ(released.size(), 1u);
  EXPECT_EQ(released[0].frameId, 7u);
  EXPECT_EQ(released[0].values, (std::vector<std::int64_t>{3, -5}));
  EXPECT_EQ(released[0].processes, (std::vector<int>{0, 1}));
  EXPECT_TRUE(board.complete(takesPart).empty());  // released once
}

TEST(FrameAgreements, AValueCountThatDiffersIsRefused) {
  FrameAgreements board(2);
  const auto t = Clock::now();
  ASSERT_TRUE(board.arrive(0, 1, {1, 2, 3}, t));
  EXPECT_FALSE(board.arrive(1, 1, {1, 2}, t));
}

TEST(FrameAgreements, ABarrierOpenPastTheDeadlineNamesWhoDidNotCome) {
  FrameAgreements board(3);
  bool twoTakesPart = true;
  const auto takesPart = [&](int p, std::uint32_t) { return p != 2 || twoTakesPart; };
  const auto t = Clock::now();
  ASSERT_TRUE(board.arrive(0, 4, {1}, t));
  ASSERT_TRUE(board.arrive(1, 4, {1}, t + 1s));  // the deadline counts from the first arrival
  ASSERT_TRUE(board.arrive(0, 5, {1}, t + 2s));
  EXPECT_TRUE(board.overdue(takesPart, t).empty());  // not open before t
  const auto late = board.overdue(takesPart, t + 1500ms);
  ASSERT_EQ(late.size(), 1u);
  EXPECT_EQ(late[0].frameId, 4u);
  EXPECT_EQ(late[0].missing, std::vector<int>{2});
  const auto both = board.overdue(takesPart, t + 3s);
  ASSERT_EQ(both.size(), 2u);
  EXPECT_EQ(both[1].missing, (std::vector<int>{1, 2}));
  twoTakesPart = false;  // dropped: frame 4 completes, frame 5 still waits for process 1
  EXPECT_EQ(board.complete(takesPart).size(), 1u);
  EXPECT_EQ(board.open(), 1u);
  EXPECT_EQ(board.overdue(takesPart, t + 3s).at(0).missing, std::vector<int>{1});
}

// A job in a window: process 0 is out of it (it has no pieces to wait for), process 1 in it.
TEST(FrameAgreements, ABarrierOnlyProcessesOutOfTheWindowCameToWaitsForTheWindowOrTheJobsEnd) {
  FrameAgreements board(2);
  bool oneTakesPart = true;
  const auto takesPart = [&](int p, std::uint32_t) { return p != 1 || oneTakesPart; };
  const auto t = Clock::now();
  ASSERT_TRUE(board.arrive(0, 2, {1}, t, false));
  EXPECT_TRUE(board.overdue(takesPart, t + 1h).empty());  // not open: the job may idle
  oneTakesPart = false;                                   // process 1 is done
  EXPECT_TRUE(board.complete(takesPart).empty());         // nobody rendered frame 2
  const auto from = [](std::uint32_t first) {
    return [first](std::uint32_t frameId) { return frameId >= first; };
  };
  EXPECT_TRUE(board.complete(takesPart, from(3)).empty());   // the job ends after frame 2
  const auto released = board.complete(takesPart, from(2));  // the job ends after frame 1
  ASSERT_EQ(released.size(), 1u);
  EXPECT_EQ(released[0].processes, std::vector<int>{0});
}

TEST(FrameAgreements, ABarrierOpensAtTheFirstArrivalInTheWindow) {
  FrameAgreements board(2);
  const auto takesPart = [](int, std::uint32_t) { return true; };
  const auto t = Clock::now();
  ASSERT_TRUE(board.arrive(0, 3, {1}, t, false));
  ASSERT_TRUE(board.arrive(0, 2, {1}, t, false));
  ASSERT_TRUE(board.arrive(1, 2, {1}, t + 10s, true));
  EXPECT_TRUE(board.overdue(takesPart, t + 10s).empty());
  EXPECT_EQ(board.complete(takesPart).size(), 1u);      // frame 2; frame 3 is not paced yet
  ASSERT_TRUE(board.arrive(1, 4, {1}, t + 20s, true));  // the window's process is past frame 3
  const auto late = board.overdue(takesPart, t + 21s);
  ASSERT_EQ(late.size(), 2u);
  EXPECT_EQ(late[0].frameId, 3u);  // open since the window came to a later frame
  EXPECT_EQ(late[0].missing, std::vector<int>{1});
  EXPECT_EQ(late[1].missing, std::vector<int>{0});
}

TEST(FrameAgreements, AGatherCompletesWithEveryoneOrAtItsDeadlineWithGaps) {
  FrameAgreements board(3);
  const auto all = [](int, std::uint32_t) { return true; };
  const auto t = Clock::now();
  board.pixels(1, 9, {11, 12});
  EXPECT_TRUE(board.gathered(all, t).empty());  // the head has not asked
  board.headPixels(9, {1}, t + 1s);
  EXPECT_TRUE(board.gathered(all, t).empty());  // process 2 missing, deadline ahead
  const auto done = board.gathered(all, t + 2s);
  ASSERT_EQ(done.size(), 1u);
  EXPECT_EQ(done[0].pixels[0], (std::vector<std::uint32_t>{1}));
  EXPECT_EQ(done[0].pixels[1], (std::vector<std::uint32_t>{11, 12}));
  EXPECT_TRUE(done[0].pixels[2].empty());  // lost: dark in the wall preview
}

}  // namespace
}  // namespace wall::service
