// Every wait has a bound (base/BoundedWait.h), on real MPI requests of this rank alone
// (MPI_COMM_SELF, so the test runs the same at any rank count): a request that completes is
// waited for, one that never does ends in base::DeadlineError with its message at its deadline, and
// the long wait's polling costs (nearly) no CPU.
#include "base/BoundedWait.h"

#include <gtest/gtest.h>
#include <mpi.h>
#include <time.h>

#include <chrono>
#include <thread>

#include "base/Error.h"
#include "tests/Stopwatch.h"

namespace messaging {
namespace {

using namespace std::chrono_literals;
using testutil::Clock;
using testutil::secondsSince;

double threadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

// A receive on a private communicator, matched by a send from another thread after `delay`
// (or never, when `delay` is negative).
class Receive {
 public:
  explicit Receive(std::chrono::milliseconds delay) {
    MPI_Comm_dup(MPI_COMM_SELF, &comm_);
    MPI_Irecv(&value_, 1, MPI_INT, 0, 7, comm_, &request);
    if (delay >= 0ms)
      sender_ = std::thread([this, delay] {
        std::this_thread::sleep_for(delay);
        const int value = 42;
        MPI_Send(&value, 1, MPI_INT, 0, 7, comm_);
      });
  }
  ~Receive() {
    if (sender_.joinable()) sender_.join();
    if (request != MPI_REQUEST_NULL) {  // never matched: cancelled, so nothing is left pending
      MPI_Cancel(&request);
      MPI_Wait(&request, MPI_STATUS_IGNORE);
    }
    MPI_Comm_free(&comm_);
  }
  int value() const { return value_; }

  MPI_Request request = MPI_REQUEST_NULL;

 private:
  MPI_Comm comm_ = MPI_COMM_NULL;
  int value_ = 0;
  std::thread sender_;
};

TEST(BoundedWait, ARequestThatCompletesIsWaitedFor) {
  Receive receive(200ms);
  const auto start = Clock::now();
  base::waitWithDeadline(receive.request, start + 20s, "never said");
  EXPECT_EQ(receive.value(), 42);
  EXPECT_EQ(receive.request, MPI_REQUEST_NULL);  // completed and freed by MPI_Test
  EXPECT_GE(secondsSince(start), 0.19);
  EXPECT_LT(secondsSince(start), 10.0);
}

TEST(BoundedWait, ACompletedRequestReturnsEvenPastItsDeadline) {
  Receive receive(0ms);
  std::this_thread::sleep_for(100ms);  // matched by now
  base::waitWithDeadline(receive.request, Clock::now() - 1s, "never said");
  EXPECT_EQ(receive.value(), 42);
}

TEST(BoundedWait, ARequestThatNeverCompletesEndsAtItsDeadlineWithItsMessage) {
  for (const auto maxSleep : {20us, 50000us}) {
    Receive receive(-1ms);
    const auto start = Clock::now();
    try {
      if (maxSleep == 20us)
        base::waitWithDeadline(receive.request, start + 300ms, "swap barrier of frame 7: late");
      else
        base::waitWithDeadline(receive.request, start + 300ms, "swap barrier of frame 7: late",
                               maxSleep);
      ADD_FAILURE() << "returned without the request completing";
    } catch (const base::DeadlineError& e) {
      EXPECT_STREQ(e.what(), "swap barrier of frame 7: late");
    }
    const double waited = secondsSince(start);
    EXPECT_GE(waited, 0.3);
    EXPECT_LT(waited, 3.0) << "the deadline was 0.3 s";
    EXPECT_NE(receive.request, MPI_REQUEST_NULL);  // still pending: the caller decides
  }
}

// A wait whose `unless` names a reason (a peer that left for good) ends with it at once, long
// before its deadline; the request stays pending, as at a deadline.
TEST(BoundedWait, AReasonToGiveUpEndsTheWaitBeforeItsDeadline) {
  Receive receive(-1ms);
  const auto start = Clock::now();
  int polls = 0;
  try {
    base::waitWithDeadline(
        receive.request, start + 30s, "frame 3: late", 1000us,
        [&]() -> std::string { return ++polls < 5 ? "" : "rank 2 (host) left without closing"; });
    ADD_FAILURE() << "returned without the request completing";
  } catch (const base::DeadlineError& e) {
    EXPECT_STREQ(e.what(), "rank 2 (host) left without closing");
  }
  EXPECT_EQ(polls, 5);
  EXPECT_LT(secondsSince(start), 3.0) << "the deadline was 30 s";
  EXPECT_NE(receive.request, MPI_REQUEST_NULL);
}

// The long wait (a rank idling until the next order) sleeps longer and longer between polls:
// a second of waiting costs this thread a few milliseconds of CPU, not a core; and it still
// notices the completion within its longest sleep.
TEST(BoundedWait, TheLongWaitCostsNearlyNoCpuAndStillNoticesCompletion) {
  Receive receive(1000ms);
  const auto start = Clock::now();
  const double cpu = threadCpuSeconds();
  base::waitWithDeadline(receive.request, start + 20s, "never said", 50ms);
  const double used = threadCpuSeconds() - cpu, waited = secondsSince(start);
  EXPECT_EQ(receive.value(), 42);
  EXPECT_GE(waited, 0.99);
  EXPECT_LT(waited, 5.0);
  // About 20 polls in a second (the sleeps double from 20 us to 50 ms): this thread's own CPU
  // time, so a loaded machine does not inflate it.
  EXPECT_LT(used, 0.05) << "CPU seconds spent polling over " << waited << " s";
}

}  // namespace
}  // namespace messaging
