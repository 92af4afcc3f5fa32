#include "wall/service/protocol/Protocol.h"

#include <cstring>
#include <string_view>

#include "base/Error.h"
#include "wall/service/protocol/WireFormat.h"

namespace wall::service {
namespace {

constexpr std::uint32_t kMaxRanks = 1 << 20;

DirectoryProcess readProcess(Reader& r, std::uint32_t index) {
  DirectoryProcess p;
  p.endpoint = r.text();
  const auto live = r.get<std::uint8_t>();
  if (live > 1)
    r.fail("process " + std::to_string(index) + " has the live flag " + std::to_string(live));
  p.live = live == 1;
  if (p.live && p.endpoint.empty())
    r.fail("live process " + std::to_string(index) + " has no endpoint");
  return p;
}

}  // namespace

std::string jobFieldsProblem(const JobFields& f) {
  const auto outside = [](const char* field, std::uint32_t value, std::uint32_t low,
                          std::uint32_t high) {
    return field + (" " + std::to_string(value)) + " (expected " + std::to_string(low) + ".." +
           std::to_string(high) + ")";
  };
  if (f.renderRanks < 1 || f.renderRanks > kMaxRanks)
    return outside("render ranks", f.renderRanks, 1, kMaxRanks);
  if (f.tileSize < 4 || f.tileSize > 1024) return outside("tile size", f.tileSize, 4, 1024);
  if (f.codec > static_cast<std::uint32_t>(Codec::Jpeg))
    return outside("codec", f.codec, 0, static_cast<std::uint32_t>(Codec::Jpeg));
  if (f.framesInFlight < 1 || f.framesInFlight > 16)
    return outside("frames in flight", f.framesInFlight, 1, 16);
  if (f.captureEvery > (1u << 30)) return outside("capture-every", f.captureEvery, 0, 1u << 30);
  return {};
}

messaging::Bytes packHello(const Hello& h) {
  Writer w(Kind::Hello, 0);
  w.text(h.token);
  w.text(h.host);
  w.put<std::uint32_t>(h.renderRanks);
  w.put<std::uint32_t>(h.tileSize);
  w.put<std::uint8_t>(static_cast<std::uint8_t>(h.codec.codec));
  w.put<std::uint8_t>(static_cast<std::uint8_t>(h.codec.jpegQuality));
  w.put<std::uint8_t>(static_cast<std::uint8_t>(h.codec.subsampling));
  w.put<std::uint8_t>(h.wait ? 1 : 0);
  w.put<std::uint32_t>(h.framesInFlight);
  w.text(h.captureDir);
  w.put<std::uint32_t>(h.captureEvery);
  w.put<std::uint8_t>(static_cast<std::uint8_t>(h.window.kind));
  w.put<std::int32_t>(h.window.rect.x0);
  w.put<std::int32_t>(h.window.rect.y0);
  w.put<std::int32_t>(h.window.rect.x1);
  w.put<std::int32_t>(h.window.rect.y1);
  w.text(h.window.display);
  w.put<std::uint8_t>(h.canReshape ? 1 : 0);
  w.text(h.job);
  w.text(h.page);
  return w.take();
}

Hello parseHello(const std::byte* data, std::size_t size) {
  Reader r(data, size, "hello");
  Hello h;
  h.token = r.text();
  h.host = r.text();
  h.renderRanks = r.get<std::uint32_t>();
  h.tileSize = r.get<std::uint32_t>();
  const auto codec = r.get<std::uint8_t>();
  const auto quality = r.get<std::uint8_t>();
  const auto subsampling = r.get<std::uint8_t>();
  const auto wait = r.get<std::uint8_t>();
  h.framesInFlight = r.get<std::uint32_t>();
  h.captureDir = r.text();
  h.captureEvery = r.get<std::uint32_t>();
  const auto window = r.get<std::uint8_t>();
  h.window.rect.x0 = r.get<std::int32_t>();
  h.window.rect.y0 = r.get<std::int32_t>();
  h.window.rect.x1 = r.get<std::int32_t>();
  h.window.rect.y1 = r.get<std::int32_t>();
  h.window.display = r.text();
  const auto canReshape = r.get<std::uint8_t>();
  h.job = r.text();
  h.page = r.text();
  r.end();
  if (canReshape > 1) r.fail("reshape flag " + std::to_string(canReshape));
  h.canReshape = canReshape == 1;
  // The rectangle and the name are judged against the layout by the wall (resolveWindow).
  if (window > static_cast<std::uint8_t>(WindowRequest::Kind::Display))
    r.fail("window kind " + std::to_string(window));
  h.window.kind = static_cast<WindowRequest::Kind>(window);
  if (const std::string problem =
          jobFieldsProblem({h.renderRanks, h.tileSize, codec, h.framesInFlight, h.captureEvery});
      !problem.empty())
    r.fail(problem);
  if (quality < 1 || quality > 100) r.fail("JPEG quality " + std::to_string(quality));
  if (subsampling > static_cast<std::uint8_t>(ChromaSubsampling::S420))
    r.fail("chroma subsampling " + std::to_string(subsampling));
  if (wait > 1) r.fail("wait flag " + std::to_string(wait));
  h.codec.codec = static_cast<Codec>(codec);
  h.codec.jpegQuality = quality;
  h.codec.subsampling = static_cast<ChromaSubsampling>(subsampling);
  h.wait = wait == 1;
  return h;
}

namespace {

// A directory's fields after its header (the session is the header's): for Directory and,
// with a new window, Reshape.
void writeDirectory(Writer& w, const Directory& d) {
  w.put<std::int32_t>(d.layout.canvasWidth);
  w.put<std::int32_t>(d.layout.canvasHeight);
  w.put<std::uint32_t>(static_cast<std::uint32_t>(d.layout.displays.size()));
  for (const Display& display : d.layout.displays) {
    w.text(display.name);
    w.put<std::int32_t>(display.rect.x0);
    w.put<std::int32_t>(display.rect.y0);
    w.put<std::int32_t>(display.rect.x1);
    w.put<std::int32_t>(display.rect.y1);
    w.put<std::int32_t>(display.process);
  }
  w.put<std::uint32_t>(static_cast<std::uint32_t>(d.processes.size()));
  for (const DirectoryProcess& p : d.processes) {
    w.text(p.endpoint);
    w.put<std::uint8_t>(p.live ? 1 : 0);
  }
  w.put<std::uint32_t>(d.framesInFlight);
  w.put<std::uint32_t>(d.timeoutMs);
  w.put<std::uint32_t>(d.rosterVersion);
  w.text(d.layout.file);
  w.put<std::int32_t>(d.window.x0);
  w.put<std::int32_t>(d.window.y0);
  w.put<std::int32_t>(d.window.x1);
  w.put<std::int32_t>(d.window.y1);
}

void readDirectory(Reader& r, Directory& d) {
  const auto width = r.get<std::int32_t>(), height = r.get<std::int32_t>();
  const auto displays = r.get<std::uint32_t>();
  if (displays < 1 || displays > static_cast<std::uint32_t>(kMaxDisplays))
    r.fail(std::to_string(displays) + " displays");
  for (std::uint32_t i = 0; i < displays; ++i) {
    Display display;
    display.name = r.text();
    display.rect.x0 = r.get<std::int32_t>();
    display.rect.y0 = r.get<std::int32_t>();
    display.rect.x1 = r.get<std::int32_t>();
    display.rect.y1 = r.get<std::int32_t>();
    display.process = r.get<std::int32_t>();
    // Checked in 64 bits before anything computes a width or moves the rectangle: a side
    // of INT_MAX - INT_MIN would overflow an int in computeCanvas and validateLayout.
    if (!dfb::isSaneRegion(display.rect, kMaxCanvasSide))
      r.fail("display " + std::to_string(i) + " has the rectangle [" +
             std::to_string(display.rect.x0) + ", " + std::to_string(display.rect.x1) + ") x [" +
             std::to_string(display.rect.y0) + ", " + std::to_string(display.rect.y1) + ")");
    d.layout.displays.push_back(std::move(display));
  }
  const auto processes = r.get<std::uint32_t>();
  if (processes < 1 || processes > static_cast<std::uint32_t>(kMaxDisplays))
    r.fail(std::to_string(processes) + " wall processes");
  for (std::uint32_t i = 0; i < processes; ++i) d.processes.push_back(readProcess(r, i));
  d.framesInFlight = r.get<std::uint32_t>();
  d.timeoutMs = r.get<std::uint32_t>();
  d.rosterVersion = r.get<std::uint32_t>();
  d.layout.file = r.text();
  d.window.x0 = r.get<std::int32_t>();
  d.window.y0 = r.get<std::int32_t>();
  d.window.x1 = r.get<std::int32_t>();
  d.window.y1 = r.get<std::int32_t>();
  if (d.framesInFlight < 1 || d.framesInFlight > 16)
    r.fail("frames in flight " + std::to_string(d.framesInFlight));
  if (d.window.x0 < 0 || d.window.y0 < 0 || !dfb::isSaneRegion(d.window, kMaxCanvasSide) ||
      width != d.window.width() || height != d.window.height())
    r.fail("its window does not match its canvas (" + std::to_string(width) + "x" +
           std::to_string(height) + ")");
  // The same checks as a layout file gets (process indices may leave gaps: a window touches
  // some displays only); every display inside the window's canvas, every process index named.
  if (const Problems problems = validateLayout(d.layout, true); !problems.empty())
    r.fail("its layout: " + joinProblems(problems));
  for (const Display& display : d.layout.displays)
    if (display.rect.x0 < 0 || display.rect.y0 < 0 || display.rect.x1 > width ||
        display.rect.y1 > height || display.process >= static_cast<int>(processes))
      r.fail("display '" + display.name + "' lies outside its canvas or its processes");
  d.layout.canvasWidth = width;
  d.layout.canvasHeight = height;
  d.layout.processCount = static_cast<int>(processes);
}

}  // namespace

messaging::Bytes packDirectory(const Directory& d) {
  Writer w(Kind::Directory, d.session);
  writeDirectory(w, d);
  return w.take();
}

Directory parseDirectory(const std::byte* data, std::size_t size) {
  Reader r(data, size, "directory");
  Directory d;
  d.session = parseHeader(data, size).session;
  readDirectory(r, d);
  r.end();
  return d;
}

messaging::Bytes packReshape(const Reshape& reshape) {
  Writer w(Kind::Reshape, reshape.session);
  w.put<std::uint32_t>(reshape.version);
  w.put<std::uint32_t>(reshape.fromFrame);
  w.put<std::uint64_t>(reshape.directory.session);
  writeDirectory(w, reshape.directory);
  return w.take();
}

Reshape parseReshape(const std::byte* data, std::size_t size) {
  Reader r(data, size, "reshape");
  Reshape reshape;
  reshape.session = parseHeader(data, size).session;
  reshape.version = r.get<std::uint32_t>();
  reshape.fromFrame = r.get<std::uint32_t>();
  reshape.directory.session = r.get<std::uint64_t>();
  readDirectory(r, reshape.directory);
  r.end();
  if (reshape.version == 0) r.fail("version 0");
  if (reshape.fromFrame == 0) r.fail("switch frame 0");
  if (reshape.directory.session == 0 || reshape.directory.session == reshape.session)
    r.fail("its piece session is 0 or the job's own");
  return reshape;
}

messaging::Bytes packRoster(const Roster& roster) {
  Writer w(Kind::Roster, roster.session);
  w.put<std::uint32_t>(roster.version);
  w.put<std::uint32_t>(roster.fromFrame);
  w.put<std::uint32_t>(static_cast<std::uint32_t>(roster.processes.size()));
  for (const DirectoryProcess& p : roster.processes) {
    w.text(p.endpoint);
    w.put<std::uint8_t>(p.live ? 1 : 0);
  }
  w.text(roster.why.size() > kMaxStringBytes ? roster.why.substr(0, kMaxStringBytes) : roster.why);
  return w.take();
}

Roster parseRoster(const std::byte* data, std::size_t size) {
  Reader r(data, size, "roster");
  Roster roster;
  roster.session = parseHeader(data, size).session;
  roster.version = r.get<std::uint32_t>();
  roster.fromFrame = r.get<std::uint32_t>();
  const auto processes = r.get<std::uint32_t>();
  if (processes < 1 || processes > static_cast<std::uint32_t>(kMaxDisplays))
    r.fail(std::to_string(processes) + " wall processes");
  for (std::uint32_t i = 0; i < processes; ++i) roster.processes.push_back(readProcess(r, i));
  roster.why = r.text();
  r.end();
  return roster;
}

messaging::Bytes packText(Kind kind, std::uint64_t session, const std::string& text) {
  Writer w(kind, session);
  w.text(text.size() > kMaxStringBytes ? text.substr(0, kMaxStringBytes) : text);
  return w.take();
}

std::string parseText(const std::byte* data, std::size_t size) {
  Reader r(data, size, "text message");
  std::string s = r.text();
  r.end();
  return s;
}

messaging::Bytes packControl(Kind kind, std::uint64_t session, std::uint64_t value,
                             std::int64_t second) {
  Writer w(kind, session);
  w.put(value);
  w.put(second);
  return w.take();
}

messaging::Bytes packInput(std::uint64_t session, const WindowInput& in) {
  Writer w(Kind::Input, session);
  w.put<std::uint32_t>(in.kind);
  w.put<std::uint32_t>(in.key);
  w.put<std::int32_t>(in.x);
  w.put<std::int32_t>(in.y);
  w.put<std::int32_t>(in.dx);
  w.put<std::int32_t>(in.dy);
  w.put<std::uint8_t>(in.pan ? 1 : 0);
  return w.take();
}

WindowInput parseInput(const std::byte* data, std::size_t size) {
  Reader r(data, size, "input event");
  if (parseHeader(data, size).kind != static_cast<std::uint16_t>(Kind::Input))
    r.fail("not an input event");
  WindowInput in;
  in.kind = r.get<std::uint32_t>();
  in.key = r.get<std::uint32_t>();
  in.x = r.get<std::int32_t>();
  in.y = r.get<std::int32_t>();
  in.dx = r.get<std::int32_t>();
  in.dy = r.get<std::int32_t>();
  const auto pan = r.get<std::uint8_t>();
  r.end();
  if (in.kind < WindowInput::kKey || in.kind > WindowInput::kScroll)
    r.fail("kind " + std::to_string(in.kind) + " (expected 1..3)");
  if (in.kind == WindowInput::kKey && in.key >= WindowInput::kKeyCount)
    r.fail("key " + std::to_string(in.key) + " (expected 0.." +
           std::to_string(WindowInput::kKeyCount - 1) + ")");
  if (in.dx < -kMaxInputMove || in.dx > kMaxInputMove || in.dy < -kMaxInputMove ||
      in.dy > kMaxInputMove)
    r.fail("move " + std::to_string(in.dx) + "," + std::to_string(in.dy) + " (at most " +
           std::to_string(kMaxInputMove) + " a side)");
  if (pan > 1) r.fail("pan flag " + std::to_string(pan));
  in.pan = pan == 1;
  return in;
}

Control parseControl(const std::byte* data, std::size_t size) {
  Reader r(data, size, "control message");
  Control c;
  c.value = r.get<std::uint64_t>();
  c.second = r.get<std::int64_t>();
  r.end();
  return c;
}

MessageHeader parseHeader(const std::byte* data, std::size_t size) {
  MessageHeader h;
  if (size < sizeof h)
    throw base::Error("not the dfbwall protocol: a message of " + std::to_string(size) + " bytes");
  std::memcpy(&h, data, sizeof h);
  if (h.magic != kMagic) throw base::Error("not the dfbwall protocol (wrong magic number)");
  if (h.version != kProtocolVersion)
    throw base::Error("protocol version " + std::to_string(h.version) + ", this side speaks " +
                      std::to_string(kProtocolVersion) + ": use the same dfbwall on both sides");
  if (h.kind < static_cast<std::uint16_t>(Kind::Hello) ||
      h.kind > static_cast<std::uint16_t>(kLastKind))
    throw base::Error("unknown message kind " + std::to_string(h.kind));
  return h;
}

void BatchWriter::start(std::uint64_t session, const BatchHeader& header) {
  Writer w(Kind::Batch, session);
  w.put<std::uint32_t>(header.frameId);
  w.put<std::int32_t>(header.display);
  w.put<std::uint32_t>(header.renderRank);
  w.put<std::uint32_t>(static_cast<std::uint32_t>(header.codec));
  w.put<std::uint32_t>(0);  // piece count, set by take()
  bytes_ = w.take();
  pieces_ = 0;
}

namespace {
constexpr std::size_t kBatchHeaderBytes = sizeof(MessageHeader) + 5 * sizeof(std::uint32_t);
constexpr std::size_t kPieceCountAt = kBatchHeaderBytes - sizeof(std::uint32_t);
struct PieceRecord {
  std::int32_t x0, y0, x1, y1;
  std::uint32_t size;
};
constexpr int kMaxPieceSide = 4096;
static_assert(sizeof(PieceRecord) == kPieceRecordBytes, "the piece record is part of the protocol");
}  // namespace

void BatchWriter::add(const CodecSpec& codec, const dfb::Region& local, const std::uint32_t* pixels,
                      int stride) {
  // Encoded aside first: a piece the codec refuses never leaves half a record in the batch.
  thread_local messaging::Bytes piece;
  encodePiece(codec, local, pixels, stride, piece);
  append(piece);
}

void BatchWriter::append(const messaging::Bytes& piece) {
  bytes_.insert(bytes_.end(), piece.begin(), piece.end());
  ++pieces_;
}

void encodePiece(const CodecSpec& codec, const dfb::Region& local, const std::uint32_t* pixels,
                 int stride, messaging::Bytes& out) {
  PieceRecord record{local.x0, local.y0, local.x1, local.y1, 0};
  out.resize(sizeof record);
  encodePixels(codec, pixels, local.width(), local.height(), stride, out);
  record.size = static_cast<std::uint32_t>(out.size() - sizeof record);
  std::memcpy(out.data(), &record, sizeof record);
}

messaging::Bytes BatchWriter::take() {
  std::memcpy(bytes_.data() + kPieceCountAt, &pieces_, sizeof pieces_);
  pieces_ = 0;
  return std::move(bytes_);
}

BatchHeader parseBatch(const std::byte* data, std::size_t size, std::vector<BatchPiece>& pieces) {
  Reader r(data, size, "piece batch");
  BatchHeader h;
  h.frameId = r.get<std::uint32_t>();
  h.display = r.get<std::int32_t>();
  h.renderRank = r.get<std::uint32_t>();
  const auto codec = r.get<std::uint32_t>();
  h.pieceCount = r.get<std::uint32_t>();
  if (codec > static_cast<std::uint32_t>(Codec::Jpeg)) r.fail("codec " + std::to_string(codec));
  h.codec = static_cast<Codec>(codec);
  // Every piece takes at least its record: a count the message cannot hold is refused before
  // anything is reserved for it.
  if (h.pieceCount > r.left() / sizeof(PieceRecord))
    r.fail(std::to_string(h.pieceCount) + " pieces in " + std::to_string(size) + " bytes");
  pieces.clear();
  pieces.reserve(h.pieceCount);
  for (std::uint32_t i = 0; i < h.pieceCount; ++i) {
    PieceRecord record;
    r.raw(&record, sizeof record);
    const dfb::Region local{record.x0, record.y0, record.x1, record.y1};
    if (local.x0 < 0 || local.y0 < 0 || local.x1 <= local.x0 || local.y1 <= local.y0 ||
        local.x1 - local.x0 > kMaxPieceSide || local.y1 - local.y0 > kMaxPieceSide)
      r.fail("piece " + std::to_string(i) + " has the rectangle [" + std::to_string(local.x0) +
             ", " + std::to_string(local.x1) + ") x [" + std::to_string(local.y0) + ", " +
             std::to_string(local.y1) + ")");
    pieces.push_back({local, r.span(record.size), record.size});
  }
  r.end();
  return h;
}

}  // namespace wall::service
