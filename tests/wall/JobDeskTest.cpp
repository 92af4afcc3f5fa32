// The jobs of a service wall's desk (wall/service/server/JobDesk.h) in process: decoded events
// in, actions out, the time the test's. The messages the actions carry are the real wire
// messages, read back with the protocol's parsers; the processes are a real Membership.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "wall/service/protocol/LinkMessages.h"
#include "wall/service/server/JobDesk.h"

namespace wall::service {
namespace {

using Clock = JobDesk::Clock;
using Actions = JobDesk::Actions;
using State = JobDesk::State;
using namespace std::chrono_literals;
constexpr auto kTimeout = 600ms;
const Clock::time_point t0{std::chrono::hours(1)};

Layout threeProcessLayout() {
  const auto path = std::filesystem::temp_directory_path() /
                    ("dfbwall-jobdesk-layout-" + std::to_string(::getpid()) + ".toml");
  std::ofstream(path) << "[grid]\ncolumns = 3\nrows = 1\ndisplay_size = [64, 64]\n";
  Layout layout = loadLayout(path.string());
  std::filesystem::remove(path);
  return layout;
}

template <class T>
std::vector<T> only(const Actions& actions) {
  std::vector<T> out;
  for (const JobDesk::Action& a : actions)
    if (const T* t = std::get_if<T>(&a)) out.push_back(*t);
  return out;
}

std::vector<JobDesk::Reply> replies(const Actions& actions, Kind kind) {
  std::vector<JobDesk::Reply> out;
  for (const JobDesk::Reply& r : only<JobDesk::Reply>(actions))
    if (r.kind == kind) out.push_back(r);
  return out;
}

std::string textOf(const JobDesk::Reply& r) {
  return parseText(r.message.data(), r.message.size());
}

// The processes given command `kind`, in order.
std::vector<int> given(const Actions& actions, Command kind) {
  std::vector<int> out;
  for (const JobDesk::ToProcess& c : only<JobDesk::ToProcess>(actions))
    if (c.command.header.kind == kind) out.push_back(c.process);
  return out;
}

ServiceCommand commandTo(const Actions& actions, int process, Command kind) {
  for (const JobDesk::ToProcess& c : only<JobDesk::ToProcess>(actions))
    if (c.process == process && c.command.header.kind == kind) return c.command;
  ADD_FAILURE() << "no such command to process " << process;
  return {};
}

std::vector<nlohmann::json> records(const Actions& actions) {
  std::vector<nlohmann::json> out;
  for (const JobDesk::Record& r : only<JobDesk::Record>(actions))
    out.push_back(nlohmann::json::parse(r.json));
  return out;
}

class JobDeskTest : public ::testing::Test {
 protected:
  JobDeskTest()
      : layout(threeProcessLayout()),
        members({3, "t", layoutHash(layout), layout.file, "tcp://head:1", kTimeout}, t0),
        jobs({&layout, "t", kTimeout, 2, [this] { return ++lastSession; }}, members) {
    for (int p = 1; p < 3; ++p) members.admit("link" + std::to_string(p), joinOf(p, 1), t0);
  }

  Join joinOf(int p, std::uint64_t incarnation) const {
    Join j;
    j.token = "t";
    j.process = static_cast<std::uint32_t>(p);
    j.host = "host" + std::to_string(p);
    j.pieceEndpoint = "tcp://host" + std::to_string(p) + ":" + std::to_string(incarnation);
    j.layoutHash = layoutHash(layout);
    j.incarnation = incarnation;
    return j;
  }
  static Hello helloFrom(const std::string& host, bool wait = false) {
    Hello h;
    h.token = "t";
    h.host = host;
    h.renderRanks = 4;
    h.framesInFlight = 3;  // the wall grants 2
    h.wait = wait;
    return h;
  }
  ServiceCommand answer(Command kind, std::int64_t a = 0, std::int64_t b = 0,
                        std::string text = {}) const {
    ServiceCommand c;
    c.header.kind = kind;
    c.header.session = jobs.session();
    c.header.a = a;
    c.header.b = b;
    c.text = std::move(text);
    return c;
  }
  // Every process in the wall answers Start; the actions of the last answer.
  Actions allReady(Clock::time_point now) {
    Actions last;
    for (int p = 0; p < 3; ++p)
      if (members.live(p)) last = jobs.answer(p, answer(Command::Ready, 1), now);
    return last;
  }
  // A job from `host` on connection `peer`, running: its directory.
  Directory run(const std::string& peer, const std::string& host, Clock::time_point now) {
    const Actions started = jobs.hello(peer, helloFrom(host), now);
    EXPECT_EQ(given(started, Command::Start), (std::vector<int>{0, 1, 2}));
    const auto directories = replies(allReady(now), Kind::Directory);
    EXPECT_EQ(directories.size(), 1u);
    EXPECT_EQ(jobs.state(), State::Running);
    if (directories.empty()) return {};
    EXPECT_EQ(directories[0].peer, peer);
    return parseDirectory(directories[0].message.data(), directories[0].message.size());
  }
  // Every process in the job says Done after `frames`; the actions of the last.
  Actions allDone(std::int64_t frames, Clock::time_point now) {
    Actions last;
    for (int p = 0; p < 3; ++p) last = jobs.answer(p, answer(Command::Done, frames, 100), now);
    return last;
  }
  // The loop's part of a loss: Membership drops, JobDesk is told.
  Actions lose(int p, const std::string& why, Clock::time_point now) {
    EXPECT_TRUE(members.drop(p));
    return jobs.lost(p, why, now);
  }

  Layout layout;
  Membership members;
  std::uint64_t lastSession = 100;
  JobDesk jobs;
};

TEST_F(JobDeskTest, AJobStartsOnceEveryProcessIsReadyAndGetsTheDirectory) {
  const Actions started = jobs.hello("job-a", helloFrom("render1"), t0);
  EXPECT_EQ(jobs.state(), State::Starting);
  const ServiceCommand start = commandTo(started, 1, Command::Start);
  EXPECT_EQ(start.header.session, 101u);
  EXPECT_EQ(start.header.a, 1);                // from frame 1
  EXPECT_EQ(start.header.framesInFlight, 2u);  // the job asked for 3
  EXPECT_EQ(start.header.renderRanks, 4u);
  EXPECT_TRUE(replies(jobs.answer(0, answer(Command::Ready, 1), t0), Kind::Directory).empty());
  EXPECT_TRUE(replies(jobs.answer(1, answer(Command::Ready, 1), t0), Kind::Directory).empty());
  const auto directory = replies(jobs.answer(2, answer(Command::Ready, 1), t0), Kind::Directory);
  ASSERT_EQ(directory.size(), 1u);
  const Directory d = parseDirectory(directory[0].message.data(), directory[0].message.size());
  EXPECT_EQ(d.session, 101u);
  EXPECT_EQ(d.framesInFlight, 2u);
  EXPECT_EQ(d.timeoutMs, 600u);
  ASSERT_EQ(d.processes.size(), 3u);
  EXPECT_EQ(d.processes[0].endpoint, "tcp://head:1");
  EXPECT_EQ(d.processes[2].endpoint, "tcp://host2:1");
  for (const DirectoryProcess& p : d.processes) EXPECT_TRUE(p.live);
}

// A job in a window (wall/layout/Window.h): every process gets the window in its Start, the job
// the window's layout, and a process with no display in it is told to start (it has no pieces
// to wait for) once the job runs.
TEST_F(JobDeskTest, AJobInAWindowGetsTheWindowsLayout) {
  Hello hello = helloFrom("render1");
  hello.window = parseWindowRequest("100,10,50,50");  // displays 1 (64..128) and 2 (128..192)
  const Actions started = jobs.hello("job-a", hello, t0);
  const ServiceCommand start = commandTo(started, 0, Command::Start);
  EXPECT_EQ(start.header.windowX0, 100);
  EXPECT_EQ(start.header.windowY0, 10);
  EXPECT_EQ(start.header.windowX1, 150);
  EXPECT_EQ(start.header.windowY1, 60);
  const Actions running = allReady(t0);
  const auto directory = replies(running, Kind::Directory);
  ASSERT_EQ(directory.size(), 1u);
  const Directory d = parseDirectory(directory[0].message.data(), directory[0].message.size());
  EXPECT_EQ(d.window, (dfb::Region{100, 10, 150, 60}));
  EXPECT_EQ(d.layout.canvasWidth, 50);
  EXPECT_EQ(d.layout.canvasHeight, 50);
  EXPECT_EQ(d.layout.processCount, 3);
  ASSERT_EQ(d.layout.displays.size(), 2u);
  EXPECT_EQ(d.layout.displays[0].rect, (dfb::Region{0, 0, 28, 50}));
  EXPECT_EQ(d.layout.displays[0].process, 1);
  EXPECT_EQ(d.layout.displays[1].rect, (dfb::Region{28, 0, 50, 50}));
  EXPECT_EQ(d.layout.displays[1].process, 2);
  EXPECT_EQ(d.processes.size(), 3u);
  EXPECT_EQ(given(running, Command::FirstFrame), (std::vector<int>{0}));
  // The whole canvas: no process waits for a FirstFrame.
  allDone(0, t0);
  ASSERT_EQ(jobs.state(), State::Idle);
  jobs.hello("job-b", helloFrom("render2"), t0);
  EXPECT_TRUE(given(allReady(t0), Command::FirstFrame).empty());
}

// Processes out of a job's window come to each barrier as soon as the one before is released:
// only the window's process paces the job. A converged job idles past the timeout with them
// waiting at the next frame, and nobody is dropped; its goodbye lets them go once the window's
// process is done, and no frame past the job's last is presented.
TEST_F(JobDeskTest, AJobInAWindowIdlesPastTheTimeoutAndEndsAfterItsLastFrame) {
  Hello hello = helloFrom("render1");
  hello.window = parseWindowRequest("130,0,40,40");  // display 2 only: processes 0 and 1 are out
  jobs.hello("job-a", hello, t0);
  EXPECT_EQ(given(allReady(t0), Command::FirstFrame), (std::vector<int>{0, 1}));
  const std::uint64_t session = jobs.session();
  jobs.arrive(0, session, 1, {1}, t0 + 10ms);
  EXPECT_TRUE(only<JobDesk::Release>(jobs.arrive(1, session, 1, {1}, t0 + 10ms)).empty());
  EXPECT_EQ(only<JobDesk::Release>(jobs.arrive(2, session, 1, {1}, t0 + 20ms)).size(), 3u);
  jobs.presented(session, 1, 0);
  // Converged: 0 and 1 wait at frame 2, which the job does not render.
  jobs.arrive(0, session, 2, {1}, t0 + 30ms);
  jobs.arrive(1, session, 2, {1}, t0 + 30ms);
  for (int beat = 1; beat <= 4; ++beat) {
    const auto now = t0 + beat * kTimeout;
    members.heard(1, now);
    members.heard(2, now);
    jobs.message({"job-a", Kind::Keepalive, session, {}, {}}, now);
    const Actions ticked = jobs.tick(now + 1ms);
    EXPECT_TRUE(only<JobDesk::Drop>(ticked).empty()) << "beat " << beat;
    EXPECT_TRUE(only<JobDesk::Release>(ticked).empty()) << "beat " << beat;
  }
  const auto end = t0 + 5 * kTimeout;
  const Actions bye = jobs.message({"job-a", Kind::Bye, session, {1, 0}, {}}, end);
  EXPECT_EQ(given(bye, Command::LastFrame), (std::vector<int>{0, 1, 2}));
  EXPECT_TRUE(only<JobDesk::Release>(bye).empty());  // process 2 may still come to frame 2
  const auto letGo = only<JobDesk::Release>(jobs.answer(2, answer(Command::Done, 1, 100), end));
  ASSERT_EQ(letGo.size(), 2u);
  EXPECT_EQ(letGo[0].frameId, 2u);
  // They do not present it (told the last frame is 1): Done after frame 1.
  jobs.answer(0, answer(Command::Done, 1, 0), end);
  const auto job = records(jobs.answer(1, answer(Command::Done, 1, 0), end));
  ASSERT_EQ(job.size(), 1u);
  EXPECT_EQ(job[0]["frames_presented"], 1);
  EXPECT_EQ(job[0]["ended"], "last frame");
}

// A frame nobody in the window came to is no frame of the job's: with the window's process lost
// the others wait, and are let go when the job is dropped (they were told to abort first).
TEST_F(JobDeskTest, ProcessesOutOfAWindowWithNobodyInItAreLetGoWhenTheJobEnds) {
  Hello hello = helloFrom("render1");
  hello.window = parseWindowRequest("130,0,40,40");
  jobs.hello("job-a", hello, t0);
  allReady(t0);
  const std::uint64_t session = jobs.session();
  jobs.arrive(0, session, 1, {1}, t0);
  jobs.arrive(1, session, 1, {1}, t0);
  EXPECT_TRUE(only<JobDesk::Release>(lose(2, "gone", t0 + 10ms)).empty());
  EXPECT_TRUE(only<JobDesk::Release>(jobs.tick(t0 + 20ms)).empty());
  const Actions died = jobs.disconnected("job-a", t0 + 30ms);
  EXPECT_EQ(given(died, Command::Abort), (std::vector<int>{0, 1}));
  const auto letGo = only<JobDesk::Release>(died);
  ASSERT_EQ(letGo.size(), 2u);
  EXPECT_EQ(letGo[0].frameId, 1u);
}

// The window's only process lost, the others wait rather than present frames nobody shows; back
// in the job from a later frame, the frames before it go (the job may have rendered them and
// needs their credits to render that one), and the later ones wait for it again.
TEST_F(JobDeskTest, AWindowsProcessBackInTheJobLetsTheFramesBeforeItsFirstGo) {
  Hello hello = helloFrom("render1");
  hello.window = parseWindowRequest("130,0,40,40");
  jobs.hello("job-a", hello, t0);
  allReady(t0);
  const std::uint64_t session = jobs.session();
  for (int p = 0; p < 3; ++p) jobs.arrive(p, session, 1, {1}, t0);
  jobs.presented(session, 1, 0);
  jobs.arrive(0, session, 2, {1}, t0 + 10ms);
  jobs.arrive(1, session, 2, {1}, t0 + 10ms);
  EXPECT_TRUE(only<JobDesk::Release>(lose(2, "gone", t0 + 20ms)).empty());
  EXPECT_TRUE(only<JobDesk::Release>(jobs.tick(t0 + 30ms)).empty());
  members.admit("link2b", joinOf(2, 2), t0 + 40ms);
  EXPECT_EQ(given(jobs.joined(2, t0 + 40ms), Command::Start), std::vector<int>{2});
  const Actions back = jobs.answer(2, answer(Command::Ready, 1), t0 + 50ms);
  EXPECT_EQ(commandTo(back, 2, Command::FirstFrame).header.a, 4);  // credited 1, granted 2
  const auto frame2 = only<JobDesk::Release>(back);
  ASSERT_EQ(frame2.size(), 2u);
  EXPECT_EQ(frame2[0].frameId, 2u);
  jobs.arrive(0, session, 3, {1}, t0 + 60ms);
  EXPECT_EQ(only<JobDesk::Release>(jobs.arrive(1, session, 3, {1}, t0 + 60ms)).size(), 2u);
  jobs.arrive(0, session, 4, {1}, t0 + 70ms);
  EXPECT_TRUE(only<JobDesk::Release>(jobs.arrive(1, session, 4, {1}, t0 + 70ms)).empty());
  EXPECT_EQ(only<JobDesk::Release>(jobs.arrive(2, session, 4, {1}, t0 + 80ms)).size(), 3u);
}

TEST_F(JobDeskTest, AWindowTheWallDoesNotHaveIsRefusedAndTheNextJobRuns) {
  // An unknown display, a rectangle past the canvas (192x64), an empty one (from the wire).
  WindowRequest unknown, outside, empty;
  unknown.kind = WindowRequest::Kind::Display;
  unknown.display = "nope";
  outside.kind = empty.kind = WindowRequest::Kind::Rect;
  outside.rect = {150, 0, 214, 64};
  for (const WindowRequest& window : {unknown, outside, empty}) {
    SCOPED_TRACE(windowText(window));
    Hello hello = helloFrom("render1");
    hello.window = window;
    const Actions refused = jobs.hello("job-a", hello, t0);
    const auto reply = replies(refused, Kind::Refused);
    ASSERT_EQ(reply.size(), 1u);
    EXPECT_NE(textOf(reply[0]).find("window"), std::string::npos) << textOf(reply[0]);
    EXPECT_TRUE(given(refused, Command::Start).empty());
    EXPECT_EQ(jobs.state(), State::Idle);
  }
  run("job-b", "render2", t0);
}

TEST_F(JobDeskTest, AWrongTokenIsRefused) {
  Hello wrong = helloFrom("stranger");
  wrong.token = "guess";
  Actions a = jobs.hello("s1", wrong, t0);
  ASSERT_EQ(replies(a, Kind::Refused).size(), 1u);
  EXPECT_EQ(textOf(replies(a, Kind::Refused)[0]), "wrong token");
  const auto logged = only<JobDesk::Log>(a);
  ASSERT_EQ(logged.size(), 1u);
  EXPECT_EQ(logged[0].line, "refused a job from stranger: wrong token");
  EXPECT_EQ(logged[0].oncePer, "s1");  // a stranger's retries do not flood the log
  wrong.token.clear();
  a = jobs.hello("s2", wrong, t0);
  EXPECT_EQ(textOf(replies(a, Kind::Refused)[0]), "this wall needs a token (--token)");
  EXPECT_TRUE(given(a, Command::Start).empty());
  EXPECT_EQ(jobs.state(), State::Idle);
}

TEST_F(JobDeskTest, ASecondJobIsRefusedBusyOrQueuedWithWait) {
  run("job-a", "render1", t0);
  const Actions busy = jobs.hello("job-b", helloFrom("render2"), t0);
  ASSERT_EQ(replies(busy, Kind::Refused).size(), 1u);
  EXPECT_EQ(textOf(replies(busy, Kind::Refused)[0]), "busy: a job from render1 is connected");
  EXPECT_TRUE(only<JobDesk::ToProcess>(busy).empty());

  const Actions queued = jobs.hello("job-c", helloFrom("render3", true), t0);
  ASSERT_EQ(replies(queued, Kind::Queued).size(), 1u);
  EXPECT_EQ(textOf(replies(queued, Kind::Queued)[0]),
            "busy: a job from render1 is connected; waiting (place 1)");
  EXPECT_EQ(jobs.queued(), 1u);
  // Its keepalive is answered with its place.
  JobDesk::JobMessage keepalive{"job-c", Kind::Keepalive, 0, {}, {}};
  const auto place = replies(jobs.message(keepalive, t0 + 100ms), Kind::Queued);
  ASSERT_EQ(place.size(), 1u);
  EXPECT_EQ(place[0].peer, "job-c");
}

TEST_F(JobDeskTest, QueuedJobsStartInOrderAndTheQueueIsBounded) {
  run("job-0", "render0", t0);
  for (std::size_t i = 1; i <= JobDesk::kMaxQueued; ++i)
    EXPECT_EQ(
        replies(jobs.hello("job-" + std::to_string(i), helloFrom("r"), t0), Kind::Refused).size(),
        1u);  // without wait: busy
  for (std::size_t i = 1; i <= JobDesk::kMaxQueued; ++i)
    jobs.hello("job-" + std::to_string(i), helloFrom("render" + std::to_string(i), true), t0);
  EXPECT_EQ(jobs.queued(), JobDesk::kMaxQueued);
  const auto full = replies(jobs.hello("job-x", helloFrom("rx", true), t0), Kind::Refused);
  ASSERT_EQ(full.size(), 1u);
  EXPECT_EQ(textOf(full[0]), "busy: a job from render0 is connected, and 16 jobs wait already");

  // Each job ends with its goodbye: the next in the queue starts, in order.
  for (int i = 1; i <= 3; ++i) {
    JobDesk::JobMessage bye{"job-" + std::to_string(i - 1), Kind::Bye, jobs.session(), {5, 0}, {}};
    EXPECT_EQ(commandTo(jobs.message(bye, t0 + 10ms), 2, Command::LastFrame).header.a, 5);
    const Actions over = allDone(5, t0 + 20ms);
    const auto job = records(over);
    ASSERT_EQ(job.size(), 1u);
    EXPECT_EQ(job[0]["host"], "render" + std::to_string(i - 1));
    EXPECT_EQ(job[0]["frames_presented"], 5);
    EXPECT_EQ(job[0]["ended"], "last frame");
    EXPECT_EQ(given(over, Command::Start), (std::vector<int>{0, 1, 2}));
    EXPECT_EQ(jobs.state(), State::Starting);
    const auto directory = replies(allReady(t0 + 30ms), Kind::Directory);
    ASSERT_EQ(directory.size(), 1u);
    EXPECT_EQ(directory[0].peer, "job-" + std::to_string(i));
  }
  EXPECT_EQ(jobs.queued(), JobDesk::kMaxQueued - 3);
}

TEST_F(JobDeskTest, AJobThatGoesSilentEndsAndTheNextStarts) {
  run("job-a", "render1", t0);
  jobs.hello("job-c", helloFrom("render3", true), t0);
  jobs.hello("job-b", helloFrom("render2", true), t0);
  // job-b keeps waiting; job-c, first in the queue, goes silent there.
  jobs.message({"job-b", Kind::Keepalive, 0, {}, {}}, t0 + 500ms);
  EXPECT_TRUE(only<JobDesk::ToProcess>(jobs.tick(t0 + kTimeout)).empty());  // not yet
  const Actions silent = jobs.tick(t0 + kTimeout + 1ms);
  EXPECT_EQ(given(silent, Command::Abort), (std::vector<int>{0, 1, 2}));
  const auto ended = replies(silent, Kind::Ended);
  ASSERT_EQ(ended.size(), 1u);
  EXPECT_EQ(ended[0].peer, "job-a");
  EXPECT_EQ(textOf(ended[0]), "no word from the job for 600 ms");
  EXPECT_EQ(jobs.state(), State::Ending);

  // The processes give the frame up and say Done: the job's record, then job-b (job-c left the
  // queue: silent for longer than the timeout).
  const Actions next = allDone(3, t0 + 700ms);
  const auto job = records(next);
  ASSERT_EQ(job.size(), 1u);
  EXPECT_EQ(job[0]["ended"], "no word from the job for 600 ms");
  EXPECT_DOUBLE_EQ(job[0]["seconds"].get<double>(), 0.7);
  EXPECT_EQ(given(next, Command::Start), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(replies(allReady(t0 + 710ms), Kind::Directory).at(0).peer, "job-b");
  EXPECT_EQ(jobs.queued(), 0u);
}

TEST_F(JobDeskTest, AJobWhoseConnectionClosesEndsAtOnceAndAQueuedOneLeavesTheQueue) {
  run("job-a", "render1", t0);
  jobs.hello("job-c", helloFrom("render3", true), t0);
  jobs.hello("job-b", helloFrom("render2", true), t0);
  // A connection that never had a job: nothing happens.
  EXPECT_TRUE(jobs.disconnected("stranger", t0 + 10ms).empty());
  // job-c dies while queued: it leaves the queue, the running job goes on.
  const Actions left = jobs.disconnected("job-c", t0 + 20ms);
  EXPECT_EQ(jobs.queued(), 1u);
  EXPECT_TRUE(only<JobDesk::ToProcess>(left).empty());
  ASSERT_EQ(only<JobDesk::Log>(left).size(), 1u);
  EXPECT_EQ(only<JobDesk::Log>(left)[0].line,
            "a queued job from render3 left the queue: its connection closed");
  EXPECT_EQ(jobs.state(), State::Running);

  // job-a's connection closes long before its silence would end it: it ends now, as if silent.
  const Actions gone = jobs.disconnected("job-a", t0 + 100ms);
  EXPECT_EQ(given(gone, Command::Abort), (std::vector<int>{0, 1, 2}));  // they give it up
  EXPECT_EQ(commandTo(gone, 1, Command::Abort).text, "its connection closed");
  const auto ended = replies(gone, Kind::Ended);
  ASSERT_EQ(ended.size(), 1u);
  EXPECT_EQ(ended[0].peer, "job-a");
  const auto logged = only<JobDesk::Log>(gone);
  ASSERT_EQ(logged.size(), 1u);
  EXPECT_EQ(logged[0].line, "dropping the job from render1: its connection closed");
  EXPECT_EQ(jobs.state(), State::Ending);

  // Once the processes gave the frame up: the job's record, then job-b.
  const Actions next = allDone(3, t0 + 200ms);
  const auto job = records(next);
  ASSERT_EQ(job.size(), 1u);
  EXPECT_EQ(job[0]["ended"], "its connection closed");
  EXPECT_EQ(given(next, Command::Start), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(replies(allReady(t0 + 210ms), Kind::Directory).at(0).peer, "job-b");
  EXPECT_EQ(jobs.queued(), 0u);
}

TEST_F(JobDeskTest, AJobThatClosesOnceItsLastFrameIsCreditedEndsAsUsual) {
  run("job-a", "render1", t0);
  const std::uint64_t session = jobs.session();
  jobs.message({"job-a", Kind::Bye, session, {3, 0}, {}}, t0 + 10ms);
  jobs.presented(session, 2, 0);
  jobs.presented(session, 3, 0);
  // Its rank 0 leaves once it saw that credit: the processes' Done end the job.
  const Actions closed = jobs.disconnected("job-a", t0 + 20ms);
  EXPECT_TRUE(given(closed, Command::Abort).empty());
  EXPECT_TRUE(replies(closed, Kind::Ended).empty());
  EXPECT_EQ(jobs.state(), State::Running);
  const auto job = records(allDone(3, t0 + 30ms));
  ASSERT_EQ(job.size(), 1u);
  EXPECT_EQ(job[0]["ended"], "last frame");

  // The next job names its last frame, 3, and its connection closes after frame 2: it died.
  run("job-b", "render2", t0 + 40ms);
  jobs.message({"job-b", Kind::Bye, jobs.session(), {3, 0}, {}}, t0 + 50ms);
  jobs.presented(jobs.session(), 2, 0);
  const Actions died = jobs.disconnected("job-b", t0 + 60ms);
  EXPECT_EQ(given(died, Command::Abort), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(textOf(replies(died, Kind::Ended).at(0)), "its connection closed");
}

TEST_F(JobDeskTest, AJobWhoseConnectionClosesWhileItStartsIsCancelled) {
  jobs.hello("job-a", helloFrom("render1"), t0);
  ASSERT_EQ(jobs.state(), State::Starting);
  const Actions gone = jobs.disconnected("job-a", t0 + 10ms);
  EXPECT_EQ(given(gone, Command::Cancel), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(jobs.state(), State::Ending);
  // The processes say Done: the wall is free for the next job.
  allDone(0, t0 + 20ms);
  EXPECT_EQ(jobs.state(), State::Idle);
  EXPECT_EQ(given(jobs.hello("job-b", helloFrom("render2"), t0 + 30ms), Command::Start),
            (std::vector<int>{0, 1, 2}));
}

TEST_F(JobDeskTest, AProcessThatMissesBeatsIsDroppedAndTheJobGetsANewRoster) {
  run("job-a", "render1", t0);
  jobs.presented(jobs.session(), 1, 0);
  // Frame 2's barrier: the head and process 1 arrive, process 2 never does.
  EXPECT_TRUE(only<JobDesk::Release>(jobs.arrive(0, jobs.session(), 2, {1, 0}, t0)).empty());
  EXPECT_TRUE(only<JobDesk::Release>(jobs.arrive(1, jobs.session(), 2, {7, 0}, t0)).empty());
  members.heard(1, t0 + 500ms);
  const auto silent = members.silent(t0 + kTimeout + 1ms);
  ASSERT_EQ(silent.size(), 1u);
  ASSERT_EQ(silent[0].process, 2);
  const Actions lost = lose(2, silent[0].why, t0 + kTimeout + 1ms);

  const auto roster = replies(lost, Kind::Roster);
  ASSERT_EQ(roster.size(), 1u);
  EXPECT_EQ(roster[0].peer, "job-a");
  const Roster r = parseRoster(roster[0].message.data(), roster[0].message.size());
  EXPECT_EQ(r.version, 1u);
  EXPECT_EQ(r.fromFrame, 0u);  // at once
  EXPECT_TRUE(r.processes[0].live);
  EXPECT_TRUE(r.processes[1].live);
  EXPECT_FALSE(r.processes[2].live);
  EXPECT_EQ(r.why, "lost wall process 2 on host2 after frame 1: no word from it for 600 ms");
  // The barrier it held up goes on without it.
  const auto released = only<JobDesk::Release>(lost);
  ASSERT_EQ(released.size(), 2u);
  EXPECT_EQ(released[0].process, 0);
  EXPECT_EQ(released[1].process, 1);
  EXPECT_EQ(released[0].values, (std::vector<std::int64_t>{7, 0}));
  // --stats, as the end-to-end tests grep it.
  const auto record = only<JobDesk::Record>(lost);
  ASSERT_EQ(record.size(), 1u);
  EXPECT_EQ(record[0].json, R"({"event":"lost","process":2,"host":"host2","frame":1,)"
                            R"("why":"no word from it for 600 ms"})");
  // The job ends with the processes left, and counts the loss.
  jobs.message({"job-a", Kind::Bye, jobs.session(), {2, 0}, {}}, t0 + 700ms);
  jobs.answer(0, answer(Command::Done, 2), t0 + 700ms);
  const auto job = records(jobs.answer(1, answer(Command::Done, 2), t0 + 700ms));
  ASSERT_EQ(job.size(), 1u);
  EXPECT_EQ(job[0]["processes_lost"], 1);
  EXPECT_EQ(jobs.state(), State::Idle);
}

TEST_F(JobDeskTest, AProcessThatRejoinsDuringAJobIsAdmittedFromTheRightFirstFrame) {
  run("job-a", "render1", t0);
  jobs.presented(jobs.session(), 1, 0);
  const auto credit = replies(jobs.presented(jobs.session(), 2, 0), Kind::Presented);
  ASSERT_EQ(credit.size(), 1u);
  EXPECT_EQ(parseControl(credit[0].message.data(), credit[0].message.size()).value, 2u);
  lose(2, "killed", t0 + 1s);

  // It starts again: a new incarnation on a new piece socket. Start with no first frame, and
  // nothing for the job until it is Ready (its node takes pieces).
  members.admit("link2-again", joinOf(2, 2), t0 + 2s);
  const Actions admitted = jobs.joined(2, t0 + 2s);
  EXPECT_EQ(given(admitted, Command::Start), std::vector<int>{2});
  EXPECT_EQ(commandTo(admitted, 2, Command::Start).header.a, 0);
  EXPECT_TRUE(replies(admitted, Kind::Roster).empty());

  // Ready: its first frame is the last credited (2) + frames in flight (2) + 1.
  const Actions ready = jobs.answer(2, answer(Command::Ready, 1), t0 + 2s);
  EXPECT_EQ(commandTo(ready, 2, Command::FirstFrame).header.a, 5);
  const auto roster = replies(ready, Kind::Roster);
  ASSERT_EQ(roster.size(), 1u);
  const Roster r = parseRoster(roster[0].message.data(), roster[0].message.size());
  EXPECT_EQ(r.version, 2u);
  EXPECT_EQ(r.fromFrame, 5u);
  EXPECT_TRUE(r.processes[2].live);
  EXPECT_EQ(r.processes[2].endpoint, "tcp://host2:2");
  EXPECT_EQ(only<JobDesk::Record>(ready).at(0).json,
            R"({"event":"rejoined","process":2,"host":"host2","frame":5})");

  // Frame 4 is not its: the head and process 1 agree alone. Frame 5 waits for it.
  const std::uint64_t session = jobs.session();
  jobs.arrive(0, session, 4, {1}, t0 + 2s);
  EXPECT_EQ(only<JobDesk::Release>(jobs.arrive(1, session, 4, {1}, t0 + 2s)).size(), 2u);
  jobs.arrive(0, session, 5, {1}, t0 + 2s);
  EXPECT_TRUE(only<JobDesk::Release>(jobs.arrive(1, session, 5, {1}, t0 + 2s)).empty());
  EXPECT_EQ(only<JobDesk::Release>(jobs.arrive(2, session, 5, {9}, t0 + 2s)).size(), 3u);
  EXPECT_EQ(records(allDone(5, t0 + 3s)).at(0)["processes_rejoined"], 1);
}

TEST_F(JobDeskTest, AProcessThatJoinsWhileAJobStartsIsAdmittedOnceItRuns) {
  lose(2, "killed", t0);
  EXPECT_EQ(given(jobs.hello("job-a", helloFrom("render1"), t0), Command::Start),
            (std::vector<int>{0, 1}));
  members.admit("link2-again", joinOf(2, 2), t0);
  EXPECT_TRUE(only<JobDesk::ToProcess>(jobs.joined(2, t0)).empty());
  jobs.answer(0, answer(Command::Ready, 1), t0);
  const Actions running = jobs.answer(1, answer(Command::Ready, 1), t0);
  const auto directory = replies(running, Kind::Directory).at(0);
  EXPECT_FALSE(
      parseDirectory(directory.message.data(), directory.message.size()).processes[2].live);
  EXPECT_EQ(given(running, Command::Start), std::vector<int>{2});
  EXPECT_EQ(
      commandTo(jobs.answer(2, answer(Command::Ready, 1), t0), 2, Command::FirstFrame).header.a,
      3);  // nothing credited yet: 0 + 2 + 1
}

TEST_F(JobDeskTest, AProcessThatCannotStartAJobRefusesIt) {
  jobs.hello("job-a", helloFrom("render1"), t0);
  jobs.answer(0, answer(Command::Ready, 1), t0);
  jobs.answer(1, answer(Command::Ready, 0, 0, "no such capture folder"), t0);
  const Actions refused = jobs.answer(2, answer(Command::Ready, 1), t0);
  EXPECT_EQ(given(refused, Command::Cancel), (std::vector<int>{0, 2}));
  EXPECT_EQ(textOf(replies(refused, Kind::Refused).at(0)), "no such capture folder");
  EXPECT_EQ(jobs.state(), State::Ending);
  jobs.answer(0, answer(Command::Done), t0);
  const auto job = records(jobs.answer(2, answer(Command::Done), t0));
  EXPECT_EQ(job.at(0)["ended"], "no such capture folder");
  EXPECT_EQ(jobs.state(), State::Idle);
}

// The head cannot write the capture of the job's last frame (its quota spent) after a member was
// done with that frame: the job, which waits for the frame's credit, is told why.
TEST_F(JobDeskTest, AFailureAfterAnotherProcessWasDoneStillReachesTheJob) {
  run("job-a", "render1", t0);
  jobs.answer(1, answer(Command::Done, 2, 100), t0);
  EXPECT_EQ(jobs.state(), State::Ending);
  const Actions failed = jobs.answer(0, answer(Command::Failed, 0, 0, "capture quota"), t0);
  const auto ended = replies(failed, Kind::Ended);
  ASSERT_EQ(ended.size(), 1u);
  EXPECT_EQ(ended[0].peer, "job-a");
  EXPECT_EQ(textOf(ended[0]), "capture quota");
  jobs.answer(0, answer(Command::Done, 1, 100, "capture quota"), t0);
  const auto job = records(jobs.answer(2, answer(Command::Done, 2, 100), t0));
  EXPECT_EQ(job.at(0)["ended"], "capture quota");
  EXPECT_EQ(jobs.state(), State::Idle);
}

TEST_F(JobDeskTest, ABarrierWithAnotherValueCountDropsTheProcess) {
  run("job-a", "render1", t0);
  jobs.arrive(0, jobs.session(), 1, {1, 2}, t0);
  const auto drop = only<JobDesk::Drop>(jobs.arrive(1, jobs.session(), 1, {1}, t0));
  ASSERT_EQ(drop.size(), 1u);
  EXPECT_EQ(drop[0].process, 1);
  EXPECT_EQ(drop[0].why, "its swap barrier of frame 1 has 1 values, not the others' count");
  // A barrier of another session (an earlier job's node) is not counted.
  EXPECT_TRUE(jobs.arrive(2, 999, 1, {1, 2}, t0).empty());
}

TEST_F(JobDeskTest, AStopRefusesTheQueueEndsTheJobAndClosesOnceEveryProcessConfirms) {
  run("job-a", "render1", t0);
  jobs.hello("job-b", helloFrom("render2", true), t0);
  const Actions stop = jobs.answer(1, answer(Command::StopAsked), t0);
  EXPECT_EQ(textOf(replies(stop, Kind::Refused).at(0)), "the wall is shutting down");
  EXPECT_EQ(replies(stop, Kind::Refused).at(0).peer, "job-b");
  EXPECT_EQ(textOf(replies(stop, Kind::Ended).at(0)), "the wall is shutting down");
  EXPECT_EQ(textOf(replies(jobs.hello("job-c", helloFrom("r"), t0), Kind::Refused).at(0)),
            "the wall is shutting down");
  allDone(4, t0);
  const Actions closing = jobs.tick(t0 + 100ms);
  EXPECT_EQ(given(closing, Command::Shutdown), (std::vector<int>{1, 2}));
  EXPECT_EQ(only<JobDesk::Closing>(closing).size(), 1u);
  EXPECT_EQ(jobs.state(), State::Closed);
  jobs.answer(1, answer(Command::Shutdown), t0 + 150ms);
  EXPECT_TRUE(jobs.tick(t0 + 200ms).empty());  // process 2 has not confirmed
  jobs.answer(2, answer(Command::Shutdown), t0 + 250ms);
  const Actions closed = jobs.tick(t0 + 300ms);
  EXPECT_EQ(given(closed, Command::Shutdown), std::vector<int>{0});  // the head's own last
  EXPECT_EQ(only<JobDesk::Closed>(closed).size(), 1u);
}

TEST_F(JobDeskTest, JobRecordsAreJsonWhateverTheHostSends) {
  Hello h = helloFrom("bad\xff\"host\n");
  run("job-a", "", t0);
  jobs.message({"job-a", Kind::Bye, jobs.session(), {0, 0}, {}}, t0);
  const auto line = only<JobDesk::Record>(allDone(0, t0 + 1500ms)).at(0).json;
  EXPECT_EQ(line.rfind(R"({"job":)", 0), 0u) << line;  // keys in the documented order
  const auto job = nlohmann::json::parse(line);
  EXPECT_EQ(job["seconds"], 1.5);
  EXPECT_EQ(job["render_ranks"], 4);

  jobs.hello("job-b", h, t0);
  allReady(t0);
  const Actions ended = jobs.failed("job-b", "a bad \xfe batch", t0);
  EXPECT_EQ(given(ended, Command::Abort), (std::vector<int>{0, 1, 2}));
  const auto bad = records(allDone(0, t0));  // parses: the bytes that are not UTF-8 replaced
  ASSERT_EQ(bad.size(), 1u);
  EXPECT_EQ(bad[0]["host"], "bad\xEF\xBF\xBD\"host\n");
}

TEST_F(JobDeskTest, AProcessThatBeatsButNeverComesToABarrierIsDroppedAtTheTimeout) {
  run("job-a", "render1", t0);
  const std::uint64_t session = jobs.session();
  jobs.presented(session, 1, 0);
  jobs.arrive(0, session, 2, {1}, t0 + 10ms);
  jobs.arrive(1, session, 2, {1}, t0 + 20ms);
  // Process 2 beats all along: not silent, yet never arrives. The job is alive.
  members.heard(2, t0 + kTimeout);
  jobs.message({"job-a", Kind::Keepalive, session, {}, {}}, t0 + 500ms);
  EXPECT_TRUE(only<JobDesk::Drop>(jobs.tick(t0 + 10ms + kTimeout)).empty());
  const auto drop = only<JobDesk::Drop>(jobs.tick(t0 + 11ms + kTimeout));
  ASSERT_EQ(drop.size(), 1u);
  EXPECT_EQ(drop[0].process, 2);
  EXPECT_EQ(drop[0].why,
            "it did not come to the swap barrier of frame 2 within 600 ms of the others");
  // The desk drops it: the others' frame goes on.
  EXPECT_EQ(only<JobDesk::Release>(lose(2, drop[0].why, t0 + 11ms + kTimeout)).size(), 2u);
}

TEST_F(JobDeskTest, ABarrierHeldUpByAJobThatDiedIsTheJobsTimeoutsToEnd) {
  run("job-a", "render1", t0);
  const std::uint64_t session = jobs.session();
  jobs.message({"job-a", Kind::Keepalive, session, {}, {}}, t0 + 100ms);
  jobs.arrive(0, session, 1, {1}, t0 + 50ms);  // the job died before process 2 had its pieces
  jobs.arrive(1, session, 1, {1}, t0 + 50ms);
  members.heard(2, t0 + kTimeout);
  EXPECT_TRUE(only<JobDesk::Drop>(jobs.tick(t0 + 51ms + kTimeout)).empty());
  const Actions silent = jobs.tick(t0 + 101ms + kTimeout);
  EXPECT_TRUE(only<JobDesk::Drop>(silent).empty());
  EXPECT_EQ(given(silent, Command::Abort), (std::vector<int>{0, 1, 2}));  // they give it up
}

TEST_F(JobDeskTest, TheHeadsOwnProcessIsNeverDroppedAtABarrier) {
  run("job-a", "render1", t0);
  jobs.arrive(1, jobs.session(), 1, {1}, t0);
  jobs.arrive(2, jobs.session(), 1, {1}, t0);
  EXPECT_TRUE(only<JobDesk::Drop>(jobs.tick(t0 + 10 * kTimeout)).empty());
}

TEST_F(JobDeskTest, ABarrierOutsideTheFramesInFlightDropsItsProcess) {
  run("job-a", "render1", t0);
  const std::uint64_t session = jobs.session();
  for (std::uint32_t f = 1; f <= 3; ++f) jobs.presented(session, f, 0);
  // Granted 2 frames in flight: frames 4..7 (framesAheadFor) may be on their way.
  EXPECT_TRUE(only<JobDesk::Drop>(jobs.arrive(1, session, 7, {1}, t0)).empty());
  auto drop = only<JobDesk::Drop>(jobs.arrive(2, session, 1000000, {1}, t0));
  ASSERT_EQ(drop.size(), 1u);
  EXPECT_EQ(drop[0].why,
            "its swap barrier of frame 1000000 is outside the frames in flight (4..7)");
  drop = only<JobDesk::Drop>(jobs.arrive(2, session, 3, {1}, t0));  // presented already
  ASSERT_EQ(drop.size(), 1u);
  EXPECT_EQ(drop[0].process, 2);
}

TEST_F(JobDeskTest, CaptureRequestsAreBoundedInNumberAndFrameRange) {
  run("job-a", "render1", t0);
  const std::uint64_t session = jobs.session();
  const auto capture = [&](std::uint64_t frame, std::int64_t sequence) {
    return jobs.message({"job-a", Kind::Capture, session, {frame, sequence}, {}}, t0);
  };
  for (int i = 1; i <= static_cast<int>(JobDesk::kMaxPendingCaptures); ++i)
    EXPECT_EQ(given(capture(2, i), Command::Capture), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(jobs.pendingCaptures(), JobDesk::kMaxPendingCaptures);
  Actions over = capture(2, 9);
  EXPECT_TRUE(given(over, Command::Capture).empty());
  auto refused = replies(over, Kind::Refused);
  ASSERT_EQ(refused.size(), 1u);
  EXPECT_EQ(refused[0].peer, "job-a");
  EXPECT_EQ(parseHeader(refused[0].message.data(), refused[0].message.size()).session, session);
  EXPECT_EQ(textOf(refused[0]),
            "capture request refused: 8 captures wait for their frames already");
  EXPECT_EQ(jobs.state(), State::Running);  // the job goes on

  // Frame 2 presented: its captures are taken; far frames and bad sequences are refused.
  jobs.presented(session, 2, 0);
  EXPECT_EQ(jobs.pendingCaptures(), 0u);
  EXPECT_EQ(textOf(replies(capture(1000000, 10), Kind::Refused).at(0)),
            "capture request refused: frame 1000000 is not near the frames in flight (1..6)");
  EXPECT_EQ(textOf(replies(capture(0, 10), Kind::Refused).at(0)),
            "capture request refused: frame 0 is not near the frames in flight (1..6)");
  EXPECT_EQ(textOf(replies(capture(3, 0), Kind::Refused).at(0)),
            "capture request refused: sequence 0 (expected 1 or more)");
  EXPECT_EQ(given(capture(1, 10), Command::Capture).size(), 3u);  // behind: taken at frame 3
  EXPECT_EQ(jobs.pendingCaptures(), 1u);
  jobs.presented(session, 3, 0);
  EXPECT_EQ(jobs.pendingCaptures(), 0u);
}

TEST_F(JobDeskTest, ASecondHelloOnTheSameConnectionIsRefused) {
  run("job-a", "render1", t0);
  const auto again = replies(jobs.hello("job-a", helloFrom("render1", true), t0), Kind::Refused);
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(textOf(again[0]), "this connection has a job at the wall already");
  jobs.hello("job-b", helloFrom("render2", true), t0);
  EXPECT_EQ(replies(jobs.hello("job-b", helloFrom("render2", true), t0), Kind::Refused).size(), 1u);
  EXPECT_EQ(jobs.queued(), 1u);
  // A queued connection that sends garbage leaves the queue.
  jobs.failed("job-b", "malformed", t0);
  EXPECT_EQ(jobs.queued(), 0u);
  EXPECT_EQ(jobs.state(), State::Running);
}

TEST_F(JobDeskTest, NamesAPeerGaveAreLoggedPrintableAndShort) {
  Hello h = helloFrom("evil\nlost wall process 1" + std::string(200, 'x'));
  h.token = "wrong";
  const auto logged = only<JobDesk::Log>(jobs.hello("s1", h, t0));
  ASSERT_EQ(logged.size(), 1u);
  EXPECT_EQ(logged[0].line, "refused a job from evil\\nlost wall process 1" + std::string(56, 'x') +
                                "... (224 bytes): wrong token");
}

// ---- several jobs on one wall (Setup::maxJobs; issue 37) ----

// The same wall with room for two jobs at once, each in its window.
class TwoJobsTest : public JobDeskTest {
 protected:
  TwoJobsTest() : two({&layout, "t", kTimeout, 2, [this] { return ++lastSession; }, 2}, members) {}

  static Hello inWindow(const std::string& host, const std::string& window, bool wait = false) {
    Hello h = helloFrom(host, wait);
    h.window = parseWindowRequest(window);
    return h;
  }
  ServiceCommand answerOf(std::uint64_t session, Command kind, std::int64_t a = 0,
                          std::int64_t b = 0, std::string text = {}) const {
    ServiceCommand c = answer(kind, a, b, std::move(text));
    c.header.session = session;
    return c;
  }
  // A job from `host` on `peer` in `window`, started and running: its session.
  std::uint64_t runIn(const std::string& peer, const std::string& host, const std::string& window,
                      Clock::time_point now) {
    const Actions started = two.hello(peer, inWindow(host, window), now);
    const auto starts = only<JobDesk::ToProcess>(started);
    EXPECT_EQ(given(started, Command::Start), (std::vector<int>{0, 1, 2}));
    if (starts.empty()) return 0;
    const std::uint64_t session = starts[0].command.header.session;
    Actions last;
    for (int p = 0; p < 3; ++p) last = two.answer(p, answerOf(session, Command::Ready, 1), now);
    const auto directory = replies(last, Kind::Directory);
    EXPECT_EQ(directory.size(), 1u);
    if (!directory.empty()) {
      EXPECT_EQ(directory[0].peer, peer);
    }
    EXPECT_EQ(two.state(session), State::Running);
    return session;
  }
  // Every process arrives at frame F of `session`: the releases of the last arrival.
  std::vector<JobDesk::Release> frame(std::uint64_t session, std::uint32_t f,
                                      Clock::time_point now) {
    Actions last;
    for (int p = 0; p < 3; ++p) last = two.arrive(p, session, f, {1}, now);
    return only<JobDesk::Release>(last);
  }

  JobDesk two;
};

TEST_F(TwoJobsTest, TwoJobsRunAtOnceEachWithItsOwnBarriersAndCredits) {
  const std::uint64_t a = runIn("job-a", "render1", "0,0,100,64", t0);
  const std::uint64_t b = runIn("job-b", "render2", "50,0,100,64", t0);
  EXPECT_NE(a, b);
  EXPECT_EQ(two.sessions(), (std::vector<std::uint64_t>{a, b}));
  // Interleaved: a barrier of one job is not completed by the other's arrivals.
  two.arrive(0, a, 1, {1}, t0);
  two.arrive(1, b, 1, {2}, t0);
  two.arrive(1, a, 1, {3}, t0);
  two.arrive(0, b, 1, {4}, t0);
  const auto releaseA = only<JobDesk::Release>(two.arrive(2, a, 1, {5}, t0));
  ASSERT_EQ(releaseA.size(), 3u);
  for (const JobDesk::Release& r : releaseA) {
    EXPECT_EQ(r.session, a);
    EXPECT_EQ(r.values, (std::vector<std::int64_t>{5}));
  }
  const auto releaseB = only<JobDesk::Release>(two.arrive(2, b, 1, {1}, t0));
  ASSERT_EQ(releaseB.size(), 3u);
  EXPECT_EQ(releaseB[0].session, b);
  EXPECT_EQ(releaseB[0].values, (std::vector<std::int64_t>{4}));
  // Each job's credit goes to its own connection and counts for it alone.
  const auto creditA = replies(two.presented(a, 1, 0), Kind::Presented);
  ASSERT_EQ(creditA.size(), 1u);
  EXPECT_EQ(creditA[0].peer, "job-a");
  EXPECT_EQ(two.lastCredited(a), 1u);
  EXPECT_EQ(two.lastCredited(b), 0u);
  EXPECT_EQ(replies(two.presented(b, 1, 0), Kind::Presented).at(0).peer, "job-b");
  // A job's capture, keepalive and goodbye go to the processes with its own session.
  const Actions kept = two.message({"job-b", Kind::Keepalive, b, {}, {}}, t0 + 10ms);
  for (const JobDesk::ToProcess& c : only<JobDesk::ToProcess>(kept))
    EXPECT_EQ(c.command.header.session, b);
  EXPECT_EQ(replies(kept, Kind::Keepalive).at(0).peer, "job-b");
  // A message naming the other job's session on this connection is not theirs.
  EXPECT_TRUE(
      only<JobDesk::ToProcess>(two.message({"job-b", Kind::Keepalive, a, {}, {}}, t0)).empty());
  // Job a ends with its goodbye; b runs on.
  two.message({"job-a", Kind::Bye, a, {1, 0}, {}}, t0 + 20ms);
  Actions over;
  for (int p = 0; p < 3; ++p) over = two.answer(p, answerOf(a, Command::Done, 1, 10), t0 + 30ms);
  EXPECT_EQ(records(over).at(0)["host"], "render1");
  EXPECT_EQ(two.sessions(), (std::vector<std::uint64_t>{b}));
  EXPECT_EQ(two.state(b), State::Running);
  EXPECT_EQ(frame(b, 2, t0 + 40ms).size(), 3u);
}

// Keys and the mouse over a window on the wall: a wall process tells the head where on the canvas
// (Command::Input); the head tells the job under it in its window's pixels, and drops what a
// process could not have seen (another process's display, outside the window), what does not
// parse, names another session or a gone job, and what comes faster than the job's rate.
ServiceCommand inputFrom(int process, std::uint64_t session, WindowInput in,
                         std::uint64_t sessionInMessage = 0) {
  const messaging::Bytes packed = packInput(sessionInMessage ? sessionInMessage : session, in);
  ServiceCommand c;
  c.header.kind = Command::Input;
  c.header.session = session;
  c.header.process = process;
  c.text.assign(reinterpret_cast<const char*>(packed.data()), packed.size());
  return c;
}
WindowInput keyAt(int x, int y, std::uint32_t key = WindowInput::kRight) {
  WindowInput in;
  in.key = key;
  in.x = x;
  in.y = y;
  return in;
}

TEST_F(TwoJobsTest, InputGoesToTheJobUnderItInItsWindowsPixelsAndTheHeadDropsTheRest) {
  const std::uint64_t a = runIn("job-a", "render1", "0,0,100,64", t0);
  const std::uint64_t b = runIn("job-b", "render2", "50,0,100,64", t0);
  // Process 1 drives display 1 (64..128): a key at (70, 10) over b, told to b at (20, 10).
  auto told = replies(two.answer(1, inputFrom(1, b, keyAt(70, 10)), t0), Kind::Input);
  ASSERT_EQ(told.size(), 1u);
  EXPECT_EQ(told[0].peer, "job-b");
  WindowInput in = parseInput(told[0].message.data(), told[0].message.size());
  EXPECT_EQ(parseHeader(told[0].message.data(), told[0].message.size()).session, b);
  EXPECT_EQ(in.kind, WindowInput::kKey);
  EXPECT_EQ(in.key, WindowInput::kRight);
  EXPECT_EQ(in.x, 20);
  EXPECT_EQ(in.y, 10);
  // A drag on display 0 over a (where b does not reach): a, with its move and flag.
  WindowInput drag;
  drag.kind = WindowInput::kDrag;
  drag.x = 30;
  drag.y = 40;
  drag.dx = -25;
  drag.dy = 7;
  drag.pan = true;
  told = replies(two.answer(0, inputFrom(0, a, drag), t0), Kind::Input);
  ASSERT_EQ(told.size(), 1u);
  EXPECT_EQ(told[0].peer, "job-a");
  in = parseInput(told[0].message.data(), told[0].message.size());
  EXPECT_EQ(in.kind, WindowInput::kDrag);
  EXPECT_EQ(in.x, 30);
  EXPECT_EQ(in.dx, -25);
  EXPECT_EQ(in.dy, 7);
  EXPECT_TRUE(in.pan);

  const auto dropped = [&](int p, const ServiceCommand& c) {
    return replies(two.answer(p, c, t0), Kind::Input).empty();
  };
  // Not on the sending process's display; outside the window named.
  EXPECT_TRUE(dropped(0, inputFrom(0, b, keyAt(70, 10))));
  EXPECT_TRUE(dropped(2, inputFrom(2, a, keyAt(130, 10))));
  EXPECT_TRUE(dropped(0, inputFrom(0, b, keyAt(-1, 10))));
  // Malformed: a key the job does not know, a kind, a move too large, another session inside,
  // bytes that are not an input event, a job that is not on the wall.
  EXPECT_TRUE(dropped(1, inputFrom(1, b, keyAt(70, 10, WindowInput::kKeyCount))));
  WindowInput odd = keyAt(70, 10);
  odd.kind = 7;
  EXPECT_TRUE(dropped(1, inputFrom(1, b, odd)));
  WindowInput far = drag;
  far.x = 70;
  far.dx = kMaxInputMove + 1;
  EXPECT_TRUE(dropped(1, inputFrom(1, b, far)));
  EXPECT_TRUE(dropped(1, inputFrom(1, b, keyAt(70, 10), a)));
  ServiceCommand garbage = inputFrom(1, b, keyAt(70, 10));
  garbage.text = "not an input event";
  const Actions logged = two.answer(1, garbage, t0);
  EXPECT_TRUE(replies(logged, Kind::Input).empty());
  EXPECT_FALSE(only<JobDesk::Log>(logged).empty());
  EXPECT_TRUE(dropped(1, inputFrom(1, 999, keyAt(70, 10))));
  EXPECT_EQ(two.state(b), State::Running);  // none of it harms the job

  // At most kMaxInputsPerSecond a second per job; the next second takes more.
  std::size_t passed = 0;
  for (int i = 0; i < JobDesk::kMaxInputsPerSecond + 30; ++i)
    passed += replies(two.answer(1, inputFrom(1, a, keyAt(70, 10)), t0 + 2s), Kind::Input).size();
  EXPECT_EQ(passed, static_cast<std::size_t>(JobDesk::kMaxInputsPerSecond));
  EXPECT_EQ(
      replies(two.answer(1, inputFrom(1, a, keyAt(70, 10)), t0 + 3s + 1ms), Kind::Input).size(),
      1u);
}

TEST_F(TwoJobsTest, AJobThatGoesSilentEndsAloneWhileTheOtherIsCredited) {
  const std::uint64_t a = runIn("job-a", "render1", "0,0,100,64", t0);
  const std::uint64_t b = runIn("job-b", "render2", "full", t0);
  // Job a is never heard from again (and its frame 1 stays open: its pieces stopped); job b keeps
  // its keepalives, frames and credits going.
  two.arrive(0, a, 1, {1}, t0);
  for (std::uint32_t f = 1; f <= 8; ++f) {
    const Clock::time_point now = t0 + f * 100ms;
    two.message({"job-b", Kind::Keepalive, b, {}, {}}, now);
    const auto released = frame(b, f, now);
    EXPECT_EQ(released.size(), 3u) << "frame " << f;
    EXPECT_EQ(replies(two.presented(b, f, 0), Kind::Presented).size(), 1u);
    const Actions ticked = two.tick(now);
    // Job a's open barrier drops nobody: a is silent, its timeout ends it.
    EXPECT_TRUE(only<JobDesk::Drop>(ticked).empty()) << "frame " << f;
    if (now - t0 <= kTimeout) {
      EXPECT_TRUE(replies(ticked, Kind::Ended).empty()) << "frame " << f;
    } else if (two.state(a) == State::Running) {
      ADD_FAILURE() << "job a not ended at " << f;
    }
  }
  EXPECT_EQ(two.state(a), State::Ending);
  EXPECT_EQ(two.state(b), State::Running);
  EXPECT_EQ(two.lastCredited(b), 8u);
  // Its processes give it up; b goes on.
  for (int p = 0; p < 3; ++p) two.answer(p, answerOf(a, Command::Done, 0, 0), t0 + 900ms);
  EXPECT_EQ(two.sessions(), (std::vector<std::uint64_t>{b}));
  EXPECT_EQ(frame(b, 9, t0 + 900ms).size(), 3u);
}

TEST_F(TwoJobsTest, AThirdJobIsRefusedBusyAndAQueuedOneStartsWhenOneEnds) {
  const std::uint64_t a = runIn("job-a", "render1", "0,0,100,64", t0);
  const std::uint64_t b = runIn("job-b", "render2", "100,0,92,64", t0);
  const Actions busy = two.hello("job-c", helloFrom("render3"), t0);
  ASSERT_EQ(replies(busy, Kind::Refused).size(), 1u);
  EXPECT_EQ(textOf(replies(busy, Kind::Refused)[0]),
            "busy: 2 jobs are on the wall (from render1, render2)");
  EXPECT_TRUE(only<JobDesk::ToProcess>(busy).empty());
  const Actions queued = two.hello("job-d", helloFrom("render4", true), t0);
  EXPECT_EQ(textOf(replies(queued, Kind::Queued).at(0)),
            "busy: 2 jobs are on the wall (from render1, render2); waiting (place 1)");
  EXPECT_EQ(two.queued(), 1u);
  // Job a's connection closes: it ends at once, and once its processes are done the queued job
  // takes its seat, next to b.
  EXPECT_EQ(given(two.disconnected("job-a", t0 + 10ms), Command::Abort),
            (std::vector<int>{0, 1, 2}));
  Actions over;
  for (int p = 0; p < 3; ++p) over = two.answer(p, answerOf(a, Command::Done, 0, 0), t0 + 20ms);
  EXPECT_EQ(records(over).at(0)["ended"], "its connection closed");
  EXPECT_EQ(given(over, Command::Start), (std::vector<int>{0, 1, 2}));
  const std::uint64_t d = commandTo(over, 0, Command::Start).header.session;
  EXPECT_EQ(two.queued(), 0u);
  EXPECT_EQ(two.sessions(), (std::vector<std::uint64_t>{b, d}));
  Actions ready;
  for (int p = 0; p < 3; ++p) ready = two.answer(p, answerOf(d, Command::Ready, 1), t0 + 30ms);
  EXPECT_EQ(replies(ready, Kind::Directory).at(0).peer, "job-d");
  EXPECT_EQ(two.state(d), State::Running);
  EXPECT_EQ(two.state(b), State::Running);
}

// A process lost is out of every job it was in: each job's barrier that waited for it completes
// and each job hears its own roster.
TEST_F(TwoJobsTest, AProcessLostLeavesEveryJob) {
  const std::uint64_t a = runIn("job-a", "render1", "full", t0);
  const std::uint64_t b = runIn("job-b", "render2", "full", t0);
  for (const std::uint64_t s : {a, b}) {
    two.arrive(0, s, 1, {1}, t0);
    two.arrive(1, s, 1, {1}, t0);
  }
  EXPECT_TRUE(members.drop(2));
  const Actions lost = two.lost(2, "silent", t0 + 10ms);
  const auto rosters = replies(lost, Kind::Roster);
  ASSERT_EQ(rosters.size(), 2u);
  EXPECT_EQ(rosters[0].peer, "job-a");
  EXPECT_EQ(rosters[1].peer, "job-b");
  const auto released = only<JobDesk::Release>(lost);
  ASSERT_EQ(released.size(), 4u);  // processes 0 and 1 of each job
  EXPECT_EQ(released[0].session, a);
  EXPECT_EQ(released[3].session, b);
  EXPECT_EQ(records(lost).size(), 1u);  // one "lost" line for the wall
}

// A job that asks for the whole wall while another is on it gets a display the other's window
// does not touch; with none free, the whole wall (on top). The first job gets the whole wall.
TEST_F(TwoJobsTest, AJobWithoutAWindowIsPlacedOnAFreeDisplay) {
  const Actions first = two.hello("job-a", helloFrom("render1"), t0);
  const ServiceCommand whole = commandTo(first, 0, Command::Start);
  EXPECT_EQ((dfb::Region{whole.header.windowX0, whole.header.windowY0, whole.header.windowX1,
                         whole.header.windowY1}),
            (dfb::Region{0, 0, 192, 64}));
  for (int p = 0; p < 3; ++p) two.answer(p, answerOf(whole.header.session, Command::Ready, 1), t0);
  for (int p = 0; p < 3; ++p)
    two.answer(p, answerOf(whole.header.session, Command::Done, 0, 0), t0);
  ASSERT_TRUE(two.sessions().empty());

  runIn("job-a", "render1", "0,0,100,64", t0);  // displays 0 and 1 (64 pixels wide each)
  const Actions placed = two.hello("job-b", helloFrom("render2"), t0);
  const ServiceCommand start = commandTo(placed, 1, Command::Start);
  EXPECT_EQ((dfb::Region{start.header.windowX0, start.header.windowY0, start.header.windowX1,
                         start.header.windowY1}),
            (dfb::Region{128, 0, 192, 64}));
  Actions ready;
  for (int p = 0; p < 3; ++p)
    ready = two.answer(p, answerOf(start.header.session, Command::Ready, 1), t0);
  const auto directory = replies(ready, Kind::Directory);
  ASSERT_EQ(directory.size(), 1u);
  const Directory d = parseDirectory(directory[0].message.data(), directory[0].message.size());
  EXPECT_EQ(d.window, (dfb::Region{128, 0, 192, 64}));
  EXPECT_EQ(d.layout.canvasWidth, 64);
}

TEST_F(TwoJobsTest, AJobWithoutAWindowGetsTheWholeWallWhenNoDisplayIsFree) {
  runIn("job-a", "render1", "60,0,80,64", t0);  // displays 0, 1 and 2
  const ServiceCommand start =
      commandTo(two.hello("job-b", helloFrom("render2"), t0), 0, Command::Start);
  EXPECT_EQ((dfb::Region{start.header.windowX0, start.header.windowY0, start.header.windowX1,
                         start.header.windowY1}),
            (dfb::Region{0, 0, 192, 64}));
}

// ---- moving and resizing a running job's window (docs/design.md, "Moving and resizing") ----

TEST_F(TwoJobsTest, AMoveBuildsTheNewWindowEverywhereThenTellsTheJobItsSwitchFrame) {
  Hello h = inWindow("render1", "0,0,100,64");
  h.canReshape = true;
  const auto starts = only<JobDesk::ToProcess>(two.hello("job-a", h, t0));
  ASSERT_FALSE(starts.empty());
  const std::uint64_t a = starts[0].command.header.session;
  for (int p = 0; p < 3; ++p) two.answer(p, answerOf(a, Command::Ready, 1), t0);
  ASSERT_EQ(two.state(a), State::Running);
  frame(a, 1, t0);
  two.presented(a, 1, 0);
  frame(a, 2, t0);
  two.presented(a, 2, 0);

  JobDesk::MoveVerdict verdict;
  const Actions asked = two.reshape(a, {40, 10, 140, 60}, t0, verdict);
  EXPECT_EQ(verdict.code, JobDesk::MoveVerdict::Code::Moving) << verdict.why;
  EXPECT_TRUE(two.moving(a));
  // Every process builds the new node first; the job hears nothing yet.
  EXPECT_EQ(given(asked, Command::Reshape), (std::vector<int>{0, 1, 2}));
  const ServiceCommand build = commandTo(asked, 1, Command::Reshape);
  const std::uint64_t pieceSession = build.header.pieceSession;
  EXPECT_NE(pieceSession, a);
  EXPECT_EQ((dfb::Region{build.header.windowX0, build.header.windowY0, build.header.windowX1,
                         build.header.windowY1}),
            (dfb::Region{40, 10, 140, 60}));
  EXPECT_TRUE(replies(asked, Kind::Reshape).empty());
  // A second move while this one is under way is a conflict.
  JobDesk::MoveVerdict again;
  two.reshape(a, {0, 0, 64, 64}, t0, again);
  EXPECT_EQ(again.code, JobDesk::MoveVerdict::Code::Conflict);
  EXPECT_EQ(again.why, "the window is moving already");

  // Frames go on while the processes build: the switch frame counts from the credits then.
  frame(a, 3, t0);
  two.presented(a, 3, 0);
  const auto built = [&](std::uint64_t pieces) {
    ServiceCommand c = answerOf(a, Command::Reshaped, 1);
    c.header.pieceSession = pieces;
    return c;
  };
  two.answer(0, built(pieceSession), t0);
  two.answer(2, built(pieceSession), t0);
  // An answer naming another piece session is not this move's.
  EXPECT_TRUE(replies(two.answer(1, built(77), t0), Kind::Reshape).empty());
  const Actions committed = two.answer(1, built(pieceSession), t0);
  const auto told = replies(committed, Kind::Reshape);
  ASSERT_EQ(told.size(), 1u);
  EXPECT_EQ(told[0].peer, "job-a");
  const Reshape r = parseReshape(told[0].message.data(), told[0].message.size());
  EXPECT_EQ(r.session, a);
  EXPECT_EQ(r.version, 1u);
  EXPECT_EQ(r.fromFrame, 6u);  // credited 3, 2 in flight
  EXPECT_EQ(r.directory.session, pieceSession);
  EXPECT_EQ(r.directory.window, (dfb::Region{40, 10, 140, 60}));
  EXPECT_EQ(r.directory.layout.canvasWidth, 100);
  EXPECT_EQ(r.directory.layout.displays.size(), 3u);  // 64-wide displays: 40..140 touches all
  EXPECT_EQ(given(committed, Command::ReshapeAt), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(commandTo(committed, 2, Command::ReshapeAt).header.a, 6);
  EXPECT_EQ(commandTo(committed, 2, Command::ReshapeAt).header.pieceSession, pieceSession);
  EXPECT_EQ(two.window(a), (dfb::Region{40, 10, 140, 60}));
  // Until frame 6 is credited the move is under way; then the next may come.
  for (std::uint32_t f = 4; f <= 5; ++f) {
    frame(a, f, t0);
    two.presented(a, f, 0);
    EXPECT_TRUE(two.moving(a));
  }
  frame(a, 6, t0);
  two.presented(a, 6, 0);
  EXPECT_FALSE(two.moving(a));
  // A process that comes back after the move is given the moved window and its piece session.
  EXPECT_TRUE(members.drop(2));
  two.lost(2, "killed", t0 + 1s);
  members.admit("link2-again", joinOf(2, 2), t0 + 2s);
  const ServiceCommand back = commandTo(two.joined(2, t0 + 2s), 2, Command::Start);
  EXPECT_EQ(back.header.pieceSession, pieceSession);
  EXPECT_EQ((dfb::Region{back.header.windowX0, back.header.windowY0, back.header.windowX1,
                         back.header.windowY1}),
            (dfb::Region{40, 10, 140, 60}));
}

TEST_F(TwoJobsTest, AMoveIsRefusedWithTheReason) {
  const std::uint64_t a = runIn("job-a", "render1", "0,0,100,64", t0);  // cannot reshape
  JobDesk::MoveVerdict v;
  EXPECT_TRUE(only<JobDesk::ToProcess>(two.reshape(a, {0, 0, 64, 64}, t0, v)).empty());
  EXPECT_EQ(v.code, JobDesk::MoveVerdict::Code::Conflict);
  EXPECT_NE(v.why.find("cannot re-plan"), std::string::npos) << v.why;
  two.reshape(a + 100, {0, 0, 64, 64}, t0, v);
  EXPECT_EQ(v.code, JobDesk::MoveVerdict::Code::UnknownWindow);

  Hello h = inWindow("render2", "0,0,100,64");
  h.canReshape = true;
  const auto starts = only<JobDesk::ToProcess>(two.hello("job-b", h, t0));
  ASSERT_FALSE(starts.empty());
  const std::uint64_t b = starts[0].command.header.session;
  two.reshape(b, {0, 0, 64, 64}, t0, v);
  EXPECT_EQ(v.code, JobDesk::MoveVerdict::Code::Conflict);
  EXPECT_EQ(v.why, "the job is starting");
  for (int p = 0; p < 3; ++p) two.answer(p, answerOf(b, Command::Ready, 1), t0);
  EXPECT_TRUE(only<JobDesk::ToProcess>(two.reshape(b, {0, 0, 300, 64}, t0, v)).empty());
  EXPECT_EQ(v.code, JobDesk::MoveVerdict::Code::BadWindow);
  EXPECT_EQ(v.why, "window 0,0,300,64 is not inside the wall's canvas (192x64)");
  two.reshape(b, {0, 0, 8, 64}, t0, v);
  EXPECT_EQ(v.code, JobDesk::MoveVerdict::Code::BadWindow);
  // A process that cannot build the new window ends the job, told why.
  const Actions asked = two.reshape(b, {0, 0, 64, 64}, t0, v);
  ASSERT_EQ(v.code, JobDesk::MoveVerdict::Code::Moving);
  ServiceCommand cannot = answerOf(b, Command::Reshaped, 0, 0, "no memory");
  cannot.header.pieceSession = commandTo(asked, 0, Command::Reshape).header.pieceSession;
  const Actions refused = two.answer(2, cannot, t0);
  EXPECT_EQ(given(refused, Command::ReshapeAt), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(commandTo(refused, 1, Command::ReshapeAt).header.a, 0);
  const auto ended = replies(refused, Kind::Ended);
  ASSERT_EQ(ended.size(), 1u);
  EXPECT_NE(textOf(ended[0]).find("could not move the window: no memory"), std::string::npos)
      << textOf(ended[0]);
}

TEST_F(JobDeskTest, AWallOfOneJobAtATimeDoesNotMoveItsWindow) {
  Hello h = helloFrom("render1");
  h.canReshape = true;
  jobs.hello("job", h, t0);
  allReady(t0);
  JobDesk::MoveVerdict v;
  jobs.reshape(jobs.session(), {0, 0, 64, 64}, t0, v);
  EXPECT_EQ(v.code, JobDesk::MoveVerdict::Code::Conflict);
  EXPECT_NE(v.why.find("--max-jobs 1"), std::string::npos);
}

}  // namespace
}  // namespace wall::service

namespace wall::service {
namespace {

TEST_F(TwoJobsTest, TheWindowManagerListsRaisesAndClosesWindows) {
  const std::uint64_t a = runIn("job-a", "render1", "0,0,100,64", t0);
  const std::uint64_t b = runIn("job-b", "render2", "50,0,100,64", t0);
  std::vector<JobDesk::Window> windows = two.windows(t0);
  ASSERT_EQ(windows.size(), 2u);
  EXPECT_EQ(windows[0].number, 1u);
  EXPECT_EQ(windows[0].host, "render1");
  EXPECT_EQ(windows[0].rect, (dfb::Region{0, 0, 100, 64}));
  EXPECT_EQ(windows[0].z, 0);
  EXPECT_EQ(windows[1].number, 2u);
  EXPECT_EQ(windows[1].rect, (dfb::Region{50, 0, 150, 64}));
  EXPECT_EQ(windows[1].z, 1);  // the newest on top
  EXPECT_EQ(windows[1].state, State::Running);
  // Frames credited: counted, and their rate over the last two seconds.
  for (std::uint32_t f = 1; f <= 10; ++f) {
    frame(a, f, t0 + f * 100ms);
    two.presented(a, f, 0, t0 + f * 100ms);
  }
  windows = two.windows(t0 + 2s);
  EXPECT_EQ(windows[0].frames, 10u);
  EXPECT_NEAR(windows[0].fps, 5.0, 0.01);
  EXPECT_FALSE(windows[0].idle);
  EXPECT_FALSE(windows[1].idle);
  EXPECT_TRUE(two.windows(t0 + 2500ms)[1].idle);  // running, nothing presented for over 2 s
  EXPECT_EQ(two.windows(t0 + 10s)[0].fps, 0.0);

  // Raise: a Raise with an order above every other to each process in the job; a window on top
  // already is left as it is.
  EXPECT_FALSE(two.raise(7).has_value());
  const std::optional<Actions> raised = two.raise(1);
  ASSERT_TRUE(raised.has_value());
  EXPECT_EQ(given(*raised, Command::Raise), (std::vector<int>{0, 1, 2}));
  const ServiceCommand raise = commandTo(*raised, 1, Command::Raise);
  EXPECT_EQ(raise.header.session, a);
  EXPECT_EQ(raise.header.a, 3);  // orders 1 and 2 were the two starts
  windows = two.windows(t0 + 2s);
  EXPECT_EQ(windows[0].z, 1);
  EXPECT_EQ(windows[1].z, 0);
  EXPECT_TRUE(given(*two.raise(1), Command::Raise).empty());
  // A process that joins the job later gets the order in its Start.
  lose(2, "gone", t0 + 2s);
  members.admit("link2b", joinOf(2, 2), t0 + 2s);
  const Actions rejoined = two.joined(2, t0 + 2s);
  EXPECT_EQ(commandTo(rejoined, 2, Command::Start).header.b, 3);

  // Close: the job is told why and its window closes (Abort to the processes); the other runs.
  EXPECT_FALSE(two.close(9, "closed", t0 + 3s).has_value());
  const std::optional<Actions> closed =
      two.close(2, "closed from the wall's control page", t0 + 3s);
  ASSERT_TRUE(closed.has_value());
  const auto ended = replies(*closed, Kind::Ended);
  ASSERT_EQ(ended.size(), 1u);
  EXPECT_EQ(ended[0].peer, "job-b");
  EXPECT_EQ(textOf(ended[0]), "closed from the wall's control page");
  EXPECT_EQ(given(*closed, Command::Abort), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(two.state(b), State::Ending);
  EXPECT_EQ(two.state(a), State::Running);
}

TEST_F(TwoJobsTest, AWindowLinksOnlyAPlainWebAddressAsItsJobsPage) {
  Hello good = inWindow("render1", "0,0,100,64");
  good.job = "scivis builtin:wavelet";
  good.page = "http://render1:8080/";
  Hello bad = inWindow("render2", "50,0,100,64");
  bad.job = "pattern\x1b[2J";
  bad.page = "javascript:alert(1)";
  two.hello("job-a", good, t0);
  two.hello("job-b", bad, t0);
  const std::vector<JobDesk::Window> windows = two.windows(t0);
  ASSERT_EQ(windows.size(), 2u);
  EXPECT_EQ(windows[0].state, State::Starting);
  EXPECT_EQ(windows[0].job, "scivis builtin:wavelet");
  EXPECT_EQ(windows[0].page, "http://render1:8080/");
  EXPECT_EQ(windows[1].page, "");
  EXPECT_EQ(windows[1].job.find('\x1b'), std::string::npos);
}

}  // namespace
}  // namespace wall::service

namespace wall::service {
namespace {

// The windows' thumbnails (serve --control): the head asks every live process once per
// thumbnailEvery (here 200 ms, within the job's timeout), takes each one's cell sums of a window
// once per request, and publishes the window's thumbnail once every process in the window answered.
// What nobody asked for, a second answer, a part of another window or with more pixels in a cell
// than it covers is dropped.
TEST_F(TwoJobsTest, ThumbnailsAreAssembledFromTheProcessesAskedAndNothingElse) {
  JobDesk::Setup setup{&layout, "t", kTimeout, 2, [this] { return ++lastSession; }, 2, 16, 200ms};
  JobDesk desk(setup, members);
  const Actions started = desk.hello("job-a", inWindow("render1", "0,0,100,64"), t0);
  const std::uint64_t a = only<JobDesk::ToProcess>(started).at(0).command.header.session;
  for (int p = 0; p < 3; ++p) desk.answer(p, answerOf(a, Command::Ready, 1), t0);
  ASSERT_EQ(desk.state(a), State::Running);

  const Actions asked = desk.tick(t0);
  EXPECT_EQ(given(asked, Command::Thumbnails), (std::vector<int>{0, 1, 2}));
  const std::uint32_t request =
      static_cast<std::uint32_t>(only<JobDesk::ToProcess>(asked).at(0).command.header.a);
  EXPECT_EQ(only<JobDesk::ToProcess>(asked).at(0).command.header.b, 16);
  EXPECT_TRUE(given(desk.tick(t0 + 100ms), Command::Thumbnails).empty());  // once per 200 ms

  // The window 100 x 64 at factor 7: 15 x 10 cells; process 0 shows its pixels 0..63, process 1
  // 64..99, so cell column 9 (pixels 63..69) holds both.
  const dfb::Region window{0, 0, 100, 64};
  const ThumbnailGrid grid = thumbnailGrid(100, 64, 16);
  ASSERT_EQ(grid, (ThumbnailGrid{7, 15, 10}));
  const std::uint32_t c0 = rgba8(70, 0, 0), c1 = rgba8(0, 140, 7);
  const auto partOf = [&](std::uint32_t color, int x0, int x1, std::uint32_t req) {
    ThumbnailPart part{req, window, emptySums(cellsOf(grid, {x0, 0, x1, 64}))};
    addPixels(part.cells, grid, Image(x1 - x0, 64, color), x0, 0);
    return part;
  };
  desk.thumbnail(0, a, partOf(c0, 0, 64, request + 1));  // a request not made
  ThumbnailPart elsewhere = partOf(c0, 0, 64, request);
  elsewhere.window = {0, 0, 100, 63};
  desk.thumbnail(0, a, elsewhere);                         // not the job's window
  desk.thumbnail(0, a + 100, partOf(c0, 0, 64, request));  // no such job
  ThumbnailPart overfull = partOf(c0, 0, 64, request);
  overfull.cells.sums[4] = 50;  // cell (0, 0) covers 49 pixels
  desk.thumbnail(0, a, overfull);
  EXPECT_EQ(desk.windows(t0)[0].thumbnail, nullptr);

  desk.thumbnail(0, a, partOf(c0, 0, 64, request));
  desk.thumbnail(0, a, partOf(c1, 0, 64, request));   // a second answer of process 0: dropped
  EXPECT_EQ(desk.windows(t0)[0].thumbnail, nullptr);  // process 1 has not answered
  desk.thumbnail(1, a, partOf(c1, 64, 100, request));
  const std::shared_ptr<const Image> shown = desk.windows(t0)[0].thumbnail;
  ASSERT_NE(shown, nullptr);  // process 2 shows none of the window: not waited for
  EXPECT_EQ(shown->width, 15);
  EXPECT_EQ(shown->height, 10);
  EXPECT_EQ(shown->at(0, 0), c0);
  EXPECT_EQ(shown->at(14, 9), c1);
  // Column 9: 1 pixel of c0 and 6 of c1 per row, rounded to nearest.
  EXPECT_EQ(shown->at(9, 3), rgba8(10, 120, 6));
  desk.thumbnail(1, a, partOf(c0, 64, 100, request));  // after publication: dropped
  EXPECT_EQ(desk.windows(t0)[0].thumbnail, shown);

  // The next request: process 1 alone answers; at the request after, process 0's cells keep
  // the last thumbnail's values.
  const Actions again = desk.tick(t0 + 200ms);
  const std::uint32_t next =
      static_cast<std::uint32_t>(only<JobDesk::ToProcess>(again).at(0).command.header.a);
  EXPECT_EQ(next, request + 1);
  desk.thumbnail(1, a, partOf(c0, 64, 100, request));  // the last request's: dropped
  desk.thumbnail(1, a, partOf(c0, 64, 100, next));
  EXPECT_EQ(desk.windows(t0 + 200ms)[0].thumbnail, shown);
  desk.tick(t0 + 400ms);
  const std::shared_ptr<const Image> later = desk.windows(t0 + 400ms)[0].thumbnail;
  ASSERT_NE(later, shown);
  EXPECT_EQ(later->at(0, 0), c0);
  EXPECT_EQ(later->at(14, 9), c0);
  EXPECT_EQ(later->at(9, 3), c0);
}

}  // namespace
}  // namespace wall::service
