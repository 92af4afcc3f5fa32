// Frame pacing (wall/route/FrameCredits.h) on render rank 0's side: acknowledgements in order, the
// bounded wait for one, the times a frame's statistics take, and the wire message through a real
// messenger (run on 1 rank: wall process 0 and render rank 0 are the same rank here).
#include "wall/route/FrameCredits.h"

#include <gtest/gtest.h>
#include <mpi.h>

#include <chrono>
#include <cstring>
#include <thread>

#include "base/Error.h"
#include "tests/Stopwatch.h"

namespace wall {
namespace {

using namespace std::chrono_literals;
using testutil::Clock;
using testutil::secondsSince;

TEST(FrameCredits, AcknowledgementsCountUpInOrderAndKeepTheirTimes) {
  FrameCredits credits;
  EXPECT_EQ(credits.lastPresented(), 0);
  credits.waitForPresented(0, 0ms);  // nothing to wait for below frame 1
  credits.waitForPresented(-5, 0ms);
  const std::int64_t before = Clock::now().time_since_epoch().count();
  credits.acknowledged(1, 111, "rank 4");
  credits.acknowledged(2, 222, "rank 4");
  credits.acknowledged(3, 333, "rank 4");
  EXPECT_EQ(credits.lastPresented(), 3);
  credits.waitForPresented(3, 0ms);  // returns at once: presented already

  const auto two = credits.takeTimes(2);
  ASSERT_TRUE(two.has_value());
  EXPECT_EQ(two->completeNs, 222);
  EXPECT_GE(two->acknowledgedNs, before);
  EXPECT_LE(two->acknowledgedNs, Clock::now().time_since_epoch().count());
  EXPECT_FALSE(credits.takeTimes(2).has_value()) << "taken once";
  EXPECT_FALSE(credits.takeTimes(1).has_value()) << "older ones go with it";
  EXPECT_EQ(credits.takeTimes(3)->completeNs, 333);
  EXPECT_FALSE(credits.takeTimes(4).has_value()) << "not acknowledged yet";
}

TEST(FrameCredits, AnAcknowledgementOutOfOrderIsAnErrorNamingItsSender) {
  FrameCredits credits;
  credits.acknowledged(1, 0, "rank 4");
  for (std::uint32_t wrong : {1u, 3u, 0u}) {
    try {
      credits.acknowledged(wrong, 0, "wall link 2");
      ADD_FAILURE() << "frame " << wrong << " accepted";
    } catch (const base::Error& e) {
      EXPECT_EQ(std::string(e.what()), "frame acknowledgement for frame " + std::to_string(wrong) +
                                           " from wall link 2 after frame 1");
    }
  }
  EXPECT_EQ(credits.lastPresented(), 1);  // unchanged by the refused ones
}

TEST(FrameCredits, TheWaitIsBoundedAndEndsWithTheAcknowledgement) {
  FrameCredits credits;
  auto start = Clock::now();
  try {
    credits.waitForPresented(1, 200ms);
    ADD_FAILURE() << "no acknowledgement came, yet the wait returned";
  } catch (const base::DeadlineError& e) {
    EXPECT_STREQ(e.what(), "the wall did not present frame 1 within 200 ms (last presented: 0)");
  }
  EXPECT_GE(secondsSince(start), 0.19);

  std::thread wall([&] {
    std::this_thread::sleep_for(150ms);
    credits.acknowledged(1, 0, "rank 4");
    std::this_thread::sleep_for(150ms);
    credits.acknowledged(2, 0, "rank 4");
  });
  start = Clock::now();
  credits.waitForPresented(2, 20s);
  wall.join();
  EXPECT_EQ(credits.lastPresented(), 2);
  EXPECT_GE(secondsSince(start), 0.29);
  EXPECT_LT(secondsSince(start), 10.0) << "woken by the acknowledgement, not at the deadline";
}

// Only the times of the last 64 frames are kept (a run without statistics never takes them).
TEST(FrameCredits, TimesAreKeptForTheLast64FramesOnly) {
  FrameCredits credits;
  for (std::uint32_t f = 1; f <= 100; ++f) credits.acknowledged(f, f * 10, "rank 4");
  EXPECT_FALSE(credits.takeTimes(36).has_value());
  EXPECT_EQ(credits.takeTimes(37)->completeNs, 370);
  EXPECT_EQ(credits.takeTimes(100)->completeNs, 1000);
}

// The wire: acknowledgeFrame through a real messenger reaches the credits registered on rank 0;
// a payload of the wrong size is refused naming its size and sender.
TEST(FrameCredits, AcknowledgementsTravelThroughTheMessenger) {
  messaging::Messenger messenger(MPI_COMM_SELF);
  {
    FrameCredits credits(messenger);
    acknowledgeFrame(messenger, 1, 123456789);
    acknowledgeFrame(messenger, 2, -7);
    credits.waitForPresented(2, 20s);
    EXPECT_EQ(credits.takeTimes(1)->completeNs, 123456789);
    EXPECT_EQ(credits.takeTimes(2)->completeNs, -7);
    messaging::Bytes wrong(15);
    try {
      credits.incoming(5, std::move(wrong));
      ADD_FAILURE() << "a 15-byte acknowledgement was accepted";
    } catch (const base::Error& e) {
      EXPECT_STREQ(e.what(), "malformed frame acknowledgement of 15 bytes from rank 5");
    }
  }
  messenger.stop();
}

}  // namespace
}  // namespace wall
