#include "wall/route/PreviewAssembler.h"

#include <algorithm>
#include <cstring>
#include <string>

#include "base/Error.h"
#include "wall/route/PreviewOp.h"

namespace wall {
namespace {
std::vector<bool> checkedMask(std::vector<bool> tilesOfFrame, const dfb::TileGrid& tiles) {
  if (static_cast<int>(tilesOfFrame.size()) != tiles.tileCount())
    throw base::Error("preview: the tile mask does not match the canvas's tiles");
  return tilesOfFrame;
}
int countOf(const std::vector<bool>& mask) {
  return static_cast<int>(std::count(mask.begin(), mask.end(), true));
}
}  // namespace

PreviewAssembler::PreviewAssembler(messaging::Messenger& messenger, PreviewGrid grid, int tileSize,
                                   std::vector<bool> tilesOfFrame)
    : messenger_(messenger),
      grid_(grid),
      tiles_(grid.canvasWidth, grid.canvasHeight, tileSize),
      tilesOfFrame_(checkedMask(std::move(tilesOfFrame), tiles_)),
      tilesPerFrame_(countOf(tilesOfFrame_)),
      latest_(std::make_shared<Snapshot>(Snapshot{0, grid, Image(grid.width(), grid.height())})) {
  messenger_.registerObject(kPreviewObject, this);
}

PreviewAssembler::~PreviewAssembler() { messenger_.unregisterObject(kPreviewObject); }

std::shared_ptr<const PreviewAssembler::Snapshot> PreviewAssembler::latest() const {
  std::lock_guard lock(mutex_);
  return latest_;
}

PreviewGrid PreviewAssembler::grid() const {
  std::lock_guard lock(mutex_);
  return grid_;
}

std::uint64_t PreviewAssembler::framesGivenUp() const {
  std::lock_guard lock(mutex_);
  return framesGivenUp_;
}

void PreviewAssembler::restart(PreviewGrid grid, int tileSize, std::vector<bool> tilesOfFrame,
                               std::uint32_t fromFrame) {
  dfb::TileGrid tiles(grid.canvasWidth, grid.canvasHeight, tileSize);
  tilesOfFrame = checkedMask(std::move(tilesOfFrame), tiles);
  std::lock_guard lock(mutex_);
  grid_ = grid;
  tiles_ = tiles;
  tilesOfFrame_ = std::move(tilesOfFrame);
  tilesPerFrame_ = countOf(tilesOfFrame_);
  pending_.clear();
  const std::uint32_t before = fromFrame > 0 ? fromFrame - 1 : 0;
  latest_ = std::make_shared<Snapshot>(Snapshot{before, grid, Image(grid.width(), grid.height())});
  givenUpThrough_ = std::max(givenUpThrough_, before);
  published_.notify_all();
}

bool PreviewAssembler::waitFor(std::uint32_t frame,
                               std::chrono::steady_clock::time_point deadline) const {
  std::unique_lock lock(mutex_);
  return published_.wait_until(lock, deadline, [&] { return latest_->frame >= frame; });
}

PreviewAssembler::Assembly* PreviewAssembler::assemblyOf(std::uint32_t frame) {
  auto it = pending_.find(frame);
  if (it != pending_.end()) return &it->second;
  // A new frame beyond the frames kept: the oldest is given up (it may be this one).
  if (pending_.size() >= kFramesKept) {
    const std::uint32_t oldest = std::min(pending_.begin()->first, frame);
    if (oldest == frame) {
      givenUpThrough_ = std::max(givenUpThrough_, frame);
      ++framesGivenUp_;
      return nullptr;
    }
    pending_.erase(pending_.begin());
    givenUpThrough_ = std::max(givenUpThrough_, oldest);
    ++framesGivenUp_;
  }
  Assembly& a = pending_[frame];
  const size_t cells = static_cast<size_t>(grid_.width()) * static_cast<size_t>(grid_.height());
  a.sums.assign(4 * cells, 0);
  a.weights.assign(cells, 0);
  a.seen.assign(tilesOfFrame_.size(), false);
  a.missing = tilesPerFrame_;
  return &a;
}

void PreviewAssembler::incoming(int fromRank, messaging::Bytes&& payload) {
  PreviewHeader h;
  if (payload.size() < sizeof h)
    throw base::Error("preview message from rank " + std::to_string(fromRank) + " is too short");
  std::memcpy(&h, payload.data(), sizeof h);
  if (h.magic != kPreviewMagic)
    throw base::Error("malformed preview message from rank " + std::to_string(fromRank) +
                      " (bad magic)");

  std::lock_guard lock(mutex_);
  // A newer frame is out already, or the frame was given up, or it is of the canvas before a
  // restart: nobody wants it.
  if (h.frameId <= std::max(latest_->frame, givenUpThrough_)) return;
  const dfb::Region region{h.x0, h.y0, h.x1, h.y1};
  const int tile =
      dfb::isSaneRegion(region, kMaxCanvasSide) ? tiles_.indexOfOrigin(h.x0, h.y0) : -1;
  if (tile < 0 || tiles_.region(tile) != region || !tilesOfFrame_[static_cast<size_t>(tile)])
    throw base::Error("malformed preview message from rank " + std::to_string(fromRank) +
                      " (a rectangle that is no tile of the frame)");
  const dfb::Region cells = grid_.cellsOf(region);
  if (payload.size() != sizeof h + 4 * static_cast<size_t>(cells.pixelCount()))
    throw base::Error("preview message from rank " + std::to_string(fromRank) + " has " +
                      std::to_string(payload.size() - sizeof h) + " cell bytes, its tile needs " +
                      std::to_string(4 * cells.pixelCount()));
  std::vector<std::uint32_t> values(static_cast<size_t>(cells.pixelCount()));
  std::memcpy(values.data(), payload.data() + sizeof h, 4 * values.size());

  Assembly* found = assemblyOf(h.frameId);
  if (!found) return;
  Assembly& a = *found;
  if (a.seen[static_cast<size_t>(tile)])
    throw base::Error("preview of tile " + std::to_string(tile) + " of frame " +
                      std::to_string(h.frameId) + " arrived twice");
  a.seen[static_cast<size_t>(tile)] = true;
  for (int cy = cells.y0; cy < cells.y1; ++cy)
    for (int cx = cells.x0; cx < cells.x1; ++cx) {
      const dfb::Region part = dfb::intersect(grid_.cellPixels(cx, cy), region);
      const auto w = static_cast<std::uint32_t>(part.pixelCount());
      const std::uint32_t v =
          values[static_cast<size_t>((cy - cells.y0) * cells.width() + (cx - cells.x0))];
      const size_t cell =
          static_cast<size_t>(cy) * static_cast<size_t>(grid_.width()) + static_cast<size_t>(cx);
      for (size_t c = 0; c < 4; ++c) a.sums[4 * cell + c] += (v >> (8 * c) & 0xff) * w;
      a.weights[cell] += w;
    }
  if (--a.missing == 0) publish(h.frameId, a);
}

void PreviewAssembler::publish(std::uint32_t frame, const Assembly& a) {
  auto snapshot = std::make_shared<Snapshot>();
  snapshot->frame = frame;
  snapshot->grid = grid_;
  snapshot->image = Image(grid_.width(), grid_.height());
  for (size_t cell = 0; cell < a.weights.size(); ++cell) {
    const std::uint32_t w = a.weights[cell];
    if (w == 0) continue;  // no tile covers it: no display shows it
    std::uint32_t p = 0;
    for (size_t c = 0; c < 4; ++c) p |= (a.sums[4 * cell + c] + w / 2) / w << (8 * c);
    snapshot->image.pixels[cell] = p;
  }
  latest_ = std::move(snapshot);
  // This frame and every older one are done with.
  pending_.erase(pending_.begin(), pending_.upper_bound(frame));
  published_.notify_all();
}

}  // namespace wall
