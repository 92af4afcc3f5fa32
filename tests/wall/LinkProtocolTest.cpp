// The messages that let wall processes come and go (wall/service/protocol/Protocol.h: Roster and
// the live flags of the directory; wall/service/protocol/LinkMessages.h: the wall's own link):
// round trips, and every malformed variant refused with a base::Error that says what was wrong.
#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <string>

#include "base/Error.h"
#include "wall/service/protocol/LinkMessages.h"
#include "wall/service/protocol/Protocol.h"
#include "wall/service/protocol/ServiceCommands.h"

namespace wall::service {
namespace {

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const base::Error& e) {
    return e.what();
  }
  return "no error";
}

Roster sampleRoster() {
  Roster r;
  r.session = 0x1234;
  r.version = 3;
  r.fromFrame = 41;
  r.processes = {
      {"tcp://10.0.0.1:5000", true}, {"tcp://10.0.0.2:5001", false}, {"tcp://10.0.0.2:5002", true}};
  r.why = "wall process 1 on wall2 lost after frame 37: no word from it for 3 s";
  return r;
}

TEST(LinkProtocol, RosterRoundTrips) {
  const Roster r = sampleRoster();
  const messaging::Bytes bytes = packRoster(r);
  EXPECT_EQ(parseHeader(bytes.data(), bytes.size()).kind, static_cast<std::uint16_t>(Kind::Roster));
  const Roster back = parseRoster(bytes.data(), bytes.size());
  EXPECT_EQ(back.session, 0x1234u);
  EXPECT_EQ(back.version, 3u);
  EXPECT_EQ(back.fromFrame, 41u);
  ASSERT_EQ(back.processes.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(back.processes[i].endpoint, r.processes[i].endpoint);
    EXPECT_EQ(back.processes[i].live, r.processes[i].live);
  }
  EXPECT_EQ(back.why, r.why);
}

TEST(LinkProtocol, EveryTruncationOfARosterIsRefused) {
  const messaging::Bytes whole = packRoster(sampleRoster());
  for (std::size_t n = sizeof(MessageHeader); n < whole.size(); ++n) {
    SCOPED_TRACE(n);
    const messaging::Bytes cut(whole.begin(), whole.begin() + static_cast<long>(n));
    EXPECT_NE(errorOf([&] { parseRoster(cut.data(), cut.size()); }).find("malformed roster"),
              std::string::npos);
  }
}

TEST(LinkProtocol, RosterWithABadLiveFlagOrNoEndpointIsRefused) {
  Roster r = sampleRoster();
  messaging::Bytes bytes = packRoster(r);
  // The first process's live flag follows its endpoint text.
  const std::size_t flagAt = sizeof(MessageHeader) + 12 + 2 + r.processes[0].endpoint.size();
  ASSERT_EQ(bytes[flagAt], std::byte{1});
  bytes[flagAt] = std::byte{7};
  EXPECT_NE(errorOf([&] { parseRoster(bytes.data(), bytes.size()); }).find("live flag 7"),
            std::string::npos);
  r.processes[2].endpoint.clear();
  bytes = packRoster(r);
  EXPECT_NE(errorOf([&] {
              parseRoster(bytes.data(), bytes.size());
            }).find("live process 2 has no endpoint"),
            std::string::npos);
  r.processes.clear();
  bytes = packRoster(r);
  EXPECT_NE(errorOf([&] { parseRoster(bytes.data(), bytes.size()); }).find("0 wall processes"),
            std::string::npos);
}

TEST(LinkProtocol, JoinRoundTripsAndNeedsATcpEndpoint) {
  Join j;
  j.token = "secret";
  j.process = 3;
  j.host = "wall2";
  j.pieceEndpoint = "tcp://10.0.0.2:41000";
  j.layoutHash = 0xfeedface;
  j.incarnation = 99;
  messaging::Bytes bytes = packJoin(j);
  const Join back = parseJoin(bytes.data(), bytes.size());
  EXPECT_EQ(back.token, "secret");
  EXPECT_EQ(back.process, 3u);
  EXPECT_EQ(back.host, "wall2");
  EXPECT_EQ(back.pieceEndpoint, j.pieceEndpoint);
  EXPECT_EQ(back.layoutHash, 0xfeedfaceu);
  EXPECT_EQ(back.incarnation, 99u);
  j.pieceEndpoint = "ipc:///tmp/x";
  bytes = packJoin(j);
  EXPECT_NE(errorOf([&] { parseJoin(bytes.data(), bytes.size()); }).find("piece endpoint"),
            std::string::npos);
}

TEST(LinkProtocol, BarrierValuesAreBounded) {
  BarrierValues b{12, {1, -2, 3, 4, 5}};
  messaging::Bytes bytes = packBarrier(7, b);
  const BarrierValues back = parseBarrier(bytes.data(), bytes.size());
  EXPECT_EQ(back.frameId, 12u);
  EXPECT_EQ(back.values, b.values);
  b.values.assign(17, 0);
  bytes = packBarrier(7, b);
  EXPECT_NE(errorOf([&] { parseBarrier(bytes.data(), bytes.size()); }).find("17 values"),
            std::string::npos);
  b.values.clear();
  bytes = packBarrier(7, b);
  EXPECT_NE(errorOf([&] { parseBarrier(bytes.data(), bytes.size()); }).find("0 values"),
            std::string::npos);
}

TEST(LinkProtocol, PixelsMustFillTheMessageExactly) {
  const std::vector<std::uint32_t> pixels = {1, 2, 3, 0xffffffff};
  messaging::Bytes bytes = packPixels(5, 9, pixels);
  const CapturePixels back = parsePixels(bytes.data(), bytes.size());
  EXPECT_EQ(back.frameId, 9u);
  EXPECT_EQ(back.pixels, pixels);
  // A count that claims more than the message holds is refused before anything is allocated.
  const std::uint64_t lie = std::uint64_t{1} << 40;
  std::memcpy(bytes.data() + sizeof(MessageHeader) + 4, &lie, sizeof lie);
  EXPECT_NE(errorOf([&] { parsePixels(bytes.data(), bytes.size()); }).find("pixels in 16 bytes"),
            std::string::npos);
}

TEST(LinkProtocol, NoPixelsAtAllRoundTrip) {
  // An empty capture (a process with nothing to show) reads into an empty vector, whose data()
  // may be null: nothing is copied from or to it.
  const messaging::Bytes bytes = packPixels(5, 9, {});
  EXPECT_TRUE(parsePixels(bytes.data(), bytes.size()).pixels.empty());
}

TEST(LinkProtocol, ThumbnailsRoundTripAndTheirSizesAreCheckedBeforeAnythingIsAllocated) {
  ThumbnailPart part{7, {10, 20, 110, 84}, emptySums({3, 0, 5, 2})};
  for (std::size_t i = 0; i < part.cells.sums.size(); ++i)
    part.cells.sums[i] = static_cast<std::uint32_t>(i);
  const messaging::Bytes bytes = packThumbnail(42, part);
  EXPECT_EQ(parseHeader(bytes.data(), bytes.size()).session, 42u);
  const ThumbnailPart back = parseThumbnail(bytes.data(), bytes.size());
  EXPECT_EQ(back.request, 7u);
  EXPECT_EQ(back.window, part.window);
  EXPECT_EQ(back.cells.cells, part.cells.cells);
  EXPECT_EQ(back.cells.sums, part.cells.sums);
  // Sums missing or left over, every truncation.
  messaging::Bytes longer = bytes;
  longer.resize(bytes.size() + 4);
  EXPECT_NE(errorOf([&] { parseThumbnail(longer.data(), longer.size()); }).find("4 cells in"),
            std::string::npos);
  for (std::size_t n = sizeof(MessageHeader); n < bytes.size(); n += 3)
    EXPECT_THROW(parseThumbnail(bytes.data(), n), base::Error) << n;
  // Cells outside the window's largest grid (100 x 64 at factor 1), an empty or huge window.
  const auto refused = [](const ThumbnailPart& bad) {
    const messaging::Bytes b = packThumbnail(1, bad);
    return !errorOf([&] { parseThumbnail(b.data(), b.size()); }).empty();
  };
  ThumbnailPart outside = part;
  outside.cells = emptySums({99, 0, 101, 1});
  EXPECT_TRUE(refused(outside));
  ThumbnailPart empty = part;
  empty.cells = emptySums({5, 0, 5, 2});
  EXPECT_TRUE(refused(empty));
  ThumbnailPart noWindow = part;
  noWindow.window = {10, 20, 10, 84};
  EXPECT_TRUE(refused(noWindow));
  ThumbnailPart huge = part;
  huge.window = {0, 0, (1 << 20) + 1, 64};
  EXPECT_TRUE(refused(huge));
}

TEST(LinkProtocol, CommandsRoundTripAndUnknownOnesAreRefused) {
  ServiceCommand c;
  c.header.kind = Command::Start;
  c.header.session = 77;
  c.header.a = 12;
  c.text = "/tmp/captures";
  const messaging::Bytes message = packCommandMessage(77, packCommand(c));
  const ServiceCommand back = parseCommand(commandBody(message.data(), message.size()));
  EXPECT_EQ(back.header.kind, Command::Start);
  EXPECT_EQ(back.header.a, 12);
  EXPECT_EQ(back.text, "/tmp/captures");
  messaging::Bytes body = packCommand(c);
  const std::uint32_t bad = 42;
  std::memcpy(body.data(), &bad, sizeof bad);
  EXPECT_NE(errorOf([&] { parseCommand(body); }).find("unknown service command 42"),
            std::string::npos);
  body.resize(body.size() - 1);
  EXPECT_NE(errorOf([&] { parseCommand(body); }).find("malformed"), std::string::npos);
}

TEST(LinkProtocol, LayoutHashSeesDisplaysNotTheFileName) {
  Layout a;
  a.file = "a.toml";
  a.canvasWidth = 400;
  a.canvasHeight = 300;
  a.processCount = 2;
  Display left;
  left.name = "left";
  left.rect = {0, 0, 200, 300};
  left.process = 0;
  Display right = left;
  right.name = "right";
  right.rect = {200, 0, 400, 300};
  right.process = 1;
  a.displays = {left, right};
  Layout b = a;
  b.file = "b.toml";
  EXPECT_EQ(layoutHash(a), layoutHash(b));
  b.displays[1].process = 0;
  EXPECT_NE(layoutHash(a), layoutHash(b));
  b = a;
  b.displays[0].rect.x1 = 199;
  EXPECT_NE(layoutHash(a), layoutHash(b));
}

}  // namespace
}  // namespace wall::service
