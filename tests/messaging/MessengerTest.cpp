// Multi-rank tests of the messaging layer; run under mpiexec with 1, 2 and 4 ranks.
#include "messaging/Messenger.h"

#include <gtest/gtest.h>
#include <mpi.h>

#include <tbb/global_control.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <map>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "base/Error.h"
#include "tests/MpiTestUtil.h"

namespace messaging {
namespace {

using testutil::worldRank;
using testutil::worldSize;

// A payload whose bytes depend on (sender, receiver, index), so corruption shows.
Bytes makePayload(int from, int to, int index, size_t size, bool compressible) {
  Bytes payload(size);
  std::mt19937 random(static_cast<unsigned>(from * 7919 + to * 104729 + index));
  for (size_t i = 0; i < size; ++i)
    payload[i] = static_cast<std::byte>(compressible ? (i / 64 + static_cast<size_t>(index)) & 0xff
                                                     : random() & 0xff);
  return payload;
}

struct Recorder : MessageHandler {
  std::mutex mutex;
  std::vector<std::pair<int, Bytes>> received;
  void incoming(int fromRank, Bytes&& payload) override {
    std::lock_guard lock(mutex);
    received.emplace_back(fromRank, std::move(payload));
  }
};

class MessengerRoundTrip : public ::testing::TestWithParam<bool> {};

TEST_P(MessengerRoundTrip, EveryRankReachesEveryRankIntact) {
  const bool compress = GetParam();
  MessengerOptions options;
  options.compress = compress;
  options.compressWithinHost = true;  // every rank of a test shares this host
  Messenger messenger(MPI_COMM_WORLD, options);
  Recorder recorder;
  messenger.registerObject(11, &recorder);
  MPI_Barrier(MPI_COMM_WORLD);

  const int rank = worldRank(), size = worldSize();
  constexpr int kPerPeer = 20;
  for (int to = 0; to < size; ++to)
    for (int i = 0; i < kPerPeer; ++i)
      messenger.send(to, 11, makePayload(rank, to, i, 100 + 997 * static_cast<size_t>(i), i % 2));
  messenger.quiesce();

  ASSERT_EQ(recorder.received.size(), static_cast<size_t>(size * kPerPeer));
  std::map<int, int> nextIndex;  // per sender: messages arrive in the order sent
  for (auto& [from, payload] : recorder.received) {
    const int i = nextIndex[from]++;
    EXPECT_EQ(payload, makePayload(from, rank, i, 100 + 997 * static_cast<size_t>(i), i % 2))
        << "from rank " << from << " message " << i;
  }
  const MessengerCounters counters = messenger.counters();
  EXPECT_EQ(counters.unknownReceiver, 0u);
  EXPECT_EQ(counters.handlerErrors, 0u);
  // The only object in use carries all the traffic between ranks.
  EXPECT_EQ(messenger.traffic(11).bytesSent, counters.wireBytesSent);
  EXPECT_EQ(messenger.traffic(11).bytesReceived, counters.wireBytesReceived);
  EXPECT_EQ(messenger.traffic(12).bytesSent, 0u);
  if (size > 1) {
    if (compress) {
      EXPECT_GT(counters.messagesCompressed, 0u);
      EXPECT_LT(counters.wireBytesSent, counters.rawBytesSent);
    } else {
      EXPECT_EQ(counters.messagesCompressed, 0u);
    }
  }
  messenger.stop();
}

INSTANTIATE_TEST_SUITE_P(Compression, MessengerRoundTrip, ::testing::Bool());

struct Counter : MessageHandler {
  std::atomic<int> count{0};
  void incoming(int, Bytes&&) override { count++; }
};

TEST(Messenger, CompressesOnlyMessagesThatLeaveTheHostByDefault) {
  Messenger messenger(MPI_COMM_WORLD);
  Recorder recorder;
  messenger.registerObject(21, &recorder);
  MPI_Barrier(MPI_COMM_WORLD);
  for (int to = 0; to < worldSize(); ++to) {
    EXPECT_TRUE(messenger.sameHost(to)) << "all test ranks run on this host";
    EXPECT_FALSE(messenger.compresses(to));
    messenger.send(to, 21, Bytes(100000, std::byte{7}));  // would compress 100x
  }
  messenger.quiesce();
  EXPECT_EQ(recorder.received.size(), static_cast<size_t>(worldSize()));
  EXPECT_EQ(messenger.counters().messagesCompressed, 0u);
  messenger.stop();
}

TEST(Messenger, ManyObjectsEachGetTheirOwnMessages) {
  Messenger messenger(MPI_COMM_WORLD);
  constexpr int kObjects = 64;
  std::vector<Counter> counters(kObjects);
  for (int id = 0; id < kObjects; ++id) messenger.registerObject(1000 + id, &counters[id]);
  MPI_Barrier(MPI_COMM_WORLD);

  // Rank r sends (id + 1) messages to object id on every rank, so each object on each rank
  // must see size * (id + 1) messages.
  for (int to = 0; to < worldSize(); ++to)
    for (int id = 0; id < kObjects; ++id)
      for (int k = 0; k <= id; ++k) messenger.send(to, 1000 + id, Bytes(16, std::byte{1}));
  messenger.quiesce();
  for (int id = 0; id < kObjects; ++id)
    EXPECT_EQ(counters[id].count.load(), worldSize() * (id + 1)) << "object " << id;
  messenger.stop();
}

TEST(Messenger, MessageToUnknownIdIsReportedWithBothIds) {
  Messenger messenger(MPI_COMM_WORLD);
  std::vector<std::string> errors;
  std::mutex errorsMutex;
  messenger.setErrorCallback([&](const std::string& e) {
    std::lock_guard lock(errorsMutex);
    errors.push_back(e);
  });
  Counter known;
  messenger.registerObject(5, &known);
  MPI_Barrier(MPI_COMM_WORLD);

  const int rank = worldRank(), size = worldSize();
  const int next = (rank + 1) % size;
  messenger.send(next, 999, Bytes(8));
  messenger.send(next, 5, Bytes(8));
  messenger.quiesce();

  const int previous = (rank + size - 1) % size;
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("object id 999"), std::string::npos) << errors[0];
  EXPECT_NE(errors[0].find("from rank " + std::to_string(previous)), std::string::npos)
      << errors[0];
  EXPECT_NE(errors[0].find("on rank " + std::to_string(rank)), std::string::npos) << errors[0];
  EXPECT_EQ(messenger.counters().unknownReceiver, 1u);
  EXPECT_EQ(known.count.load(), 1) << "the good message still arrives";
  // Bookkeeping stays bounded: an unknown id gets no traffic entry.
  EXPECT_EQ(messenger.traffic(999).bytesReceived, 0u);
  if (size > 1) {
    EXPECT_GT(messenger.traffic(5).bytesReceived, 0u);
  }
  messenger.stop();
}

// leave() is not collective: the last rank leaves, and every other rank's messenger reports it
// by rank and host, says so in departed(), and its quiesce() gives up at once instead of at its
// deadline.
TEST(Messenger, ARankThatLeavesIsReportedAndQuiesceGivesUpAtOnce) {
  if (worldSize() < 2) GTEST_SKIP() << "needs 2 ranks";
  MessengerOptions options;
  options.quiesceTimeout = std::chrono::seconds(60);
  Messenger messenger(MPI_COMM_WORLD, options);
  std::vector<std::string> errors;
  std::mutex errorsMutex;
  messenger.setErrorCallback([&](const std::string& e) {
    std::lock_guard lock(errorsMutex);
    errors.push_back(e);
  });
  // Every rank has its callback before one leaves (else the leave is printed, not reported).
  MPI_Barrier(MPI_COMM_WORLD);
  const int leaving = worldSize() - 1;
  if (worldRank() == leaving) {
    messenger.leave();
    EXPECT_TRUE(messenger.departed().empty());
    EXPECT_NO_THROW(messenger.stop());  // stopped already: nothing to do
    return;
  }
  const auto start = std::chrono::steady_clock::now();
  try {
    messenger.quiesce();
    ADD_FAILURE() << "quiesce() with a rank gone";
  } catch (const base::DeadlineError& e) {
    EXPECT_NE(std::string(e.what()).find("rank " + std::to_string(leaving) + " ("),
              std::string::npos)
        << e.what();
  }
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
  EXPECT_NE(messenger.departed().find("left without closing"), std::string::npos);
  {
    std::lock_guard lock(errorsMutex);
    ASSERT_GE(errors.size(), 1u);  // another survivor may leave meanwhile: reported after
    EXPECT_EQ(errors[0], messenger.departed());
  }
  messenger.leave();  // the others go too, without a collective
}

// A handler that forwards a token around the ring until it has travelled `hops` times:
// quiesce must also wait for messages sent by handlers.
struct Relay : MessageHandler {
  Messenger* messenger = nullptr;
  std::atomic<int> seen{0};
  void incoming(int, Bytes&& payload) override {
    seen++;
    int hopsLeft = static_cast<int>(payload[0]);
    if (hopsLeft == 0) return;
    payload[0] = static_cast<std::byte>(hopsLeft - 1);
    messenger->send((messenger->rank() + 1) % messenger->size(), 77, std::move(payload));
  }
};

TEST(Messenger, QuiesceWaitsForMessagesSentByHandlers) {
  Messenger messenger(MPI_COMM_WORLD);
  Relay relay;
  relay.messenger = &messenger;
  messenger.registerObject(77, &relay);
  MPI_Barrier(MPI_COMM_WORLD);
  constexpr int kHops = 40;
  messenger.send((worldRank() + 1) % worldSize(), 77, Bytes(1, std::byte{kHops}));
  messenger.quiesce();
  int total = 0, mine = relay.seen.load();
  MPI_Allreduce(&mine, &total, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(total, worldSize() * (kHops + 1));
  messenger.stop();
}

// Ranks share cores: an idle messenger must sleep, not spin its MPI thread. Counted in passes of
// its loop, not in CPU time, which a loaded machine inflates: each idle pass sleeps at least the
// current idle sleep (more under load, never less), so an idle second allows at most
// 1 s / maxIdleSleep passes plus the back-off's ramp; a thread that spins makes hundreds of
// thousands even on a share of a core.
TEST(Messenger, IdleMessengerBacksOffInsteadOfSpinning) {
  MessengerOptions options;
  Messenger messenger(MPI_COMM_WORLD, options);
  MPI_Barrier(MPI_COMM_WORLD);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));  // let it settle into idling
  auto idleSecond = [&] {
    const std::uint64_t before = messenger.counters().mpiThreadWakeups;
    std::this_thread::sleep_for(std::chrono::seconds(1));
    return messenger.counters().mpiThreadWakeups - before;
  };
  const std::uint64_t awake = idleSecond();
  const auto allowed = [](std::chrono::microseconds sleep) {
    return static_cast<std::uint64_t>(std::chrono::seconds(1) / sleep) + 64;
  };
  EXPECT_LE(awake, allowed(options.maxIdleSleep)) << "MPI thread passes in an idle second";
  // Resting (a converged wall), the sleeps grow to restingSleep.
  messenger.setResting(true);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  const std::uint64_t resting = idleSecond();
  EXPECT_LE(resting, allowed(options.restingSleep)) << "MPI thread passes in a resting second";
  std::printf("idle messenger: %llu passes of the MPI thread per second, %llu resting\n",
              static_cast<unsigned long long>(awake), static_cast<unsigned long long>(resting));
  MPI_Barrier(MPI_COMM_WORLD);
  messenger.stop();
}

// The receiver's cap is the sender's: a payload above maxMessageBytes is refused by send(),
// before anything is queued (a 2.5 GiB one would have wrapped MPI's int count).
TEST(Messenger, SendRefusesAPayloadAboveTheReceiversCap) {
  MessengerOptions options;
  options.maxMessageBytes = 4096;
  Messenger messenger(MPI_COMM_WORLD, options);
  Counter counter;
  messenger.registerObject(5, &counter);
  MPI_Barrier(MPI_COMM_WORLD);
  const int next = (worldRank() + 1) % worldSize();
  try {
    messenger.send(next, 5, Bytes(4097));
    ADD_FAILURE() << "send() took a payload above the cap";
  } catch (const base::Error& e) {
    EXPECT_NE(std::string(e.what()).find("object id 5 on rank " + std::to_string(next) +
                                         " of 4097 bytes, more than the limit of 4096"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(messenger.counters().messagesSent, 0u);
  messenger.send(next, 5, Bytes(4096));  // the cap itself passes
  messenger.quiesce();
  EXPECT_EQ(counter.count.load(), 1);
  // Stopped before rank 0 goes on alone: the other ranks must not wait in a quiesce meanwhile
  // (filling 2.5 GiB takes over 20 s under AddressSanitizer).
  messenger.stop();
  // A real 2.5 GiB payload (on one rank only: it is held for a moment) is refused by send() of a
  // messenger with the default cap, before MPI sees it.
  const std::size_t gib = std::size_t{1} << 30;
  if (worldRank() == 0) {
    Messenger defaults(MPI_COMM_SELF);
    Bytes huge(5 * gib / 2);
    EXPECT_THROW(defaults.send(0, 5, std::move(huge)), base::Error);
    EXPECT_EQ(defaults.counters().messagesSent, 0u);
    defaults.stop();
  }
  // The same check send() makes first, for the sizes the issue names.
  EXPECT_THROW(checkPayloadSize(5 * gib / 2, MessengerOptions{}.maxMessageBytes, "a payload"),
               base::Error);
  EXPECT_THROW(checkPayloadSize(5 * gib / 2, ~std::size_t{0}, "a payload"), base::Error);
  EXPECT_NO_THROW(checkPayloadSize(gib, MessengerOptions{}.maxMessageBytes, "a payload"));
}

TEST(Messenger, ALimitAboveWhatMpiCanCountIsRefused) {
  MessengerOptions options;
  options.maxMessageBytes = std::size_t{3} << 30;
  EXPECT_THROW(Messenger(MPI_COMM_WORLD, options), base::Error);
}

TEST(Messenger, StopWithMessagesInFlightLosesNothing) {
  Counter counter;
  constexpr int kMessages = 500;
  {
    Messenger messenger(MPI_COMM_WORLD);
    messenger.registerObject(3, &counter);
    MPI_Barrier(MPI_COMM_WORLD);
    for (int i = 0; i < kMessages; ++i)
      messenger.send(i % worldSize(), 3, Bytes(static_cast<size_t>(64 + i * 37 % 5000)));
    // No quiesce: the destructor's stop must flush everything first.
  }
  int total = 0, mine = counter.count.load();
  MPI_Allreduce(&mine, &total, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(total, worldSize() * kMessages);
}

// What a concurrent handler and a serial one saw: the serial one in send order per sender, the
// concurrent one several at once, and neither overtaking the other (messaging/Messenger.h).
struct Ordering {
  std::mutex mutex;
  std::map<int, std::vector<int>> serialSeen;  // per sender: the sequence numbers, in order
  std::map<int, int> concurrentDone;           // per sender: handled so far
  std::map<int, int> serialDone;               // per sender
  std::vector<std::string> problems;
  std::atomic<int> inFlight{0}, maxInFlight{0};
};

// Payload: [sequence, serial messages sent before it, concurrent messages sent before it].
struct Sent {
  int sequence, serialBefore, concurrentBefore;
};

struct ConcurrentSide : MessageHandler {
  Ordering* o = nullptr;
  bool concurrent() const override { return true; }
  void incoming(int from, Bytes&& payload) override {
    const int now = ++o->inFlight;
    for (int seen = o->maxInFlight.load();
         now > seen && !o->maxInFlight.compare_exchange_weak(seen, now);) {
    }
    Sent m{};
    std::memcpy(&m, payload.data(), sizeof m);
    {
      std::lock_guard lock(o->mutex);
      // Every serial message sent before this one was handled first, none sent after it.
      if (o->serialDone[from] != m.serialBefore)
        o->problems.push_back("concurrent message " + std::to_string(m.sequence) + " from rank " +
                              std::to_string(from) + " saw " + std::to_string(o->serialDone[from]) +
                              " serial ones handled, not " + std::to_string(m.serialBefore));
    }
    std::this_thread::sleep_for(std::chrono::microseconds(500));  // time to overlap
    std::lock_guard lock(o->mutex);
    ++o->concurrentDone[from];
    --o->inFlight;
  }
};

struct SerialSide : MessageHandler {
  Ordering* o = nullptr;
  void incoming(int from, Bytes&& payload) override {
    Sent m{};
    std::memcpy(&m, payload.data(), sizeof m);
    std::lock_guard lock(o->mutex);
    if (o->concurrentDone[from] != m.concurrentBefore || o->inFlight.load() != 0)
      o->problems.push_back("serial message " + std::to_string(m.sequence) + " from rank " +
                            std::to_string(from) + " ran with " +
                            std::to_string(o->concurrentDone[from]) +
                            " concurrent ones done, not " + std::to_string(m.concurrentBefore));
    o->serialSeen[from].push_back(m.sequence);
    ++o->serialDone[from];
  }
};

TEST(Messenger, ConcurrentHandlersRunTogetherAndNeverCrossSerialOnes) {
  // Room for TBB workers whatever the machine (a 1-core CI box would have none by default).
  tbb::global_control workers(tbb::global_control::max_allowed_parallelism, 4);
  MessengerOptions options;
  options.handlerThreads = 4;
  Messenger messenger(MPI_COMM_WORLD, options);
  Ordering ordering;
  ConcurrentSide concurrent;
  SerialSide serial;
  concurrent.o = serial.o = &ordering;
  messenger.registerObject(91, &concurrent);
  messenger.registerObject(92, &serial);
  MPI_Barrier(MPI_COMM_WORLD);
  // To every rank: runs of 40 concurrent messages, each run followed by a serial one.
  constexpr int kRuns = 4, kRun = 40;
  for (int to = 0; to < worldSize(); ++to) {
    int sequence = 0, serialSent = 0, concurrentSent = 0;
    for (int run = 0; run < kRuns; ++run) {
      for (int i = 0; i < kRun; ++i) {
        const Sent m{sequence++, serialSent, concurrentSent++};
        Bytes payload(sizeof m);
        std::memcpy(payload.data(), &m, sizeof m);
        messenger.send(to, 91, std::move(payload));
      }
      const Sent m{sequence++, serialSent++, concurrentSent};
      Bytes payload(sizeof m);
      std::memcpy(payload.data(), &m, sizeof m);
      messenger.send(to, 92, std::move(payload));
    }
  }
  messenger.quiesce();
  for (const std::string& p : ordering.problems) ADD_FAILURE() << p;
  for (int from = 0; from < worldSize(); ++from) {
    EXPECT_EQ(ordering.concurrentDone[from], kRuns * kRun) << "from rank " << from;
    std::vector<int> expected;
    for (int run = 0; run < kRuns; ++run) expected.push_back(run * (kRun + 1) + kRun);
    EXPECT_EQ(ordering.serialSeen[from], expected) << "from rank " << from;
  }
  // Each rank sent itself 160 messages of 0.5 ms at once: the arena handled some together.
  EXPECT_GE(ordering.maxInFlight.load(), 2);
  std::printf("concurrent handler: up to %d messages at once\n", ordering.maxInFlight.load());
  messenger.stop();
}

// A message is one MPI message however large: a wall piece or a gathered display is never cut
// into many small sends, on the sender's side nor the receiver's.
TEST(Messenger, ALargeMessageIsOneMpiMessage) {
  if (worldSize() < 2) GTEST_SKIP() << "needs two ranks";
  Messenger messenger(MPI_COMM_WORLD);
  Recorder recorder;
  messenger.registerObject(93, &recorder);
  MPI_Barrier(MPI_COMM_WORLD);
  constexpr size_t kBytes = 1920 * 1080 * 4;  // a whole 1080p display of RGBA8
  const MessengerCounters before = messenger.counters();
  const int to = (worldRank() + 1) % worldSize();
  messenger.send(to, 93, makePayload(worldRank(), to, 0, kBytes, false));
  messenger.quiesce();
  const MessengerCounters after = messenger.counters();
  EXPECT_EQ(after.messagesSent - before.messagesSent, 1u);
  EXPECT_EQ(after.messagesReceived - before.messagesReceived, 1u);
  EXPECT_EQ(after.wireBytesSent - before.wireBytesSent, kBytes + Messenger::kSpareCapacity);
  ASSERT_EQ(recorder.received.size(), 1u);
  const int from = (worldRank() + worldSize() - 1) % worldSize();
  EXPECT_EQ(recorder.received[0].second, makePayload(from, worldRank(), 0, kBytes, false));
  messenger.stop();
}

}  // namespace
}  // namespace messaging
