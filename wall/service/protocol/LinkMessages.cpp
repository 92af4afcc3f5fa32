#include "wall/service/protocol/LinkMessages.h"

#include "wall/service/protocol/WireFormat.h"

namespace wall::service {
namespace {
constexpr std::uint32_t kMaxBarrierValues = 16;
}

messaging::Bytes packJoin(const Join& j) {
  Writer w(Kind::Join, 0);
  w.text(j.token);
  w.put<std::uint32_t>(j.process);
  w.text(j.host);
  w.text(j.pieceEndpoint);
  w.put<std::uint64_t>(j.layoutHash);
  w.put<std::uint64_t>(j.incarnation);
  return w.take();
}

Join parseJoin(const std::byte* data, std::size_t size) {
  Reader r(data, size, "join");
  Join j;
  j.token = r.text();
  j.process = r.get<std::uint32_t>();
  j.host = r.text();
  j.pieceEndpoint = r.text();
  j.layoutHash = r.get<std::uint64_t>();
  j.incarnation = r.get<std::uint64_t>();
  r.end();
  if (j.pieceEndpoint.rfind("tcp://", 0) != 0) r.fail("piece endpoint '" + j.pieceEndpoint + "'");
  return j;
}

std::uint64_t layoutHash(const Layout& layout) {
  std::uint64_t hash = 0xcbf29ce484222325ull;
  const auto mix = [&hash](const void* p, std::size_t n) {
    const auto* bytes = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) hash = (hash ^ bytes[i]) * 0x100000001b3ull;
  };
  const std::int32_t head[3] = {layout.canvasWidth, layout.canvasHeight, layout.processCount};
  mix(head, sizeof head);
  for (const Display& d : layout.displays) {
    mix(d.name.data(), d.name.size() + 1);
    const std::int32_t fields[5] = {d.rect.x0, d.rect.y0, d.rect.x1, d.rect.y1, d.process};
    mix(fields, sizeof fields);
  }
  return hash;
}

messaging::Bytes packBarrier(std::uint64_t session, const BarrierValues& b) {
  Writer w(Kind::Barrier, session);
  w.put<std::uint32_t>(b.frameId);
  w.put<std::uint32_t>(static_cast<std::uint32_t>(b.values.size()));
  for (std::int64_t v : b.values) w.put(v);
  return w.take();
}

BarrierValues parseBarrier(const std::byte* data, std::size_t size) {
  Reader r(data, size, "barrier");
  BarrierValues b;
  b.frameId = r.get<std::uint32_t>();
  const auto count = r.get<std::uint32_t>();
  if (count < 1 || count > kMaxBarrierValues) r.fail(std::to_string(count) + " values");
  for (std::uint32_t i = 0; i < count; ++i) b.values.push_back(r.get<std::int64_t>());
  r.end();
  return b;
}

messaging::Bytes packPixels(std::uint64_t session, std::uint32_t frameId,
                            const std::vector<std::uint32_t>& pixels) {
  Writer w(Kind::Pixels, session);
  w.put<std::uint32_t>(frameId);
  w.put<std::uint64_t>(pixels.size());
  w.raw(pixels.data(), pixels.size() * sizeof(std::uint32_t));
  return w.take();
}

CapturePixels parsePixels(const std::byte* data, std::size_t size) {
  Reader r(data, size, "captured pixels");
  CapturePixels c;
  c.frameId = r.get<std::uint32_t>();
  const auto count = r.get<std::uint64_t>();
  if (count != r.left() / sizeof(std::uint32_t) || r.left() % sizeof(std::uint32_t) != 0)
    r.fail(std::to_string(count) + " pixels in " + std::to_string(r.left()) + " bytes");
  c.pixels.resize(count);
  r.raw(c.pixels.data(), count * sizeof(std::uint32_t));
  r.end();
  return c;
}

messaging::Bytes packThumbnail(std::uint64_t session, const ThumbnailPart& part) {
  Writer w(Kind::Thumbnail, session);
  w.put<std::uint32_t>(part.request);
  for (const int v : {part.window.x0, part.window.y0, part.window.x1, part.window.y1})
    w.put<std::int32_t>(v);
  const dfb::Region& c = part.cells.cells;
  for (const int v : {c.x0, c.y0, c.x1, c.y1}) w.put<std::int32_t>(v);
  w.raw(part.cells.sums.data(), part.cells.sums.size() * sizeof(std::uint32_t));
  return w.take();
}

ThumbnailPart parseThumbnail(const std::byte* data, std::size_t size) {
  Reader r(data, size, "thumbnail");
  ThumbnailPart t;
  t.request = r.get<std::uint32_t>();
  int v[8];
  for (int& each : v) each = r.get<std::int32_t>();
  t.window = {v[0], v[1], v[2], v[3]};
  const dfb::Region cells{v[4], v[5], v[6], v[7]};
  // Canvases are at most 2^20 pixels a side (docs/design.md, "Hostile input").
  if (!dfb::isSaneRegion(t.window, 1 << 20) || t.window.x0 < 0 || t.window.y0 < 0)
    r.fail("window " + std::to_string(v[0]) + "," + std::to_string(v[1]) + " to " +
           std::to_string(v[2]) + "," + std::to_string(v[3]));
  const ThumbnailGrid grid = thumbnailGrid(t.window.width(), t.window.height(), kMaxThumbnailSide);
  // The largest grid any thumbnail size gives (the head checks its own).
  if (!dfb::isSaneRegion(cells, kMaxThumbnailSide) || cells.x0 < 0 || cells.y0 < 0 ||
      cells.x1 > grid.width || cells.y1 > grid.height)
    r.fail("cells " + std::to_string(v[4]) + "," + std::to_string(v[5]) + " to " +
           std::to_string(v[6]) + "," + std::to_string(v[7]));
  const std::size_t count = static_cast<std::size_t>(cells.pixelCount()) * CellSums::kChannels;
  if (r.left() != count * sizeof(std::uint32_t))
    r.fail(std::to_string(cells.pixelCount()) + " cells in " + std::to_string(r.left()) + " bytes");
  t.cells = emptySums(cells);
  r.raw(t.cells.sums.data(), count * sizeof(std::uint32_t));
  r.end();
  return t;
}

messaging::Bytes packCommandMessage(std::uint64_t session, const messaging::Bytes& body) {
  Writer w(Kind::Command, session);
  w.raw(body.data(), body.size());
  return w.take();
}

messaging::Bytes commandBody(const std::byte* data, std::size_t size) {
  Reader r(data, size, "command");
  const std::byte* body = r.span(r.left());
  return messaging::Bytes(body, body + (size - sizeof(MessageHeader)));
}

}  // namespace wall::service
