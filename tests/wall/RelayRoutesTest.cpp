// What a relay (wall/service/relay/RelayRoutes.h) does to the messages it forwards: the wall's
// Directory and Roster reach the job with the relay's endpoints (live flags, layout, session,
// credits, roster version and reason as the wall said); piece messages pass only when they are
// batches of a session the relay has seen in a Directory; the directory link carries the kinds of
// a job's conversation with the wall only.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "wall/layout/Layout.h"
#include "wall/service/protocol/Protocol.h"
#include "wall/service/relay/RelayRoutes.h"

namespace wall::service {
namespace {

std::string relayAt(int p) { return "tcp://10.0.9.1:" + std::to_string(41000 + p); }

Directory wallDirectory() {
  Directory d;
  d.session = 0x1122'3344'5566'7788ull;
  d.layout = loadLayout(std::string(DFBWALL_SOURCE_DIR) + "/configs/walls/2x2.toml");
  for (int p = 0; p < d.layout.processCount; ++p)
    d.processes.push_back({"tcp://wall" + std::to_string(p) + ":" + std::to_string(5600 + p)});
  d.processes[2].live = false;  // lost before the job came
  d.framesInFlight = 3;
  d.timeoutMs = 7000;
  d.rosterVersion = 4;
  d.window = {0, 0, d.layout.canvasWidth, d.layout.canvasHeight};
  return d;
}

messaging::Bytes batch(std::uint64_t session) {
  BatchWriter w;
  BatchHeader h;
  h.frameId = 1;
  h.display = 0;
  h.codec = Codec::Raw;
  w.start(session, h);
  const std::vector<std::uint32_t> pixels(16 * 8, 0xff336699u);
  w.add(CodecSpec{}, {0, 0, 16, 8}, pixels.data(), 16);
  return w.take();
}

TEST(RelayRoutes, DirectoryNamesTheRelayAndKeepsTheRest) {
  const Directory wall = wallDirectory();
  const messaging::Bytes bytes = relayDirectory(wall, relayAt);
  const Directory job = parseDirectory(bytes.data(), bytes.size());
  ASSERT_EQ(job.processes.size(), wall.processes.size());
  for (size_t p = 0; p < job.processes.size(); ++p) {
    EXPECT_EQ(job.processes[p].endpoint, relayAt(static_cast<int>(p)));
    EXPECT_EQ(job.processes[p].live, wall.processes[p].live) << "process " << p;
  }
  EXPECT_EQ(job.session, wall.session);
  EXPECT_EQ(job.framesInFlight, 3u);
  EXPECT_EQ(job.timeoutMs, 7000u);
  EXPECT_EQ(job.rosterVersion, 4u);
  EXPECT_EQ(job.layout.file, wall.layout.file);
  ASSERT_EQ(job.layout.displays.size(), wall.layout.displays.size());
  for (size_t i = 0; i < job.layout.displays.size(); ++i) {
    EXPECT_EQ(job.layout.displays[i].name, wall.layout.displays[i].name);
    EXPECT_EQ(job.layout.displays[i].process, wall.layout.displays[i].process);
    EXPECT_EQ(job.layout.displays[i].rect.x0, wall.layout.displays[i].rect.x0);
    EXPECT_EQ(job.layout.displays[i].rect.y1, wall.layout.displays[i].rect.y1);
  }
}

TEST(RelayRoutes, RosterNamesTheRelayForProcessesWithAnEndpoint) {
  Roster wall;
  wall.session = 77;
  wall.version = 5;
  wall.fromFrame = 12;
  wall.processes = {{"tcp://wall0:5600", true},
                    {"tcp://wall1:5611", true},  // restarted: a new port
                    {"", false},                 // lost
                    {"tcp://wall3:5603", false}};
  wall.why = "wall process 1 on wall1 rejoined at frame 12";
  const messaging::Bytes bytes = relayRoster(wall, relayAt);
  const Roster job = parseRoster(bytes.data(), bytes.size());
  ASSERT_EQ(job.processes.size(), 4u);
  EXPECT_EQ(job.processes[0].endpoint, relayAt(0));
  EXPECT_EQ(job.processes[1].endpoint, relayAt(1));
  EXPECT_EQ(job.processes[2].endpoint, "");
  EXPECT_EQ(job.processes[3].endpoint, relayAt(3));
  for (size_t p = 0; p < 4; ++p) EXPECT_EQ(job.processes[p].live, wall.processes[p].live);
  EXPECT_EQ(job.session, 77u);
  EXPECT_EQ(job.version, 5u);
  EXPECT_EQ(job.fromFrame, 12u);
  EXPECT_EQ(job.why, wall.why);
}

TEST(RelayRoutes, AMovedWindowsDirectoryNamesTheRelayToo) {
  Reshape wall;
  wall.session = wallDirectory().session;
  wall.version = 1;
  wall.fromFrame = 40;
  wall.directory = wallDirectory();
  wall.directory.session = wall.session + 1;  // the moved window's piece session
  const messaging::Bytes bytes = relayReshape(wall, relayAt);
  const Reshape job = parseReshape(bytes.data(), bytes.size());
  ASSERT_EQ(job.directory.processes.size(), wall.directory.processes.size());
  for (size_t p = 0; p < job.directory.processes.size(); ++p) {
    EXPECT_EQ(job.directory.processes[p].endpoint, relayAt(static_cast<int>(p)));
    EXPECT_EQ(job.directory.processes[p].live, wall.directory.processes[p].live);
  }
  EXPECT_EQ(job.session, wall.session);
  EXPECT_EQ(job.directory.session, wall.session + 1);
  EXPECT_EQ(job.fromFrame, 40u);
  EXPECT_EQ(job.directory.window, wall.directory.window);
}

TEST(RelayRoutes, OnlyBatchesOfTheWallsSessionsPass) {
  RelaySessions sessions;
  const messaging::Bytes mine = batch(0xabc), stranger = batch(0xdef), unset = batch(0);
  auto verdict = [&](const messaging::Bytes& m) { return sessions.admit(m.data(), m.size()); };

  EXPECT_FALSE(verdict(mine).forward) << "before the wall gave the session";
  sessions.add(0xabc);
  const RelaySessions::Verdict ok = verdict(mine);
  EXPECT_TRUE(ok.forward);
  EXPECT_EQ(ok.session, 0xabcu);

  const RelaySessions::Verdict other = verdict(stranger);
  EXPECT_FALSE(other.forward);
  EXPECT_EQ(other.session, 0xdefu);
  EXPECT_NE(other.why.find("not the session"), std::string::npos) << other.why;
  EXPECT_FALSE(verdict(unset).forward);

  // The session's id on another kind of message, garbage, a cut header.
  const messaging::Bytes keepalive = packControl(Kind::Keepalive, 0xabc, 0);
  EXPECT_FALSE(verdict(keepalive).forward);
  EXPECT_NE(verdict(keepalive).why.find("not a piece batch"), std::string::npos);
  messaging::Bytes garbage(mine.size(), std::byte{0x5a});
  EXPECT_FALSE(verdict(garbage).forward);
  EXPECT_FALSE(sessions.admit(mine.data(), 10).forward);
  messaging::Bytes otherVersion = mine;
  otherVersion[4] = std::byte{7};
  EXPECT_NE(verdict(otherVersion).why.find("protocol version 7"), std::string::npos);

  sessions.remove(0xabc);
  EXPECT_FALSE(verdict(mine).forward) << "after the job is gone";
}

TEST(RelayRoutes, TheDirectoryLinkCarriesJobKindsOnly) {
  for (Kind k : {Kind::Hello, Kind::Keepalive, Kind::Capture, Kind::Bye}) EXPECT_TRUE(jobKind(k));
  for (Kind k : {Kind::Batch, Kind::Join, Kind::Welcome, Kind::Beat, Kind::Command, Kind::Barrier,
                 Kind::Pixels, Kind::Dropped, Kind::Directory, Kind::Presented, Kind::Input})
    EXPECT_FALSE(jobKind(k)) << static_cast<int>(k);
  for (Kind k : {Kind::Directory, Kind::Refused, Kind::Queued, Kind::Keepalive, Kind::Presented,
                 Kind::Ended, Kind::Roster, Kind::Reshape, Kind::Input})
    EXPECT_TRUE(wallToJobKind(k));
  for (Kind k : {Kind::Welcome, Kind::Command, Kind::Barrier, Kind::Hello, Kind::Batch})
    EXPECT_FALSE(wallToJobKind(k)) << static_cast<int>(k);
}

}  // namespace
}  // namespace wall::service
