// The wall's own coordination (wall/service/server/Desk.h, wall/service/server/MemberLink.h) in one
// process: a real desk and real member links over ZeroMQ on loopback, and a real job link
// (wall/service/client/ServiceClient.h), with the processes' answers given by the test. Checks what
// the end-to-end tests (tests/apps/wall_survives_test.sh, cluster_test.sh survive) cannot pin
// down exactly: who takes part in which swap barrier, when a silent process is dropped, the
// roster the job gets, the first frame a process that comes back is given, refusals.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <future>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "base/Error.h"
#include "wall/route/FrameCredits.h"
#include "wall/service/client/ServiceClient.h"
#include "wall/service/protocol/LinkMessages.h"
#include "wall/service/server/Desk.h"
#include "wall/service/server/MemberLink.h"

namespace wall::service {
namespace {

using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;
constexpr auto kTimeout = 600ms;

Layout threeProcessLayout() {
  const auto path = std::filesystem::temp_directory_path() /
                    ("dfbwall-walllink-layout-" + std::to_string(::getpid()) + ".toml");
  std::ofstream(path) << "[grid]\ncolumns = 3\nrows = 1\ndisplay_size = [64, 64]\n";
  Layout layout = loadLayout(path.string());
  std::filesystem::remove(path);
  return layout;
}

// One process's side: what the head told it, and its answers (Ready at once; a process that
// joins a running job is Ready too and then waits for its first frame).
struct Process {
  std::mutex mutex;
  std::vector<ServiceCommand> got;
  std::atomic<std::uint32_t> firstFrame{0};
  ProcessLink* link = nullptr;
  // The process's presenting thread, as far as the link sees it: alive until `hangs`.
  std::atomic<bool> hangs{false}, stop{false};
  std::thread presenting;
  void startPresenting(MemberLink& member) {
    presenting = std::thread([this, &member] {
      while (!stop) {
        if (!hangs) member.mainAlive();
        std::this_thread::sleep_for(50ms);
      }
    });
  }
  ~Process() {
    stop = true;
    if (presenting.joinable()) presenting.join();
  }

  void deliver(const ServiceCommand& c) {
    {
      std::lock_guard lock(mutex);
      got.push_back(c);
    }
    if (c.header.kind == Command::FirstFrame) firstFrame = static_cast<std::uint32_t>(c.header.a);
    if (c.header.kind != Command::Start) return;
    if (c.header.a > 0) firstFrame = static_cast<std::uint32_t>(c.header.a);
    ServiceCommand ready;
    ready.header.kind = Command::Ready;
    ready.header.session = c.header.session;
    ready.header.a = 1;
    link->toHead(ready, link->epoch());
  }
  bool got_(Command kind) {
    std::lock_guard lock(mutex);
    for (const ServiceCommand& c : got)
      if (c.header.kind == kind) return true;
    return false;
  }
};

bool eventually(const std::function<bool()>& condition, std::chrono::milliseconds within) {
  const auto until = Clock::now() + within;
  while (Clock::now() < until) {
    if (condition()) return true;
    std::this_thread::sleep_for(10ms);
  }
  return condition();
}

class WallLinkTest : public ::testing::Test {
 protected:
  void SetUp() override {
    layout = threeProcessLayout();
    ASSERT_EQ(layout.processCount, 3);
    Desk::Setup setup;
    setup.layout = &layout;
    setup.options.timeout = kTimeout;
    setup.options.framesInFlight = 2;
    setup.options.log = [](const std::string& line) {
      std::fprintf(stderr, "head: %s\n", line.c_str());
    };
    setup.options.credentials.token = "t";
    setup.ownEndpoint = "tcp://127.0.0.1:1";
    setup.deliver = [this](const ServiceCommand& c) { head.deliver(c); };
    desk = std::make_unique<Desk>(std::move(setup));
    head.link = desk.get();
    address = "127.0.0.1:" + std::to_string(portOf(desk->bind("tcp://127.0.0.1:*")));
    desk->start();
    for (int p = 1; p < 3; ++p) join(p);
    ASSERT_TRUE(eventually([&] { return desk->absentProcesses().empty(); }, 5s));
  }
  void join(int p, const std::string& token = "t") {
    MemberLink::Setup setup;
    setup.head = address;
    setup.credentials.token = token;
    setup.join.process = static_cast<std::uint32_t>(p);
    setup.join.host = "test";
    setup.join.pieceEndpoint = "tcp://127.0.0.1:" + std::to_string(10000 + p);
    setup.join.layoutHash = layoutHash(layout);
    setup.timeout = kTimeout;
    processes[p] = std::make_unique<Process>();
    Process* process = processes[p].get();
    setup.deliver = [process](const ServiceCommand& c) { process->deliver(c); };
    links[p] = std::make_unique<MemberLink>(std::move(setup));
    process->link = links[p].get();
    links[p]->start();
    process->startPresenting(*links[p]);
  }
  // A job: its directory names every live process.
  void connectJob() {
    Hello hello;
    hello.host = "job";
    Credentials credentials;
    credentials.token = "t";
    client = std::make_unique<ServiceClient>(address, credentials, hello, 5s);
    client->start(credits, [this](const std::string& why) { jobError = why; });
  }
  // Frame `frameId`'s barrier among `who` (0: the head), each with its own values; the
  // element-wise maximum each got back.
  std::vector<std::vector<std::int64_t>> barrier(std::uint32_t frameId, std::vector<int> who) {
    std::vector<std::future<std::vector<std::int64_t>>> results;
    for (int p : who) {
      results.push_back(std::async(std::launch::async, [this, p, frameId] {
        std::vector<std::int64_t> values = {p * 10, -p, 0, 0, 0};
        ProcessLink& link = p == 0 ? static_cast<ProcessLink&>(*desk) : *links[p];
        link.agreeMax(link.epoch(), client->directory().session, frameId, values.data(), 5,
                      Clock::now() + 5s);
        return values;
      }));
    }
    std::vector<std::vector<std::int64_t>> out;
    for (auto& r : results) out.push_back(r.get());
    return out;
  }

  Layout layout;
  std::unique_ptr<Desk> desk;
  Process head;
  std::unique_ptr<MemberLink> links[3];
  std::unique_ptr<Process> processes[3];  // their presenting threads stop before the links go
  std::string address;
  FrameCredits credits;
  std::unique_ptr<ServiceClient> client;
  std::string jobError;
};

TEST_F(WallLinkTest, ABarrierAgreesOnTheMaximumOfEveryProcessInTheJob) {
  connectJob();
  ASSERT_EQ(client->directory().processes.size(), 3u);
  for (const DirectoryProcess& p : client->directory().processes) EXPECT_TRUE(p.live);
  EXPECT_EQ(client->directory().processes[2].endpoint, "tcp://127.0.0.1:10002");
  for (const auto& values : barrier(1, {0, 1, 2}))
    EXPECT_EQ(values, (std::vector<std::int64_t>{20, 0, 0, 0, 0}));
  // The head's process presented frame 1: the job's credit.
  desk->presented(client->directory().session, 1, 42);
  EXPECT_TRUE(eventually([&] { return credits.lastPresented() == 1; }, 2s));
}

TEST_F(WallLinkTest, ASilentProcessIsDroppedAndTheBarrierGoesOnWithoutIt) {
  connectJob();
  barrier(1, {0, 1, 2});
  processes[2].reset();
  links[2].reset();  // process 2 dies: no beats, no barrier
  const auto start = Clock::now();
  // Frame 2: the head and process 1 arrive; process 2 never does. Released once it is dropped.
  const auto results = barrier(2, {0, 1});
  const auto took = Clock::now() - start;
  for (const auto& values : results) EXPECT_EQ(values[0], 10);
  EXPECT_LT(took, kTimeout + 1s);
  EXPECT_EQ(desk->absentProcesses(), std::vector<int>{2});
  // The job hears of it: roster 1, process 2 not live.
  ASSERT_TRUE(eventually([&] { return client->rosterVersion() == 1; }, 2s));
  const messaging::Bytes bytes = client->rosterBytes();
  const Roster roster = parseRoster(bytes.data(), bytes.size());
  EXPECT_TRUE(roster.processes[0].live);
  EXPECT_TRUE(roster.processes[1].live);
  EXPECT_FALSE(roster.processes[2].live);
  EXPECT_NE(roster.why.find("lost wall process 2"), std::string::npos) << roster.why;
  EXPECT_TRUE(jobError.empty()) << jobError;
}

TEST_F(WallLinkTest, AProcessWhosePresentingThreadHangsIsDroppedThoughItsLinkIsUp) {
  connectJob();
  barrier(1, {0, 1, 2});
  processes[2]->hangs = true;  // a driver call that never returns
  EXPECT_TRUE(eventually([&] { return desk->absentProcesses() == std::vector<int>{2}; },
                         kTimeout + 1500ms));
  // Process 1 beats but does not come to frame 2's barrier: the timeout after the head came,
  // while the job is alive, it is dropped like a silent one and the head's frame goes on.
  const auto start = Clock::now();
  for (const auto& values : barrier(2, {0})) EXPECT_EQ(values[0], 0);
  const auto took = Clock::now() - start;
  EXPECT_GE(took, kTimeout);
  EXPECT_LT(took, kTimeout + 1s);
  ASSERT_TRUE(eventually([&] { return client->rosterVersion() == 2; }, 2s));
  const messaging::Bytes bytes = client->rosterBytes();
  const Roster roster = parseRoster(bytes.data(), bytes.size());
  EXPECT_NE(roster.why.find("lost wall process 1 on test after frame 0: it did not come to the "
                            "swap barrier of frame 2 within 600 ms of the others"),
            std::string::npos)
      << roster.why;
  EXPECT_TRUE(jobError.empty()) << jobError;
}

TEST_F(WallLinkTest, AProcessThatComesBackIsGivenTheFirstFrameTheJobCannotHaveStartedWithoutIt) {
  connectJob();
  barrier(1, {0, 1, 2});
  desk->presented(client->directory().session, 1, 0);
  ASSERT_TRUE(eventually([&] { return credits.lastPresented() == 1; }, 2s));
  processes[2].reset();
  links[2].reset();
  barrier(2, {0, 1});
  // Process 2 starts again (a new link, a new incarnation) and joins the running job: Start
  // with no first frame, Ready, then its first frame: last credited (1) + frames in flight (2)
  // + 1, and the job a roster naming it live again.
  join(2);
  ASSERT_TRUE(eventually([&] { return processes[2]->firstFrame != 0; }, 3s));
  EXPECT_EQ(processes[2]->firstFrame, 4u);
  ASSERT_TRUE(eventually([&] { return client->rosterVersion() == 2; }, 2s));
  const messaging::Bytes bytes = client->rosterBytes();
  const Roster roster = parseRoster(bytes.data(), bytes.size());
  EXPECT_TRUE(roster.processes[2].live);
  EXPECT_EQ(roster.fromFrame, 4u);
  // Frame 3 is not its: the head and process 1 agree alone. Frame 4 is everyone's.
  for (const auto& values : barrier(3, {0, 1})) EXPECT_EQ(values[0], 10);
  for (const auto& values : barrier(4, {0, 1, 2})) EXPECT_EQ(values[0], 20);
}

TEST_F(WallLinkTest, AnAnswerOfAnEarlierEpochIsNotTakenForTheNewOnes) {
  // A process's link lost the head and joined again; its old job's node still says Done.
  connectJob();
  const std::uint64_t before = links[1]->epoch();
  ServiceCommand done;
  done.header.kind = Command::Done;
  done.header.session = client->directory().session;
  done.text = "stale";
  // Drop process 1 from the head's side: it stops beating until it is dropped and rejoins.
  // Instead of waiting for that, check the link's own rule: an answer of another epoch is
  // never sent.
  links[1]->toHead(done, before + 1);
  for (const auto& values : barrier(1, {0, 1, 2})) EXPECT_EQ(values[0], 20);
  EXPECT_TRUE(jobError.empty()) << jobError;
}

// A job whose scene or bricks take longer than the wall's timeout to set up, between the
// directory and its first frame, is not dropped: its link keeps it alive from the directory on.
TEST_F(WallLinkTest, AJobThatSetsUpForLongerThanTheTimeoutIsNotDropped) {
  Hello hello;
  hello.host = "job";
  Credentials credentials;
  credentials.token = "t";
  client = std::make_unique<ServiceClient>(address, credentials, hello, 5s);
  std::this_thread::sleep_for(3 * kTimeout);  // setting up
  client->start(credits, [this](const std::string& why) { jobError = why; });
  std::this_thread::sleep_for(2 * kTimeout);
  EXPECT_TRUE(jobError.empty()) << jobError;
  const auto got = barrier(1, {0, 1, 2});
  for (const auto& values : got) EXPECT_EQ(values[0], 20);
  EXPECT_TRUE(jobError.empty()) << jobError;
}

TEST_F(WallLinkTest, AJoinWithAWrongTokenOrAnotherLayoutIsRefusedWithTheReason) {
  MemberLink::Setup setup;
  setup.head = address;
  setup.credentials.token = "wrong";
  setup.join.process = 1;
  setup.join.host = "stranger";
  setup.join.pieceEndpoint = "tcp://127.0.0.1:9";
  setup.join.layoutHash = layoutHash(layout);
  setup.timeout = kTimeout;
  MemberLink wrongToken(setup);
  wrongToken.start();
  try {
    wrongToken.waitUntilJoined(Clock::now() + 5s);
    FAIL() << "joined with a wrong token";
  } catch (const base::Error& e) {
    EXPECT_NE(std::string(e.what()).find("refused this token"), std::string::npos) << e.what();
  }
  setup.credentials.token = "t";
  setup.join.layoutHash ^= 1;
  MemberLink otherLayout(setup);
  otherLayout.start();
  try {
    otherLayout.waitUntilJoined(Clock::now() + 5s);
    FAIL() << "joined with another layout";
  } catch (const base::Error& e) {
    EXPECT_NE(std::string(e.what()).find("layout"), std::string::npos) << e.what();
  }
  // The wall's own processes are untouched.
  EXPECT_TRUE(desk->absentProcesses().empty());
}

}  // namespace
}  // namespace wall::service
