// The wall service's wire protocol (wall/service/protocol/Protocol.h): round trips of every message
// kind (hello, directory, text, control, piece batches in each codec, built with BatchWriter::add
// and with encodePiece + append), and hostile input: every malformed message is a base::Error with
// a message a log can print, never a crash (this suite also runs under ASan+UBSan, and every
// truncated message is copied into a buffer of exactly its size so an over-read is caught).
//
// With DFBWALL_WRITE_FUZZ_SEEDS=DIR, the test WritesFuzzSeeds writes real pack* output into
// DIR/service_hello, DIR/service_batch and DIR/service_directory: the seed corpora of the fuzz
// targets (tests/fuzz/corpus/, scripts/fuzz).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "base/Error.h"
#include "wall/image/Image.h"
#include "wall/layout/Layout.h"
#include "wall/service/protocol/Codec.h"
#include "wall/service/protocol/PeerText.h"
#include "wall/service/protocol/Protocol.h"
#include "wall/service/protocol/ServiceCommands.h"

namespace wall::service {
namespace {

using Pixels = std::vector<std::uint32_t>;

// Byte offsets of the fields the hostile tests patch (the layout Protocol.cpp writes).
constexpr std::size_t kHeaderBytes = sizeof(MessageHeader);
constexpr std::size_t kVersionAt = 4;
constexpr std::size_t kKindAt = 6;
constexpr std::size_t kHelloTokenLengthAt = kHeaderBytes;
constexpr std::size_t kDirectoryCanvasWidthAt = kHeaderBytes;
constexpr std::size_t kDirectoryDisplayCountAt = kHeaderBytes + 8;
constexpr std::size_t kDirectoryFirstNameAt = kHeaderBytes + 12;
constexpr std::size_t kBatchPieceCountAt = kHeaderBytes + 16;
constexpr std::size_t kBatchFirstRecordAt = kHeaderBytes + 20;
constexpr std::size_t kRecordSizeAt = 16;  // within a piece record: x0, y0, x1, y1, size
constexpr std::size_t kRecordBytes = 20;

template <typename T>
void poke(messaging::Bytes& bytes, std::size_t at, T value) {
  ASSERT_LE(at + sizeof value, bytes.size());
  std::memcpy(bytes.data() + at, &value, sizeof value);
}

// The message of the base::Error `f` throws; a test failure when it throws nothing or another
// type.
std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const base::Error& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not a base::Error: " << e.what();
    return {};
  }
  ADD_FAILURE() << "no exception";
  return {};
}

#define EXPECT_ERROR_HAS(statement, text)                                                 \
  do {                                                                                    \
    const std::string message_ = errorOf([&] { statement; });                             \
    EXPECT_NE(message_.find(text), std::string::npos) << "message: '" << message_ << "'"; \
  } while (false)

Pixels randomPixels(int width, int height, unsigned seed) {
  std::mt19937 random(seed);
  Pixels pixels(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  for (std::uint32_t& p : pixels) p = random();
  return pixels;
}

// Smooth and opaque, with a little structure: compresses, and JPEG keeps it close.
Pixels smoothPixels(int width, int height) {
  Pixels pixels(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
             static_cast<std::size_t>(x)] =
          rgba8(static_cast<std::uint8_t>(30 + 190 * x / width),
                static_cast<std::uint8_t>(50 + 150 * y / height),
                static_cast<std::uint8_t>(220 - 120 * (x + y) / (width + height)), 255);
  return pixels;
}

Hello fullHello() {
  Hello h;
  h.token = "s3cret-token";
  h.host = "render-node-07";
  h.renderRanks = 12;
  h.tileSize = 32;
  h.codec = parseCodec("jpeg:75:444");
  h.framesInFlight = 3;
  h.wait = true;
  h.captureDir = "/scratch/captures/run 1";
  h.captureEvery = 10;
  h.job = "scivis builtin:wavelet";
  h.page = "http://render-node-07:8080/";
  return h;
}

// configs/walls/2x2.toml: four 200x150 panels, bezels 6/6/5/5 px, one process each.
constexpr const char* k2x2Bezels = R"(
description = "2x2 grid of 200x150 panels with bezels"
[grid]
columns = 2
rows = 2
display_size = [200, 150]
bezel_px = [6, 6, 5, 5]
)";

constexpr const char* k3x2ByColumn = R"(
[grid]
columns = 3
rows = 2
display_size = [160, 120]
bezel_px = [15, 30, 10, 20]
process_per = "column"
)";

Layout layoutOf(const char* toml, const std::string& file) {
  LayoutResult result = readLayoutText(toml, file);
  EXPECT_TRUE(result.ok()) << joinProblems(result.problems);
  return result.layout;
}

Directory directoryOf(const char* toml, const std::string& file) {
  Directory d;
  d.session = 0x0123'4567'89AB'CDEFull;
  d.layout = layoutOf(toml, file);
  for (int p = 0; p < d.layout.processCount; ++p)
    d.processes.push_back(
        {"tcp://wall" + std::to_string(p + 1) + ".example:" + std::to_string(5600 + p)});
  d.framesInFlight = 3;
  d.timeoutMs = 15000;
  d.window = {0, 0, d.layout.canvasWidth, d.layout.canvasHeight};
  return d;
}

Directory twoByTwo() { return directoryOf(k2x2Bezels, "configs/walls/2x2.toml"); }

// A display-sized image and the pieces a render rank would cut from it: 64x64 tiles clipped at
// the display's border (so odd sizes), rows `stride` pixels apart.
struct Source {
  int width = 0, height = 0;
  Pixels pixels;
  std::vector<dfb::Region> pieces;
  const std::uint32_t* at(const dfb::Region& r) const {
    return pixels.data() + static_cast<std::size_t>(r.y0) * static_cast<std::size_t>(width) +
           static_cast<std::size_t>(r.x0);
  }
};

Source sourceImage(int width, int height, bool smooth, unsigned seed) {
  Source s;
  s.width = width, s.height = height;
  s.pixels = smooth ? smoothPixels(width, height) : randomPixels(width, height, seed);
  for (int y = 0; y < height; y += 64)
    for (int x = 0; x < width; x += 64)
      s.pieces.push_back({x, y, std::min(x + 64, width), std::min(y + 64, height)});
  return s;
}

BatchHeader batchHeader(Codec codec) {
  BatchHeader h;
  h.frameId = 41;
  h.display = 2;
  h.renderRank = 5;
  h.codec = codec;
  return h;
}

// A batch of every piece of `source`; every other piece through encodePiece + append, as the
// service client does it.
messaging::Bytes batchOf(const CodecSpec& spec, const Source& source, std::uint64_t session = 77) {
  BatchWriter writer;
  BatchHeader h = batchHeader(spec.codec);
  writer.start(session, h);
  messaging::Bytes piece;
  for (std::size_t i = 0; i < source.pieces.size(); ++i) {
    const dfb::Region& r = source.pieces[i];
    if (i % 2 == 0) {
      writer.add(spec, r, source.at(r), source.width);
    } else {
      encodePiece(spec, r, source.at(r), source.width, piece);
      writer.append(piece);
    }
  }
  EXPECT_EQ(writer.pieces(), source.pieces.size());
  return writer.take();
}

Pixels decodePiece(Codec codec, const BatchPiece& piece) {
  Pixels out(static_cast<std::size_t>(piece.local.pixelCount()));
  decodePixels(codec, piece.data, piece.size, piece.local.width(), piece.local.height(), out.data(),
               piece.local.width());
  return out;
}

Pixels cut(const Source& source, const dfb::Region& r) {
  Pixels out;
  for (int y = r.y0; y < r.y1; ++y) {
    const std::uint32_t* row = source.at({r.x0, y, r.x1, y + 1});
    out.insert(out.end(), row, row + r.width());
  }
  return out;
}

// ---- round trips ----

TEST(Protocol, HelloRoundTrips) {
  for (const Hello& hello : {Hello{}, fullHello()}) {
    const messaging::Bytes bytes = packHello(hello);
    const MessageHeader header = parseHeader(bytes.data(), bytes.size());
    EXPECT_EQ(header.magic, kMagic);
    EXPECT_EQ(header.version, kProtocolVersion);
    EXPECT_EQ(header.kind, static_cast<std::uint16_t>(Kind::Hello));
    EXPECT_EQ(header.session, 0u);
    const Hello back = parseHello(bytes.data(), bytes.size());
    EXPECT_EQ(back.token, hello.token);
    EXPECT_EQ(back.host, hello.host);
    EXPECT_EQ(back.renderRanks, hello.renderRanks);
    EXPECT_EQ(back.tileSize, hello.tileSize);
    EXPECT_EQ(back.codec, hello.codec);
    EXPECT_EQ(back.framesInFlight, hello.framesInFlight);
    EXPECT_EQ(back.wait, hello.wait);
    EXPECT_EQ(back.captureDir, hello.captureDir);
    EXPECT_EQ(back.captureEvery, hello.captureEvery);
    EXPECT_EQ(back.canReshape, hello.canReshape);
    EXPECT_EQ(back.job, hello.job);
    EXPECT_EQ(back.page, hello.page);
  }
  // A hello cut in its job and page fields is refused.
  {
    messaging::Bytes bytes = packHello(fullHello());
    const std::size_t tail = 2 + fullHello().job.size() + 2 + fullHello().page.size();
    bytes.resize(bytes.size() - tail + 3);  // half a job field
    EXPECT_THROW(parseHello(bytes.data(), bytes.size()), base::Error);
  }
  Hello movable = fullHello();
  movable.canReshape = true;
  const messaging::Bytes movableBytes = packHello(movable);
  EXPECT_TRUE(parseHello(movableBytes.data(), movableBytes.size()).canReshape);
  // Each codec, and the longest strings allowed.
  for (const char* codec : {"raw", "snappy", "jpeg:1:420", "jpeg:100:422"}) {
    Hello hello = fullHello();
    hello.codec = parseCodec(codec);
    hello.token = std::string(kMaxStringBytes, 't');
    const messaging::Bytes bytes = packHello(hello);
    const Hello back = parseHello(bytes.data(), bytes.size());
    EXPECT_EQ(back.codec, hello.codec) << codec;
    EXPECT_EQ(back.token, hello.token);
  }
}

TEST(Protocol, DirectoryOfA2x2WallWithBezelsRoundTrips) {
  const Directory d = twoByTwo();
  ASSERT_EQ(d.layout.displays.size(), 4u);
  ASSERT_EQ(d.layout.canvasWidth, 412);
  ASSERT_EQ(d.layout.canvasHeight, 310);
  const messaging::Bytes bytes = packDirectory(d);
  const MessageHeader header = parseHeader(bytes.data(), bytes.size());
  EXPECT_EQ(header.kind, static_cast<std::uint16_t>(Kind::Directory));
  EXPECT_EQ(header.session, d.session);

  const Directory back = parseDirectory(bytes.data(), bytes.size());
  EXPECT_EQ(back.session, d.session);
  EXPECT_EQ(back.framesInFlight, 3u);
  EXPECT_EQ(back.timeoutMs, 15000u);
  EXPECT_EQ(back.layout.file, "configs/walls/2x2.toml");
  EXPECT_EQ(back.layout.canvasWidth, 412);
  EXPECT_EQ(back.layout.canvasHeight, 310);
  EXPECT_EQ(back.layout.processCount, 4);
  ASSERT_EQ(back.layout.displays.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(back.layout.displays[i].name, d.layout.displays[i].name);
    EXPECT_EQ(back.layout.displays[i].rect, d.layout.displays[i].rect);
    EXPECT_EQ(back.layout.displays[i].process, d.layout.displays[i].process);
  }
  // The bezels: 12 px between the columns, 10 px between the rows.
  EXPECT_EQ(back.layout.displays[0].rect, (dfb::Region{0, 0, 200, 150}));
  EXPECT_EQ(back.layout.displays[3].rect, (dfb::Region{212, 160, 412, 310}));
  ASSERT_EQ(back.processes.size(), 4u);
  for (std::size_t p = 0; p < 4; ++p)
    EXPECT_EQ(back.processes[p].endpoint, d.processes[p].endpoint);
  EXPECT_EQ(back.processes[3].endpoint, "tcp://wall4.example:5603");
}

TEST(Protocol, DirectoryWithProcessesDrivingSeveralDisplaysRoundTrips) {
  const Directory d = directoryOf(k3x2ByColumn, "3x2.toml");
  ASSERT_EQ(d.layout.processCount, 3);
  const messaging::Bytes bytes = packDirectory(d);
  const Directory back = parseDirectory(bytes.data(), bytes.size());
  ASSERT_EQ(back.layout.displays.size(), 6u);
  EXPECT_EQ(back.layout.processCount, 3);
  EXPECT_EQ(back.processes.size(), 3u);
  for (std::size_t i = 0; i < 6; ++i) {
    EXPECT_EQ(back.layout.displays[i].rect, d.layout.displays[i].rect);
    EXPECT_EQ(back.layout.displays[i].process, d.layout.displays[i].process);
  }
}

TEST(Protocol, AReshapeCarriesTheNewWindowsDirectoryAndSwitchFrame) {
  Reshape r;
  r.session = 0x1234;
  r.version = 2;
  r.fromFrame = 77;
  r.directory = twoByTwo();
  r.directory.session = 0x5678;
  const messaging::Bytes bytes = packReshape(r);
  const MessageHeader header = parseHeader(bytes.data(), bytes.size());
  EXPECT_EQ(header.kind, static_cast<std::uint16_t>(Kind::Reshape));
  EXPECT_EQ(header.session, 0x1234u);
  const Reshape back = parseReshape(bytes.data(), bytes.size());
  EXPECT_EQ(back.session, 0x1234u);
  EXPECT_EQ(back.version, 2u);
  EXPECT_EQ(back.fromFrame, 77u);
  EXPECT_EQ(back.directory.session, 0x5678u);
  EXPECT_EQ(back.directory.layout.displays.size(), 4u);
  EXPECT_EQ(back.directory.layout.displays[3].rect, (dfb::Region{212, 160, 412, 310}));
  EXPECT_EQ(back.directory.processes[3].endpoint, "tcp://wall4.example:5603");
  EXPECT_EQ(back.directory.window, r.directory.window);
  // The piece session is the new window's own: never 0 nor the job's session.
  Reshape same = r;
  same.directory.session = r.session;
  const messaging::Bytes sameBytes = packReshape(same);
  EXPECT_ERROR_HAS(parseReshape(sameBytes.data(), sameBytes.size()), "piece session");
  Reshape never = r;
  never.fromFrame = 0;
  const messaging::Bytes neverBytes = packReshape(never);
  EXPECT_ERROR_HAS(parseReshape(neverBytes.data(), neverBytes.size()), "switch frame 0");
}

TEST(Protocol, TextMessagesRoundTrip) {
  for (const Kind kind : {Kind::Refused, Kind::Queued, Kind::Ended})
    for (const std::string& text :
         {std::string(), std::string("the wall is busy with a job from render-3 (since 12:00)"),
          std::string("2"), std::string(kMaxStringBytes, 'x'), std::string("\0 nul\n", 6)}) {
      const messaging::Bytes bytes = packText(kind, 99, text);
      const MessageHeader header = parseHeader(bytes.data(), bytes.size());
      EXPECT_EQ(header.kind, static_cast<std::uint16_t>(kind));
      EXPECT_EQ(header.session, 99u);
      EXPECT_EQ(parseText(bytes.data(), bytes.size()), text);
    }
  // A longer reason is cut, not refused: the job still learns why.
  const messaging::Bytes bytes =
      packText(Kind::Refused, 1, std::string(kMaxStringBytes + 100, 'y'));
  EXPECT_EQ(parseText(bytes.data(), bytes.size()), std::string(kMaxStringBytes, 'y'));
}

TEST(Protocol, ControlMessagesRoundTrip) {
  struct Case {
    Kind kind;
    std::uint64_t value;
    std::int64_t second;
  };
  for (const Case c :
       {Case{Kind::Keepalive, 0, 0}, Case{Kind::Bye, 1234, 0}, Case{Kind::Capture, 17, 3},
        Case{Kind::Presented, 4'000'000'000u, 1'700'000'000'123'456'789},
        Case{Kind::Presented, std::numeric_limits<std::uint64_t>::max(),
             std::numeric_limits<std::int64_t>::min()},
        Case{Kind::Capture, 0, -1}}) {
    const messaging::Bytes bytes = packControl(c.kind, 0xFEED, c.value, c.second);
    const MessageHeader header = parseHeader(bytes.data(), bytes.size());
    EXPECT_EQ(header.kind, static_cast<std::uint16_t>(c.kind));
    EXPECT_EQ(header.session, 0xFEEDu);
    const Control back = parseControl(bytes.data(), bytes.size());
    EXPECT_EQ(back.value, c.value);
    EXPECT_EQ(back.second, c.second);
  }
}

TEST(Protocol, InputEventsRoundTripAndBadFieldsAreRefusedByName) {
  WindowInput in;
  in.kind = WindowInput::kDrag;
  in.x = 12;
  in.y = -3;
  in.dx = -kMaxInputMove;
  in.dy = 40;
  in.pan = true;
  messaging::Bytes bytes = packInput(0xBEEF, in);
  EXPECT_EQ(parseHeader(bytes.data(), bytes.size()).session, 0xBEEFu);
  const WindowInput back = parseInput(bytes.data(), bytes.size());
  EXPECT_EQ(back.kind, in.kind);
  EXPECT_EQ(back.x, 12);
  EXPECT_EQ(back.y, -3);
  EXPECT_EQ(back.dx, -kMaxInputMove);
  EXPECT_EQ(back.dy, 40);
  EXPECT_TRUE(back.pan);
  const auto refused = [](const WindowInput& bad, const std::string& why) {
    const messaging::Bytes b = packInput(1, bad);
    try {
      parseInput(b.data(), b.size());
      ADD_FAILURE() << "accepted: " << why;
    } catch (const base::Error& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  };
  WindowInput bad = in;
  bad.kind = 0;
  refused(bad, "kind 0");
  bad = WindowInput{};
  bad.key = WindowInput::kKeyCount;
  refused(bad, "key 6");
  bad = in;
  bad.dy = kMaxInputMove + 1;
  refused(bad, "move");
  bytes.back() = std::byte{2};
  EXPECT_THROW(parseInput(bytes.data(), bytes.size()), base::Error);  // the pan flag
  bytes.pop_back();
  EXPECT_THROW(parseInput(bytes.data(), bytes.size()), base::Error);  // cut short
  const messaging::Bytes control = packControl(Kind::Keepalive, 1, 0);
  EXPECT_THROW(parseInput(control.data(), control.size()), base::Error);
}

TEST(Protocol, LosslessBatchesRoundTripBitExactly) {
  // 150 x 100: pieces of 64x64, 64x36, 22x64, 22x36; a random and a smooth image (Snappy stores
  // the one and compresses the other).
  for (const bool smooth : {false, true})
    for (const char* codec : {"raw", "snappy"}) {
      SCOPED_TRACE(std::string(codec) + (smooth ? " smooth" : " random"));
      const CodecSpec spec = parseCodec(codec);
      const Source source = sourceImage(150, 100, smooth, 3);
      const messaging::Bytes bytes = batchOf(spec, source, 1234);
      const MessageHeader header = parseHeader(bytes.data(), bytes.size());
      EXPECT_EQ(header.kind, static_cast<std::uint16_t>(Kind::Batch));
      EXPECT_EQ(header.session, 1234u);
      std::vector<BatchPiece> pieces;
      const BatchHeader h = parseBatch(bytes.data(), bytes.size(), pieces);
      EXPECT_EQ(h.frameId, 41u);
      EXPECT_EQ(h.display, 2);
      EXPECT_EQ(h.renderRank, 5u);
      EXPECT_EQ(h.codec, spec.codec);
      EXPECT_EQ(h.pieceCount, source.pieces.size());
      ASSERT_EQ(pieces.size(), source.pieces.size());
      for (std::size_t i = 0; i < pieces.size(); ++i) {
        SCOPED_TRACE(i);
        EXPECT_EQ(pieces[i].local, source.pieces[i]);
        EXPECT_GE(pieces[i].data, bytes.data());
        EXPECT_LE(pieces[i].data + pieces[i].size, bytes.data() + bytes.size());
        if (spec.codec == Codec::Raw) {
          EXPECT_EQ(pieces[i].size, static_cast<std::size_t>(source.pieces[i].pixelCount()) * 4);
        }
        EXPECT_EQ(decodePiece(h.codec, pieces[i]), cut(source, source.pieces[i]));
      }
    }
}

TEST(Protocol, JpegBatchesRoundTripClosely) {
  for (const char* codec : {"jpeg:90:444", "jpeg:90:420"}) {
    SCOPED_TRACE(codec);
    const Source source = sourceImage(150, 100, true, 0);
    const messaging::Bytes bytes = batchOf(parseCodec(codec), source);
    std::vector<BatchPiece> pieces;
    const BatchHeader h = parseBatch(bytes.data(), bytes.size(), pieces);
    EXPECT_EQ(h.codec, Codec::Jpeg);
    ASSERT_EQ(pieces.size(), source.pieces.size());
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      EXPECT_EQ(pieces[i].local, source.pieces[i]);
      const Pixels got = decodePiece(h.codec, pieces[i]);
      const Pixels want = cut(source, source.pieces[i]);
      ASSERT_EQ(got.size(), want.size());
      for (std::size_t p = 0; p < got.size(); ++p) {
        ASSERT_EQ(got[p] >> 24, 255u);
        for (int c = 0; c < 3; ++c)
          ASSERT_NEAR(static_cast<int>((got[p] >> (8 * c)) & 0xFF),
                      static_cast<int>((want[p] >> (8 * c)) & 0xFF), 8)
              << "piece " << i << " pixel " << p << " channel " << c;
      }
    }
  }
}

TEST(Protocol, EmptyBatchAndAWriterUsedTwice) {
  BatchWriter writer;
  writer.start(5, batchHeader(Codec::Snappy));
  EXPECT_EQ(writer.pieces(), 0u);
  const messaging::Bytes empty = writer.take();
  std::vector<BatchPiece> pieces{BatchPiece{}};
  const BatchHeader h = parseBatch(empty.data(), empty.size(), pieces);
  EXPECT_EQ(h.pieceCount, 0u);
  EXPECT_TRUE(pieces.empty());

  // The same writer, a second batch: nothing of the first is left in it.
  const Source source = sourceImage(70, 10, false, 8);
  writer.start(6, batchHeader(Codec::Raw));
  for (const dfb::Region& r : source.pieces)
    writer.add(CodecSpec{Codec::Raw}, r, source.at(r), source.width);
  const messaging::Bytes second = writer.take();
  EXPECT_EQ(parseHeader(second.data(), second.size()).session, 6u);
  parseBatch(second.data(), second.size(), pieces);
  ASSERT_EQ(pieces.size(), 2u);
  EXPECT_EQ(decodePiece(Codec::Raw, pieces[1]), cut(source, source.pieces[1]));
}

TEST(Protocol, AFailedAddLeavesTheBatchAsItWas) {
  const Source source = sourceImage(16, 16, false, 2);
  BatchWriter writer;
  writer.start(1, batchHeader(Codec::Raw));
  const std::size_t before = writer.bytes();
  // An empty rectangle: the codec refuses it.
  EXPECT_THROW(writer.add(CodecSpec{Codec::Raw}, {4, 4, 4, 8}, source.at({4, 4, 5, 5}), 16),
               base::Error);
  EXPECT_EQ(writer.bytes(), before);
  EXPECT_EQ(writer.pieces(), 0u);
  writer.add(CodecSpec{Codec::Raw}, {0, 0, 16, 16}, source.pixels.data(), 16);
  const messaging::Bytes bytes = writer.take();
  std::vector<BatchPiece> pieces;
  parseBatch(bytes.data(), bytes.size(), pieces);
  ASSERT_EQ(pieces.size(), 1u);
  EXPECT_EQ(decodePiece(Codec::Raw, pieces[0]), source.pixels);
}

TEST(Protocol, PackRefusesWhatItCannotSay) {
  Hello hello;
  hello.host = std::string(kMaxStringBytes + 1, 'h');
  EXPECT_ERROR_HAS(packHello(hello), "4097 bytes");
}

// ---- hostile input ----

// Every parser on `bytes` copied into a buffer of exactly its size (ASan sees any over-read).
void expectEveryParserRefuses(const messaging::Bytes& message, const std::string& what) {
  const messaging::Bytes bytes(message);  // exactly sized
  std::vector<BatchPiece> pieces;
  EXPECT_THROW(parseHello(bytes.data(), bytes.size()), base::Error) << what;
  EXPECT_THROW(parseDirectory(bytes.data(), bytes.size()), base::Error) << what;
  EXPECT_THROW(parseText(bytes.data(), bytes.size()), base::Error) << what;
  EXPECT_THROW(parseControl(bytes.data(), bytes.size()), base::Error) << what;
  EXPECT_THROW(parseBatch(bytes.data(), bytes.size(), pieces), base::Error) << what;
}

TEST(ProtocolHostile, EmptyAndTinyMessages) {
  EXPECT_ERROR_HAS(parseHeader(nullptr, 0), "not the dfbwall protocol: a message of 0 bytes");
  std::vector<BatchPiece> pieces;
  EXPECT_ERROR_HAS(parseHello(nullptr, 0), "malformed hello");
  EXPECT_ERROR_HAS(parseDirectory(nullptr, 0), "malformed directory");
  EXPECT_ERROR_HAS(parseText(nullptr, 0), "malformed text message");
  EXPECT_ERROR_HAS(parseControl(nullptr, 0), "malformed control message");
  EXPECT_ERROR_HAS(parseBatch(nullptr, 0, pieces), "malformed piece batch");

  const messaging::Bytes three = {std::byte{'D'}, std::byte{'F'}, std::byte{'B'}};
  EXPECT_ERROR_HAS(parseHeader(three.data(), three.size()), "a message of 3 bytes");
  expectEveryParserRefuses(three, "3 bytes");
  EXPECT_ERROR_HAS(parseHello(three.data(), three.size()), "ends after 3 bytes");
}

TEST(ProtocolHostile, WrongMagic) {
  messaging::Bytes bytes = packHello(Hello{});
  bytes[0] ^= std::byte{0x20};
  EXPECT_ERROR_HAS(parseHeader(bytes.data(), bytes.size()),
                   "not the dfbwall protocol (wrong magic number)");
  // An HTTP request on the port.
  const std::string http = "GET / HTTP/1.1\r\nHost: wall\r\n\r\n";
  EXPECT_ERROR_HAS(parseHeader(reinterpret_cast<const std::byte*>(http.data()), http.size()),
                   "not the dfbwall protocol");
}

TEST(ProtocolHostile, WrongVersionNamesBothVersions) {
  for (const std::uint16_t version :
       {std::uint16_t{0}, std::uint16_t{1}, std::uint16_t{7}, std::uint16_t{0xFFFF}}) {
    messaging::Bytes bytes = packControl(Kind::Keepalive, 3, 0);
    poke(bytes, kVersionAt, version);
    const std::string message = errorOf([&] { parseHeader(bytes.data(), bytes.size()); });
    EXPECT_NE(message.find("protocol version " + std::to_string(version)), std::string::npos)
        << message;
    EXPECT_NE(message.find("speaks " + std::to_string(kProtocolVersion)), std::string::npos)
        << message;
  }
}

TEST(ProtocolHostile, UnknownKind) {
  for (const std::uint16_t kind : {std::uint16_t{0}, std::uint16_t{22}, std::uint16_t{0xFFFF}}) {
    messaging::Bytes bytes = packControl(Kind::Keepalive, 3, 0);
    poke(bytes, kKindAt, kind);
    EXPECT_ERROR_HAS(parseHeader(bytes.data(), bytes.size()),
                     "unknown message kind " + std::to_string(kind));
  }
}

TEST(ProtocolHostile, EveryTruncationOfAHello) {
  const messaging::Bytes whole = packHello(fullHello());
  for (std::size_t n = 0; n < whole.size(); ++n) {
    SCOPED_TRACE(n);
    const messaging::Bytes cut(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(n));
    if (n < kHeaderBytes) {
      EXPECT_ERROR_HAS(parseHeader(cut.data(), cut.size()), "not the dfbwall protocol");
    } else {
      EXPECT_NO_THROW(parseHeader(cut.data(), cut.size()));
    }
    EXPECT_ERROR_HAS(parseHello(cut.data(), cut.size()),
                     "malformed hello: ends after " + std::to_string(n) + " bytes");
  }
}

TEST(ProtocolHostile, EveryTruncationOfABatch) {
  for (const char* codec : {"raw", "snappy", "jpeg"}) {
    SCOPED_TRACE(codec);
    const messaging::Bytes whole = batchOf(parseCodec(codec), sourceImage(20, 12, true, 0));
    std::vector<BatchPiece> pieces;
    for (std::size_t n = 0; n < whole.size(); ++n) {
      const messaging::Bytes cut(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(n));
      const std::string message = errorOf([&] { parseBatch(cut.data(), cut.size(), pieces); });
      // Cut before the count: the header ends early; after it: the count cannot fit, or the
      // piece's data is cut.
      EXPECT_NE(message.find("malformed piece batch"), std::string::npos) << n << ": " << message;
    }
  }
}

TEST(ProtocolHostile, EveryTruncationOfTheOtherMessages) {
  for (const messaging::Bytes& whole :
       {packDirectory(twoByTwo()), packText(Kind::Refused, 1, "busy"),
        packControl(Kind::Presented, 1, 2, 3), packReshape({1, 1, 5, twoByTwo()})}) {
    const Kind kind = static_cast<Kind>(parseHeader(whole.data(), whole.size()).kind);
    for (std::size_t n = 0; n < whole.size(); ++n) {
      SCOPED_TRACE(n);
      const messaging::Bytes cut(whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(n));
      if (kind == Kind::Directory)
        EXPECT_ERROR_HAS(parseDirectory(cut.data(), cut.size()), "malformed directory");
      else if (kind == Kind::Reshape)
        EXPECT_ERROR_HAS(parseReshape(cut.data(), cut.size()), "malformed reshape");
      else if (kind == Kind::Refused)
        EXPECT_ERROR_HAS(parseText(cut.data(), cut.size()), "malformed text message");
      else
        EXPECT_ERROR_HAS(parseControl(cut.data(), cut.size()), "malformed control message");
    }
  }
}

TEST(ProtocolHostile, ABatchClaimingTwoToThe32PiecesIsRefusedBeforeAnyAllocation) {
  const Source source = sourceImage(8, 8, false, 1);
  messaging::Bytes bytes = batchOf(CodecSpec{Codec::Raw}, source);
  poke(bytes, kBatchPieceCountAt, std::numeric_limits<std::uint32_t>::max());
  std::vector<BatchPiece> pieces;
  EXPECT_ERROR_HAS(parseBatch(bytes.data(), bytes.size(), pieces), "4294967295 pieces in");
  // One more piece than there is.
  poke(bytes, kBatchPieceCountAt, std::uint32_t{2});
  EXPECT_ERROR_HAS(parseBatch(bytes.data(), bytes.size(), pieces), "malformed piece batch");
}

TEST(ProtocolHostile, APieceWhoseSizeFieldSaysFourGiB) {
  const Source source = sourceImage(8, 8, false, 1);
  for (const std::uint32_t size :
       {std::numeric_limits<std::uint32_t>::max(), std::uint32_t{1} << 31, std::uint32_t{257}}) {
    messaging::Bytes bytes = batchOf(CodecSpec{Codec::Raw}, source);
    poke(bytes, kBatchFirstRecordAt + kRecordSizeAt, size);
    std::vector<BatchPiece> pieces;
    EXPECT_ERROR_HAS(parseBatch(bytes.data(), bytes.size(), pieces),
                     std::to_string(size) + " more needed");
  }
  // A size smaller than the data: the rest is "too many" bytes, or the raw decode refuses it.
  messaging::Bytes bytes = batchOf(CodecSpec{Codec::Raw}, source);
  poke(bytes, kBatchFirstRecordAt + kRecordSizeAt, std::uint32_t{255});
  std::vector<BatchPiece> pieces;
  EXPECT_ERROR_HAS(parseBatch(bytes.data(), bytes.size(), pieces), "1 bytes too many");
}

TEST(ProtocolHostile, BadPieceRectangles) {
  constexpr int kMax = std::numeric_limits<int>::max(), kMin = std::numeric_limits<int>::min();
  const Source source = sourceImage(8, 8, false, 1);
  for (const dfb::Region r :
       {dfb::Region{-1, 0, 7, 8}, dfb::Region{0, -8, 8, 0}, dfb::Region{3, 0, 3, 8},  // empty
        dfb::Region{0, 5, 8, 5},                                                      // empty
        dfb::Region{8, 0, 0, 8},                                                      // inverted
        dfb::Region{0, 0, 4097, 1}, dfb::Region{0, 0, 1, 4097}, dfb::Region{0, 0, kMax, kMax},
        dfb::Region{kMin, kMin, kMax, kMax}, dfb::Region{kMax, 0, kMin, 1},
        dfb::Region{kMax - 1, 0, kMax, 1}}) {
    SCOPED_TRACE(std::to_string(r.x0) + "," + std::to_string(r.y0) + " " + std::to_string(r.x1) +
                 "," + std::to_string(r.y1));
    messaging::Bytes bytes = batchOf(CodecSpec{Codec::Raw}, source);
    poke(bytes, kBatchFirstRecordAt + 0, r.x0);
    poke(bytes, kBatchFirstRecordAt + 4, r.y0);
    poke(bytes, kBatchFirstRecordAt + 8, r.x1);
    poke(bytes, kBatchFirstRecordAt + 12, r.y1);
    std::vector<BatchPiece> pieces;
    if (r == dfb::Region{kMax - 1, 0, kMax, 1}) {
      // A 1x1 piece far out: the batch parses (the wall node checks it against the display),
      // and its raw data is the wrong size for one pixel.
      parseBatch(bytes.data(), bytes.size(), pieces);
      ASSERT_EQ(pieces.size(), 1u);
      EXPECT_THROW(decodePiece(Codec::Raw, pieces[0]), base::Error);
      continue;
    }
    EXPECT_ERROR_HAS(parseBatch(bytes.data(), bytes.size(), pieces),
                     "piece 0 has the rectangle [" + std::to_string(r.x0) + ", " +
                         std::to_string(r.x1) + ") x [" + std::to_string(r.y0) + ", " +
                         std::to_string(r.y1) + ")");
  }
  // The largest piece allowed is 4096 a side; the codec refuses data of the wrong size for it.
  messaging::Bytes bytes = batchOf(CodecSpec{Codec::Raw}, source);
  poke(bytes, kBatchFirstRecordAt + 8, 4096);
  poke(bytes, kBatchFirstRecordAt + 12, 4096);
  std::vector<BatchPiece> pieces;
  parseBatch(bytes.data(), bytes.size(), pieces);
  ASSERT_EQ(pieces.size(), 1u);
  EXPECT_EQ(pieces[0].local, (dfb::Region{0, 0, 4096, 4096}));
}

TEST(ProtocolHostile, AnUnknownCodecInABatch) {
  messaging::Bytes bytes = batchOf(CodecSpec{Codec::Raw}, sourceImage(8, 8, false, 1));
  poke(bytes, kHeaderBytes + 12, std::uint32_t{3});
  std::vector<BatchPiece> pieces;
  EXPECT_ERROR_HAS(parseBatch(bytes.data(), bytes.size(), pieces), "codec 3");
}

TEST(ProtocolHostile, AHelloWithA60000ByteTextLength) {
  messaging::Bytes bytes = packHello(fullHello());
  poke(bytes, kHelloTokenLengthAt, std::uint16_t{60000});
  EXPECT_ERROR_HAS(parseHello(bytes.data(), bytes.size()), "a text field longer than 4096");
  // Also when the 60000 bytes are there.
  bytes.insert(bytes.end(), 60000, std::byte{'a'});
  EXPECT_ERROR_HAS(parseHello(bytes.data(), bytes.size()), "a text field longer than 4096");
  // A length just past the message.
  bytes = packHello(fullHello());
  poke(bytes, kHelloTokenLengthAt, static_cast<std::uint16_t>(bytes.size()));
  EXPECT_ERROR_HAS(parseHello(bytes.data(), bytes.size()), "malformed hello: ends after");
}

TEST(ProtocolHostile, HelloFieldsOutOfRange) {
  const auto expectBad = [](const std::function<void(Hello&)>& change, const std::string& text) {
    Hello hello = fullHello();
    change(hello);
    const messaging::Bytes bytes = packHello(hello);
    EXPECT_ERROR_HAS(parseHello(bytes.data(), bytes.size()), text);
  };
  expectBad([](Hello& h) { h.renderRanks = 0; }, "render ranks 0");
  expectBad([](Hello& h) { h.renderRanks = 1u << 21; }, "render ranks");
  expectBad([](Hello& h) { h.tileSize = 2; }, "tile size 2");
  expectBad([](Hello& h) { h.tileSize = 1u << 20; }, "tile size");
  expectBad([](Hello& h) { h.codec.codec = static_cast<Codec>(7); }, "codec 7");
  expectBad([](Hello& h) { h.codec.jpegQuality = 0; }, "JPEG quality 0");
  expectBad([](Hello& h) { h.codec.jpegQuality = 101; }, "JPEG quality 101");
  expectBad([](Hello& h) { h.codec.subsampling = static_cast<ChromaSubsampling>(3); },
            "chroma subsampling 3");
  expectBad([](Hello& h) { h.framesInFlight = 0; }, "frames in flight 0");
  expectBad([](Hello& h) { h.framesInFlight = 17; }, "frames in flight 17");
  expectBad([](Hello& h) { h.captureEvery = (1u << 30) + 1; }, "capture-every");
  messaging::Bytes bytes = packHello(fullHello());
  // The wait flag: the byte after codec, quality and subsampling.
  const std::size_t waitAt =
      kHeaderBytes + 2 + fullHello().token.size() + 2 + fullHello().host.size() + 4 + 4 + 3;
  ASSERT_EQ(bytes[waitAt], std::byte{1});
  bytes[waitAt] = std::byte{2};
  EXPECT_ERROR_HAS(parseHello(bytes.data(), bytes.size()), "wait flag 2");
}

// A wall process checks the Start the head sends as the head checked the job's hello.
TEST(ProtocolHostile, AStartIsCheckedAsTheHelloIs) {
  ServiceCommand start;
  start.header.kind = Command::Start;
  start.header.session = 7;
  start.header.a = 1;
  start.header.tileSize = 64;
  start.header.renderRanks = 2;
  start.header.framesInFlight = 2;
  EXPECT_EQ(startProblem(start), "");
  const auto problem = [&](const std::function<void(CommandHeader&)>& change) {
    ServiceCommand bad = start;
    change(bad.header);
    return startProblem(parseCommand(packCommand(bad)));
  };
  EXPECT_EQ(problem([](CommandHeader& h) { h.tileSize = 0; }), "tile size 0 (expected 4..1024)");
  EXPECT_EQ(problem([](CommandHeader& h) { h.tileSize = 5000; }),
            "tile size 5000 (expected 4..1024)");
  EXPECT_EQ(problem([](CommandHeader& h) { h.renderRanks = 0; }),
            "render ranks 0 (expected 1..1048576)");
  EXPECT_EQ(problem([](CommandHeader& h) { h.framesInFlight = 0; }),
            "frames in flight 0 (expected 1..16)");
  EXPECT_EQ(problem([](CommandHeader& h) { h.codec = 9; }), "codec 9 (expected 0..2)");
  EXPECT_EQ(problem([](CommandHeader& h) { h.captureEvery = 0xffffffffu; }),
            "capture-every 4294967295 (expected 0..1073741824)");
  EXPECT_EQ(problem([](CommandHeader& h) { h.a = -1; }), "first frame -1 (expected 0..4294967295)");
  EXPECT_EQ(problem([](CommandHeader& h) { h.session = 0; }), "session 0");
}

TEST(ProtocolHostile, WhatAPeerSaysIsLoggedPrintableAndShort) {
  EXPECT_EQ(peerText("wall2.lab"), "wall2.lab");
  EXPECT_EQ(peerText("evil\nlost wall process 1\x1b[2J\xff"),
            "evil\\nlost wall process 1\\x1b[2J\\xff");
  EXPECT_EQ(peerText(std::string("a\0b\\", 4)), "a\\x00b\\\\");
  const std::string longName(5000, 'x');
  EXPECT_EQ(peerText(longName), std::string(80, 'x') + "... (5000 bytes)");
  EXPECT_EQ(peerText(longName, 3), "xxx... (5000 bytes)");
}

// A directory packed from a layout no loader would accept.
messaging::Bytes directoryWith(const std::function<void(Directory&)>& change) {
  Directory d = twoByTwo();
  change(d);
  return packDirectory(d);
}

TEST(ProtocolHostile, ADirectoryWhoseDisplaysOverlap) {
  const messaging::Bytes bytes = directoryWith([](Directory& d) {
    d.layout.displays[1].rect = {150, 0, 350, 150};  // 50 px over display 0
  });
  EXPECT_ERROR_HAS(parseDirectory(bytes.data(), bytes.size()), "overlaps display 'r0c0'");
}

TEST(ProtocolHostile, ADirectoryWhoseCanvasDoesNotMatch) {
  messaging::Bytes bytes = packDirectory(twoByTwo());
  poke(bytes, kDirectoryCanvasWidthAt, 413);
  EXPECT_ERROR_HAS(parseDirectory(bytes.data(), bytes.size()),
                   "its window does not match its canvas");
  poke(bytes, kDirectoryCanvasWidthAt, -412);
  EXPECT_ERROR_HAS(parseDirectory(bytes.data(), bytes.size()), "does not match");
  // A display driven by a process the directory does not list (four endpoints).
  bytes = directoryWith([](Directory& d) { d.layout.displays[3].process = 4; });
  EXPECT_ERROR_HAS(parseDirectory(bytes.data(), bytes.size()),
                   "outside its canvas or its processes");
  // A display outside the window's canvas, a window of another size than the canvas.
  bytes = directoryWith([](Directory& d) { d.layout.displays[3].rect = {212, 160, 413, 310}; });
  EXPECT_ERROR_HAS(parseDirectory(bytes.data(), bytes.size()), "outside its canvas");
  bytes = directoryWith([](Directory& d) { d.window = {0, 0, 412, 311}; });
  EXPECT_ERROR_HAS(parseDirectory(bytes.data(), bytes.size()), "its window does not match");
}

// A job in a window (wall/layout/Window.h): the directory is the window's layout, whose displays
// may leave process indices out and need not reach the canvas's corners.
TEST(Protocol, DirectoryOfAWindowRoundTrips) {
  Directory d = twoByTwo();
  const Layout wall = d.layout;
  d.window = {205, 100, 412, 300};  // r0c1 and r1c1 (processes 1 and 3), a bezel at the left
  d.layout = windowLayout(wall, d.window);
  ASSERT_EQ(d.layout.displays.size(), 2u);
  EXPECT_EQ(d.layout.displays[0].name, "r0c1");
  EXPECT_EQ(d.layout.displays[0].rect, (dfb::Region{7, 0, 207, 50}));
  EXPECT_EQ(d.layout.displays[1].name, "r1c1");
  EXPECT_EQ(d.layout.displays[1].rect, (dfb::Region{7, 60, 207, 200}));
  EXPECT_EQ(d.layout.displays[1].process, 3);
  const messaging::Bytes bytes = packDirectory(d);
  const Directory back = parseDirectory(bytes.data(), bytes.size());
  EXPECT_EQ(back.window, d.window);
  EXPECT_EQ(back.layout.canvasWidth, 207);
  EXPECT_EQ(back.layout.canvasHeight, 200);
  EXPECT_EQ(back.layout.processCount, 4);
  ASSERT_EQ(back.layout.displays.size(), 2u);
  EXPECT_EQ(back.layout.displays[1].rect, d.layout.displays[1].rect);
  EXPECT_EQ(back.layout.displays[1].process, 3);
}

TEST(Protocol, AWindowRequestIsResolvedAgainstTheWall) {
  const Layout wall = twoByTwo().layout;
  EXPECT_EQ(resolveWindow(wall, parseWindowRequest("full")), (dfb::Region{0, 0, 412, 310}));
  EXPECT_EQ(resolveWindow(wall, parseWindowRequest("")), (dfb::Region{0, 0, 412, 310}));
  EXPECT_EQ(resolveWindow(wall, parseWindowRequest("90,70,250,170")),
            (dfb::Region{90, 70, 340, 240}));
  EXPECT_EQ(resolveWindow(wall, parseWindowRequest("r1c0")), (dfb::Region{0, 160, 200, 310}));
  EXPECT_ERROR_HAS(resolveWindow(wall, parseWindowRequest("300,200,200,200")),
                   "is not inside the wall's canvas (412x310)");
  EXPECT_ERROR_HAS(resolveWindow(wall, parseWindowRequest("nope")),
                   "no display of that name (r0c0, r0c1, r1c0, r1c1)");
  EXPECT_ERROR_HAS(resolveWindow(wall, parseWindowRequest("201,151,10,8")), "touches no display");
  EXPECT_ERROR_HAS(parseWindowRequest("1,2,0,4"), "the window is empty");
  EXPECT_ERROR_HAS(parseWindowRequest("1,2,3"), "expected X,Y,W,H");
  EXPECT_ERROR_HAS(parseWindowRequest("-1,2,3,4"), "expected X,Y,W,H");
  EXPECT_ERROR_HAS(parseWindowRequest("a b"), "expected full, X,Y,W,H or a display's name");
  // From the wire: a rectangle no parser would make is refused by the wall.
  WindowRequest raw;
  raw.kind = WindowRequest::Kind::Rect;
  raw.rect = {10, 10, 5, 20};
  EXPECT_ERROR_HAS(resolveWindow(wall, raw), "empty or negative");
  raw.rect = {std::numeric_limits<int>::min(), 0, 10, 10};
  EXPECT_ERROR_HAS(resolveWindow(wall, raw), "empty or negative");
}

TEST(ProtocolHostile, AHelloWithABadWindowKind) {
  Hello hello = fullHello();
  hello.window.kind = WindowRequest::Kind::Rect;
  hello.window.rect = {1, 2, 3, 4};
  messaging::Bytes bytes = packHello(hello);
  const Hello back = parseHello(bytes.data(), bytes.size());
  EXPECT_EQ(back.window.kind, WindowRequest::Kind::Rect);
  EXPECT_EQ(back.window.rect, hello.window.rect);
  // The window kind: 20 bytes before the job and page fields (kind, rectangle, an empty name's
  // length, the reshape flag).
  const std::size_t jobAndPage = 4 + hello.job.size() + hello.page.size();
  bytes[bytes.size() - jobAndPage - 20] = std::byte{3};
  EXPECT_ERROR_HAS(parseHello(bytes.data(), bytes.size()), "window kind 3");
  bytes = packHello(hello);
  bytes[bytes.size() - jobAndPage - 1] = std::byte{2};
  EXPECT_ERROR_HAS(parseHello(bytes.data(), bytes.size()), "reshape flag 2");
}

TEST(ProtocolHostile, ADirectoryWithBadCountsOrDisplays) {
  messaging::Bytes bytes = packDirectory(twoByTwo());
  for (const std::uint32_t count : {0u, 1025u, std::numeric_limits<std::uint32_t>::max()}) {
    poke(bytes, kDirectoryDisplayCountAt, count);
    EXPECT_ERROR_HAS(parseDirectory(bytes.data(), bytes.size()),
                     std::to_string(count) + " displays");
  }
  bytes = directoryWith([](Directory& d) { d.processes.clear(); });
  EXPECT_ERROR_HAS(parseDirectory(bytes.data(), bytes.size()), "0 wall processes");
  bytes = directoryWith([](Directory& d) { d.framesInFlight = 0; });
  EXPECT_ERROR_HAS(parseDirectory(bytes.data(), bytes.size()), "frames in flight 0");
  bytes = directoryWith([](Directory& d) { d.layout.displays[2].name = "a b"; });
  EXPECT_ERROR_HAS(parseDirectory(bytes.data(), bytes.size()), "'a b' may contain only");
  bytes = directoryWith([](Directory& d) { d.layout.displays[2].process = -1; });
  EXPECT_ERROR_HAS(parseDirectory(bytes.data(), bytes.size()), "malformed directory");
  bytes = directoryWith([](Directory& d) { d.layout.displays[2].rect = {0, 0, 0, 0}; });
  EXPECT_ERROR_HAS(parseDirectory(bytes.data(), bytes.size()), "malformed directory");
  // A name length past the cap.
  bytes = packDirectory(twoByTwo());
  poke(bytes, kDirectoryFirstNameAt, std::uint16_t{60000});
  EXPECT_ERROR_HAS(parseDirectory(bytes.data(), bytes.size()), "a text field longer than 4096");
}

TEST(ProtocolHostile, ADirectoryWithExtremeRectangles) {
  constexpr int kMax = std::numeric_limits<int>::max(), kMin = std::numeric_limits<int>::min();
  for (const dfb::Region r :
       {dfb::Region{kMin, 0, kMax, 150}, dfb::Region{0, kMin, 200, kMax},
        dfb::Region{kMax, 0, kMin, 150}, dfb::Region{kMin, kMin, 0, 0},
        dfb::Region{kMax - 200, 0, kMax, 150}, dfb::Region{kMin, 0, kMin + 200, 150},
        dfb::Region{0, 0, (1 << 20) + 1, 150}}) {
    SCOPED_TRACE(std::to_string(r.x0) + "," + std::to_string(r.y0) + " " + std::to_string(r.x1) +
                 "," + std::to_string(r.y1));
    const messaging::Bytes bytes =
        directoryWith([&](Directory& d) { d.layout.displays[3].rect = r; });
    EXPECT_ERROR_HAS(parseDirectory(bytes.data(), bytes.size()), "malformed directory");
  }
}

// A wall process decodes every piece of every job on a few threads: a corrupt JPEG piece (every
// single-byte corruption of one) is refused, and the next, valid batch on the same thread still
// decodes to the same pixels.
TEST(ProtocolHostile, ACorruptJpegPieceDoesNotSpoilTheNextBatch) {
  const messaging::Bytes good = batchOf(parseCodec("jpeg:90:420"), sourceImage(20, 12, true, 0));
  std::vector<BatchPiece> pieces;
  const BatchHeader h = parseBatch(good.data(), good.size(), pieces);
  ASSERT_EQ(pieces.size(), 1u);
  const Pixels want = decodePiece(h.codec, pieces[0]);
  for (std::size_t at = kBatchFirstRecordAt + kRecordBytes; at < good.size(); ++at)
    for (const std::uint8_t x : {0x01, 0x80, 0xFF}) {
      messaging::Bytes corrupt = good;
      corrupt[at] ^= std::byte{x};
      try {
        std::vector<BatchPiece> bad;
        parseBatch(corrupt.data(), corrupt.size(), bad);
        decodePiece(h.codec, bad[0]);
      } catch (const base::Error&) {
      }
      parseBatch(good.data(), good.size(), pieces);
      Pixels got;
      ASSERT_NO_THROW(got = decodePiece(h.codec, pieces[0]))
          << "after byte " << at << " of the batch was flipped with " << int{x};
      ASSERT_EQ(got, want) << "after byte " << at << " of the batch was flipped with " << int{x};
    }
}

TEST(ProtocolHostile, TrailingGarbage) {
  std::vector<messaging::Bytes> messages = {
      packHello(fullHello()), packDirectory(twoByTwo()), packText(Kind::Queued, 2, "3"),
      packControl(Kind::Bye, 2, 9), batchOf(parseCodec("snappy"), sourceImage(8, 8, true, 0))};
  for (messaging::Bytes& bytes : messages) {
    const Kind kind = static_cast<Kind>(parseHeader(bytes.data(), bytes.size()).kind);
    for (const std::size_t extra : {std::size_t{1}, std::size_t{3}, std::size_t{1000}}) {
      messaging::Bytes longer = bytes;
      longer.insert(longer.end(), extra, std::byte{0x5A});
      const std::string tooMany = std::to_string(extra) + " bytes too many";
      std::vector<BatchPiece> pieces;
      switch (kind) {
        case Kind::Hello:
          EXPECT_ERROR_HAS(parseHello(longer.data(), longer.size()), tooMany);
          break;
        case Kind::Directory:
          EXPECT_ERROR_HAS(parseDirectory(longer.data(), longer.size()), tooMany);
          break;
        case Kind::Queued:
          EXPECT_ERROR_HAS(parseText(longer.data(), longer.size()), tooMany);
          break;
        case Kind::Bye:
          EXPECT_ERROR_HAS(parseControl(longer.data(), longer.size()), tooMany);
          break;
        default:
          EXPECT_ERROR_HAS(parseBatch(longer.data(), longer.size(), pieces), tooMany);
      }
    }
  }
}

TEST(ProtocolHostile, RandomBytesAndSingleByteCorruptions) {
  std::mt19937 random(11);
  std::vector<BatchPiece> pieces;
  const auto everyParser = [&](const messaging::Bytes& bytes) {
    // Each may accept or refuse; none may crash or throw anything but base::Error.
    const auto tryOne = [](const std::function<void()>& f) {
      try {
        f();
      } catch (const base::Error&) {
      }
    };
    tryOne([&] { parseHeader(bytes.data(), bytes.size()); });
    tryOne([&] { parseHello(bytes.data(), bytes.size()); });
    tryOne([&] { parseDirectory(bytes.data(), bytes.size()); });
    tryOne([&] { parseText(bytes.data(), bytes.size()); });
    tryOne([&] { parseControl(bytes.data(), bytes.size()); });
    tryOne([&] {
      const BatchHeader h = parseBatch(bytes.data(), bytes.size(), pieces);
      for (const BatchPiece& p : pieces)
        if (p.local.pixelCount() <= 64 * 64) decodePiece(h.codec, p);
    });
  };
  for (int i = 0; i < 200; ++i) {
    messaging::Bytes bytes(random() % 200);
    for (std::byte& b : bytes) b = static_cast<std::byte>(random());
    everyParser(bytes);
  }
  for (const messaging::Bytes& whole : {packHello(fullHello()), packDirectory(twoByTwo()),
                                        batchOf(parseCodec("snappy"), sourceImage(20, 12, true, 0)),
                                        batchOf(parseCodec("jpeg"), sourceImage(20, 12, true, 0))})
    for (std::size_t at = 0; at < whole.size(); ++at) {
      messaging::Bytes bytes = whole;
      bytes[at] ^= static_cast<std::byte>(1 + random() % 255);
      everyParser(bytes);
    }
}

// ---- fuzz seeds ----

void writeSeed(const std::filesystem::path& dir, const std::string& name,
               const messaging::Bytes& bytes) {
  std::filesystem::create_directories(dir);
  std::ofstream out(dir / name, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  ASSERT_TRUE(out.good()) << (dir / name);
}

TEST(Protocol, WritesFuzzSeeds) {
  // Without the variable the seeds go to a temporary folder, and every one must parse back: the
  // corpus generator is checked on every run, not only when someone regenerates the corpus.
  const char* root = std::getenv("DFBWALL_WRITE_FUZZ_SEEDS");
  const bool keep = root != nullptr && *root != '\0';
  const std::filesystem::path dir =
      keep ? std::filesystem::path(root)
           : std::filesystem::temp_directory_path() /
                 ("dfbwall-seeds-" +
                  std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "-" +
                  std::to_string(std::rand()));

  const std::filesystem::path hello = dir / "service_hello";
  writeSeed(hello, "hello-default", packHello(Hello{}));
  writeSeed(hello, "hello-full", packHello(fullHello()));
  Hello snappy = fullHello();
  snappy.codec = parseCodec("snappy");
  snappy.token.clear();
  snappy.wait = false;
  writeSeed(hello, "hello-snappy", packHello(snappy));
  snappy.window = parseWindowRequest("90,70,250,170");
  writeSeed(hello, "hello-window", packHello(snappy));
  snappy.window = parseWindowRequest("r1c0");
  writeSeed(hello, "hello-window-display", packHello(snappy));
  writeSeed(hello, "text-refused", packText(Kind::Refused, 0, "the wall is busy"));
  writeSeed(hello, "text-queued", packText(Kind::Queued, 5, "2"));
  writeSeed(hello, "text-ended", packText(Kind::Ended, 5, "no word from the job for 60 s"));
  writeSeed(hello, "control-keepalive", packControl(Kind::Keepalive, 5, 0));
  writeSeed(hello, "control-presented", packControl(Kind::Presented, 5, 17, 1'700'000'000'000));
  writeSeed(hello, "control-capture", packControl(Kind::Capture, 5, 3, 1));

  const std::filesystem::path batch = dir / "service_batch";
  const Source small = sourceImage(24, 20, true, 0);
  const Source noise = sourceImage(66, 20, false, 4);  // 64x20 and 2x20
  writeSeed(batch, "batch-raw", batchOf(parseCodec("raw"), small));
  writeSeed(batch, "batch-snappy-compressed", batchOf(parseCodec("snappy"), small));
  writeSeed(batch, "batch-snappy-stored", batchOf(parseCodec("snappy"), noise));
  writeSeed(batch, "batch-jpeg-420", batchOf(parseCodec("jpeg:90:420"), small));
  writeSeed(batch, "batch-jpeg-444",
            batchOf(parseCodec("jpeg:50:444"), sourceImage(9, 7, true, 0)));
  writeSeed(batch, "batch-jpeg-422-four",
            batchOf(parseCodec("jpeg:75:422"), sourceImage(80, 70, true, 0)));
  BatchWriter writer;
  writer.start(5, batchHeader(Codec::Raw));
  writeSeed(batch, "batch-empty", writer.take());

  const std::filesystem::path directory = dir / "service_directory";
  writeSeed(directory, "directory-2x2-bezels", packDirectory(twoByTwo()));
  Directory window = twoByTwo();
  window.window = {205, 100, 412, 300};
  window.layout = windowLayout(twoByTwo().layout, window.window);
  writeSeed(directory, "directory-2x2-window", packDirectory(window));
  writeSeed(directory, "directory-3x2-by-column",
            packDirectory(directoryOf(k3x2ByColumn, "3x2.toml")));
  writeSeed(directory, "directory-1x1",
            packDirectory(directoryOf("[[display]]\nname = \"main\"\norigin = [0, 0]\n"
                                      "size = [640, 480]\nprocess = 0\n",
                                      "1x1.toml")));

  int seeds = 0;
  for (const auto& folder : {hello, batch, directory})
    for (const auto& entry : std::filesystem::directory_iterator(folder)) {
      std::string text(static_cast<size_t>(std::filesystem::file_size(entry.path())), '\0');
      FILE* in = std::fopen(entry.path().c_str(), "rb");
      ASSERT_NE(in, nullptr) << entry.path();
      const size_t got = std::fread(text.data(), 1, text.size(), in);
      std::fclose(in);
      ASSERT_EQ(got, text.size()) << entry.path();
      const auto* bytes = reinterpret_cast<const std::byte*>(text.data());
      const MessageHeader h = parseHeader(bytes, text.size());
      std::vector<BatchPiece> pieces;
      if (h.kind == static_cast<std::uint16_t>(Kind::Hello)) {
        EXPECT_NO_THROW(parseHello(bytes, text.size()));
      }
      if (h.kind == static_cast<std::uint16_t>(Kind::Directory)) {
        EXPECT_NO_THROW(parseDirectory(bytes, text.size()));
      }
      if (h.kind == static_cast<std::uint16_t>(Kind::Batch)) {
        EXPECT_NO_THROW(parseBatch(bytes, text.size(), pieces));
      }
      ++seeds;
    }
  EXPECT_GE(seeds, 15);
  if (!keep) std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace wall::service
