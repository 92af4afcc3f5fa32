#include "dfb/DistributedFrameBuffer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <limits>
#include <map>
#include <mutex>
#include <string>

#include "base/Collectives.h"
#include "base/Error.h"
#include "base/Timing.h"
#include "dfb/ImageGather.h"
#include "dfb/TileDoor.h"
#include "dfb/TileMessage.h"

namespace dfb {

int roundRobinOwner(int tileIndex, int, int ranks) { return tileIndex % ranks; }

// What the owner keeps per tile: the live operation and the final pixels of the last frame.
struct OwnedTile {
  std::mutex mutex;
  std::unique_ptr<TileOperation> operation;
  std::vector<std::uint32_t> rgba8;
  // What the door (dfb/TileDoor.h) checks every input against: region, needs, frame and pass,
  // whether the tile expects inputs this frame and is complete. Set by begin() and read by
  // every input under `mutex`, the lock that applies the input.
  TileState state;
};

struct DistributedFrameBuffer::Impl {
  Impl(messaging::Messenger& m, DfbOptions o)
      : messenger(m),
        options(std::move(o)),
        grid(options.width, options.height, options.tileSize) {}

  messaging::Messenger& messenger;
  DfbOptions options;
  TileGrid grid;
  MPI_Comm comm = MPI_COMM_NULL;
  int rank = 0, size = 1;
  std::vector<int> messengerRank;                 // of each rank of `comm`
  std::vector<int> owner;                         // of each tile
  std::vector<int> ownedTiles;                    // ascending
  std::vector<std::unique_ptr<OwnedTile>> tiles;  // non-null where owned
  std::vector<std::shared_ptr<PixelOp>> pixelOps;

  // Frame state; `frameMutex` orders incoming inputs against begin()/end().
  std::mutex frameMutex;
  std::condition_variable frameDone;
  std::int64_t activeFrame = -1;
  bool inFrame = false;
  // inFrame for setTile(), which must not take the frame lock on every call.
  std::atomic<bool> open{false};
  FrameInfo frame;
  std::uint32_t accumulationId = 0;
  bool haveEpoch = false;
  // Inputs for frames not begun yet, with their senders.
  std::map<std::uint32_t, std::vector<std::pair<int, messaging::Bytes>>> early;
  int remaining = 0;  // owned tiles not complete this frame
  std::vector<std::string> inputErrors;

  std::vector<float> tileErrors;
  std::vector<float> errorsLocal, errorsGlobal;  // the frame-end reduction's buffers
  std::vector<std::uint32_t> imageRgba8;
  std::vector<float> imageRgbaF32;
  GatherBuffers gatherBuffers;  // kept between frames: see GatherBuffers

  std::atomic<std::uint64_t> tilesSet{0}, tilesCompleted{0}, staleInputs{0}, earlyInputs{0};
  std::atomic<std::int64_t> lastSetTileNs{0};
  // Stage timers in nanoseconds of the working thread's CPU time (base/Timing.h), read once or
  // twice per stage per tile.
  std::atomic<std::int64_t> unpackNs{0}, operationNs{0}, toneMapNs{0}, pixelOpsNs{0};
  base::Clock::time_point frameStart;
  messaging::Messenger::ObjectTraffic trafficAtBegin;
  messaging::MessengerCounters countersAtBegin;
  FrameStats lastStats;

  // Through the door into the tile's operation, under the tile's lock. `fromRank`: the
  // messenger rank that sent it, -1 when it was set on this rank.
  void processInput(int tileIndex, Tile&& input, const FrameInfo& label, int fromRank);
  // "tile T of frame F, input from rank S (host)": what an input error starts with.
  std::string whichInput(int tileIndex, std::uint32_t frameId, int fromRank) const;
  // Runs the pixel ops of a tile whose last input arrived, with the tile's mutex held.
  void finishTile(int tileIndex, OwnedTile& owned);
  void deliver(int fromRank, messaging::Bytes&& bytes);
  // The display-format gather of the finished frame to rank 0 (nothing with NONE).
  GatherCounts gather(base::Clock::time_point deadline);
  void failInput(const std::string& message) {
    std::lock_guard lock(frameMutex);
    inputErrors.push_back(message);
    frameDone.notify_all();
  }
};

DistributedFrameBuffer::DistributedFrameBuffer(messaging::Messenger& messenger, MPI_Comm comm,
                                               DfbOptions options)
    : impl_(std::make_unique<Impl>(messenger, std::move(options))) {
  Impl& d = *impl_;
  base::checkMpi(MPI_Comm_dup(comm, &d.comm), "MPI_Comm_dup");
  MPI_Comm_rank(d.comm, &d.rank);
  MPI_Comm_size(d.comm, &d.size);
  const int mine = messenger.rank();
  const base::Bound joined{.until = base::Clock::now() + d.options.frameTimeout,
                           .late = "creating the frame buffer: another rank did not join within " +
                                   std::to_string(d.options.frameTimeout.count()) + " ms"};
  d.messengerRank = base::allgather(mine, d.comm, joined);

  const int count = d.grid.tileCount();
  d.owner.resize(static_cast<size_t>(count));
  d.tiles.resize(static_cast<size_t>(count));
  d.tileErrors.assign(static_cast<size_t>(count), 0.0f);
  for (int t = 0; t < count; ++t) {
    const int o = d.options.ownership(t, count, d.size);
    if (o < 0 || o >= d.size)
      throw base::Error("the ownership function gave tile " + std::to_string(t) + " to rank " +
                        std::to_string(o) + " of " + std::to_string(d.size));
    d.owner[static_cast<size_t>(t)] = o;
    if (o == d.rank) {
      d.ownedTiles.push_back(t);
      d.tiles[static_cast<size_t>(t)] = std::make_unique<OwnedTile>();
    }
  }
  d.pixelOps.push_back(std::make_shared<ToneMapOp>(d.options.toneMap));
  messenger.registerObject(d.options.objectId, this);
  // Nobody may send to this object before every rank has registered it.
  base::barrier(d.comm, joined);
}

DistributedFrameBuffer::~DistributedFrameBuffer() {
  impl_->messenger.unregisterObject(impl_->options.objectId);
  MPI_Comm_free(&impl_->comm);
}

void DistributedFrameBuffer::addPixelOp(std::shared_ptr<PixelOp> op) {
  impl_->pixelOps.push_back(std::move(op));
}

void DistributedFrameBuffer::setToneMap(const ToneMapSettings& toneMap) {
  // The tone map is the first op of every chain (the constructor put it there); between frames
  // no tile is in a chain, so replacing it races with nothing.
  impl_->options.toneMap = toneMap;
  impl_->pixelOps.front() = std::make_shared<ToneMapOp>(toneMap);
}

void DistributedFrameBuffer::begin(const FrameInfo& frame) {
  Impl& d = *impl_;
  std::vector<std::pair<int, messaging::Bytes>> held;
  {
    std::lock_guard lock(d.frameMutex);
    // A bad input that came between frames is this rank's failure (end() took those before).
    if (!d.inputErrors.empty()) throw base::Error(d.inputErrors.front());
    if (d.inFrame)
      throw base::Error("begin(" + std::to_string(frame.frameId) + ") inside frame " +
                        std::to_string(d.frame.frameId));
    if (static_cast<std::int64_t>(frame.frameId) <= d.activeFrame)
      throw base::Error("frame ids must increase: begin(" + std::to_string(frame.frameId) +
                        ") after frame " + std::to_string(d.activeFrame));
    if (!d.haveEpoch || frame.epoch != d.frame.epoch)
      d.accumulationId = 0;
    else
      ++d.accumulationId;
    d.haveEpoch = true;
    d.frame = frame;
    d.remaining = 0;
    for (int t : d.ownedTiles) {
      OwnedTile& owned = *d.tiles[static_cast<size_t>(t)];
      std::lock_guard tileLock(owned.mutex);
      const int expected = d.options.expectedInputs ? d.options.expectedInputs(t) : 1;
      TileState& state = owned.state;
      state.frame = frame;
      state.accumulationId = d.accumulationId;
      state.active = expected > 0;
      state.complete = !state.active;  // a tile nobody renders this frame is done already
      if (state.active) {
        if (!owned.operation) {
          state.region = d.grid.region(t);
          owned.operation = d.options.operation(state.region);
          state.needs = owned.operation->needs();
          // The float gather reads color: display pixels cannot stand in for it then.
          if (d.options.format == DisplayFormat::RGBAF32) state.needs.displayPixelsForColor = false;
        }
        owned.operation->newFrame(frame, d.accumulationId, expected);
        ++d.remaining;
      }
    }
    d.tilesSet = d.tilesCompleted = 0;
    d.trafficAtBegin = d.messenger.traffic(d.options.objectId);
    d.countersAtBegin = d.messenger.counters();
    d.staleInputs = d.earlyInputs = 0;
    d.lastSetTileNs = 0;
    d.unpackNs = d.operationNs = d.toneMapNs = d.pixelOpsNs = 0;
    d.frameStart = base::Clock::now();
    d.activeFrame = frame.frameId;
    d.inFrame = true;
    auto found = d.early.find(frame.frameId);
    if (found != d.early.end()) {
      held = std::move(found->second);
      d.early.erase(found);
      d.earlyInputs = held.size();  // counted for the frame they belong to
    }
    // Anything older can never be used.
    while (!d.early.empty() && d.early.begin()->first < frame.frameId) {
      d.staleInputs += d.early.begin()->second.size();
      d.early.erase(d.early.begin());
    }
    d.open = true;
  }
  for (auto& [from, bytes] : held) d.deliver(from, std::move(bytes));
}

void DistributedFrameBuffer::setTile(Tile tile) {
  Impl& d = *impl_;
  if (!d.open)
    throw base::Error("setTile outside a frame: tiles are set between begin() and end()");
  // The tile is rendered when it comes here: compositing overhead counts from this moment (a
  // tile this rank owns is composited, and maybe routed, inside this call). Threads race: keep
  // the latest.
  const std::int64_t now = base::Clock::now().time_since_epoch().count();
  for (std::int64_t seen = d.lastSetTileNs; seen < now;)
    if (d.lastSetTileNs.compare_exchange_weak(seen, now)) break;
  const int index = d.grid.indexOfOrigin(tile.region.x0, tile.region.y0);
  if (index < 0 || d.grid.region(index) != tile.region)
    throw base::Error("setTile: region [" + std::to_string(tile.region.x0) + ", " +
                      std::to_string(tile.region.x1) + ") x [" + std::to_string(tile.region.y0) +
                      ", " + std::to_string(tile.region.y1) + ") is not a tile of the " +
                      std::to_string(d.grid.width()) + "x" + std::to_string(d.grid.height()) +
                      " image at tile size " + std::to_string(d.grid.tileSize()));
  d.tilesSet++;
  const int owner = d.owner[static_cast<size_t>(index)];
  if (owner == d.rank) {
    d.processInput(index, std::move(tile), {d.frame.frameId, d.frame.epoch}, -1);
  } else {
    messaging::Bytes bytes = packTile(tile, index, d.frame.frameId, d.frame.epoch);
    d.messenger.send(d.messengerRank[static_cast<size_t>(owner)], d.options.objectId,
                     std::move(bytes));
  }
}

void DistributedFrameBuffer::incoming(int fromRank, messaging::Bytes&& payload) {
  impl_->deliver(fromRank, std::move(payload));
}

std::string DistributedFrameBuffer::Impl::whichInput(int tileIndex, std::uint32_t frameId,
                                                     int fromRank) const {
  std::string which =
      "tile " + std::to_string(tileIndex) + " of frame " + std::to_string(frameId) + ", input ";
  if (fromRank < 0) return which + "set on this rank (" + std::to_string(rank) + "): ";
  return which + "from rank " + std::to_string(fromRank) + " (" + messenger.hostOf(fromRank) +
         "): ";
}

void DistributedFrameBuffer::Impl::deliver(int fromRank, messaging::Bytes&& bytes) {
  TileMessageHeader header;
  Tile tile;
  const std::int64_t start = base::threadCpuNs();
  try {
    tile = unpackTile(bytes, header);
  } catch (const base::Error& e) {
    failInput("a tile message from rank " + std::to_string(fromRank) + " (" +
              messenger.hostOf(fromRank) + "): " + e.what());
    return;
  }
  unpackNs += base::threadCpuNs() - start;
  {
    std::lock_guard lock(frameMutex);
    if (static_cast<std::int64_t>(header.frameId) > activeFrame + options.framesAhead) {
      inputErrors.push_back(whichInput(header.tileIndex, header.frameId, fromRank) + "more than " +
                            std::to_string(options.framesAhead) + " frames past frame " +
                            std::to_string(activeFrame));
      frameDone.notify_all();
      return;
    }
    if (static_cast<std::int64_t>(header.frameId) > activeFrame) {
      early[header.frameId].emplace_back(fromRank, std::move(bytes));
      return;
    }
    if (!inFrame || static_cast<std::int64_t>(header.frameId) < activeFrame) {
      staleInputs++;
      return;
    }
  }
  if (header.tileIndex < 0 || header.tileIndex >= grid.tileCount() ||
      owner[static_cast<size_t>(header.tileIndex)] != rank) {
    failInput(whichInput(header.tileIndex, header.frameId, fromRank) + "rank " +
              std::to_string(rank) + " does not own that tile");
    return;
  }
  processInput(header.tileIndex, std::move(tile), {header.frameId, header.epoch}, fromRank);
}

void DistributedFrameBuffer::Impl::processInput(int tileIndex, Tile&& input, const FrameInfo& label,
                                                int fromRank) {
  OwnedTile& owned = *tiles[static_cast<size_t>(tileIndex)];
  bool done = false;
  try {
    // The frame is checked under the lock that applies the input: begin() moves the tile to the
    // next frame under it, so an input of frame N never lands in frame N + 1.
    std::lock_guard lock(owned.mutex);
    if (admitInput(input, label, owned.state) == Admission::Stale) {
      staleInputs++;
      return;
    }
    const std::int64_t start = base::threadCpuNs();
    done = owned.operation->process(std::move(input));
    operationNs += base::threadCpuNs() - start;
    if (done) finishTile(tileIndex, owned);
  } catch (const std::exception& e) {
    failInput(whichInput(tileIndex, label.frameId, fromRank) + e.what());
    return;
  }
  // The frame lock is taken only after the tile lock is released: begin() takes them in the
  // other order (frame, then each tile).
  if (done) {
    std::lock_guard lock(frameMutex);
    if (--remaining == 0) frameDone.notify_all();
  }
}

void DistributedFrameBuffer::Impl::finishTile(int tileIndex, OwnedTile& owned) {
  owned.state.complete = true;
  FinishedTile finished;
  finished.tileIndex = tileIndex;
  finished.region = grid.region(tileIndex);
  finished.frameId = frame.frameId;
  finished.accumulationId = accumulationId;
  finished.linear = &owned.operation->finished();
  finished.rgba8 = &owned.rgba8;
  finished.error = owned.operation->error();
  const std::int64_t start = base::threadCpuNs();
  // Tone mapping comes first, but only when something reads its RGBA8: the display format or a
  // later op. A linear-only frame (RGBAF32 or NONE without ops) skips the per-pixel work, and a
  // tile that came as display pixels (Tile::rgba8) has them already: they move over (a copy was
  // a third of the pattern renderer's per-pixel CPU on its owner).
  const size_t pixels = static_cast<size_t>(finished.region.pixelCount());
  if (finished.linear->rgba8.size() == pixels) {
    std::vector<std::uint32_t> taken = owned.operation->takeDisplayPixels();
    if (taken.size() == pixels)
      owned.rgba8 = std::move(taken);
    else
      owned.rgba8 = finished.linear->rgba8;
  } else if (options.format == DisplayFormat::RGBA8 || pixelOps.size() > 1)
    pixelOps.front()->process(finished);
  const std::int64_t now = base::threadCpuNs();
  toneMapNs += now - start;
  for (size_t i = 1; i < pixelOps.size(); ++i) pixelOps[i]->process(finished);
  if (pixelOps.size() > 1) pixelOpsNs += base::threadCpuNs() - now;
  // NaN (from NaN pixels) would make the frame-end MAX reduction differ between ranks, and the
  // ranks then plan the next frame differently; an unknown error counts as "needs samples".
  tileErrors[static_cast<size_t>(tileIndex)] =
      std::isnan(finished.error) ? std::numeric_limits<float>::infinity() : finished.error;
  tilesCompleted++;
}

GatherCounts DistributedFrameBuffer::Impl::gather(base::Clock::time_point deadline) {
  if (options.format == DisplayFormat::NONE) return {};
  const bool rgba8 = options.format == DisplayFormat::RGBA8;
  const int bytesPerPixel = rgba8 ? 4 : 16;
  std::byte* image = nullptr;
  if (rank == 0) {
    const size_t pixels = static_cast<size_t>(grid.width()) * static_cast<size_t>(grid.height());
    if (rgba8) {
      imageRgba8.resize(pixels);
      image = reinterpret_cast<std::byte*>(imageRgba8.data());
    } else {
      imageRgbaF32.resize(4 * pixels);
      image = reinterpret_cast<std::byte*>(imageRgbaF32.data());
    }
  }
  auto tilesOf = [&](int r) {
    std::vector<int> list;
    for (int t = 0; t < grid.tileCount(); ++t)
      if (owner[static_cast<size_t>(t)] == r) list.push_back(t);
    return list;
  };
  std::vector<std::byte> blank;
  auto pixelsOf = [&](int t) -> const std::byte* {
    OwnedTile& owned = *tiles[static_cast<size_t>(t)];
    if (!owned.state.active) {  // not rendered this frame: black, transparent
      blank.assign(static_cast<size_t>(grid.region(t).pixelCount() * bytesPerPixel), std::byte{0});
      return blank.data();
    }
    if (rgba8) return reinterpret_cast<const std::byte*>(owned.rgba8.data());
    return reinterpret_cast<const std::byte*>(owned.operation->finished().color.data());
  };
  return dfb::gatherImage(comm, grid, bytesPerPixel, options.compressGather, ownedTiles, tilesOf,
                          pixelsOf, image, deadline, gatherBuffers);
}

void DistributedFrameBuffer::gatherImage() {
  Impl& d = *impl_;
  d.gather(base::Clock::now() + 2 * d.options.frameTimeout);
}

void DistributedFrameBuffer::end() {
  Impl& d = *impl_;
  const auto deadline = base::Clock::now() + d.options.frameTimeout;
  {
    std::string failure;
    bool late = false;
    std::unique_lock lock(d.frameMutex);
    if (!d.inFrame) throw base::Error("end() without begin()");
    d.open = false;  // setTile() after end() has begun is refused
    d.frameDone.wait_until(lock, deadline,
                           [&] { return d.remaining == 0 || !d.inputErrors.empty(); });
    if (!d.inputErrors.empty()) {
      failure = d.inputErrors.front();
      d.inputErrors.clear();  // reported here; begin() throws only those that come after
    } else if (d.remaining > 0) {
      late = true;
      std::string missing;
      int listed = 0;
      for (int t : d.ownedTiles)
        if (!d.tiles[static_cast<size_t>(t)]->state.complete && listed++ < 8) {
          missing += ' ';  // appended piecewise: GCC 12 -O3 warns falsely on " " + to_string
          missing += std::to_string(t);
        }
      failure = "frame " + std::to_string(d.frame.frameId) + " not complete after " +
                std::to_string(d.options.frameTimeout.count()) + " ms on rank " +
                std::to_string(d.rank) + ": " + std::to_string(d.remaining) +
                " owned tiles still waiting for inputs (tiles" + missing +
                (d.remaining > 8 ? " ..." : "") + ")";
    }
    if (!failure.empty()) {
      d.inFrame = false;
      if (late) throw base::DeadlineError(failure);  // at once: no collective on a failure path
      throw base::Error(failure);
    }
  }

  // One reduction agrees that every rank's tiles are complete and shares the tiles' error
  // estimates (each owner contributes its own, never NaN; the rest are zero). It runs while the
  // image is gathered: every rank enters the gather with its tiles complete as well, so the
  // image is finished when the gather is, and the agreement costs no time of its own. Another
  // rank may be up to a frame timeout later than this one: both waits allow for that.
  const size_t count = d.tileErrors.size();
  d.errorsLocal.assign(count, 0.0f);
  d.errorsGlobal.resize(count);
  for (int t : d.ownedTiles)
    d.errorsLocal[static_cast<size_t>(t)] = d.tileErrors[static_cast<size_t>(t)];
  const auto collectiveDeadline = deadline + d.options.frameTimeout;
  base::Pending agreement =
      base::startAllreduce(d.errorsLocal.data(), d.errorsGlobal.data(), static_cast<int>(count),
                           MPI_FLOAT, MPI_MAX, d.comm);
  const GatherCounts counts =
      d.options.gatherEveryFrame ? d.gather(collectiveDeadline) : GatherCounts{};
  agreement.finish({.until = collectiveDeadline,
                    .late = "frame " + std::to_string(d.frame.frameId) +
                            ": another rank did not finish the frame within " +
                            std::to_string(2 * d.options.frameTimeout.count()) + " ms"});
  const auto complete = base::Clock::now();
  {
    std::lock_guard lock(d.frameMutex);
    d.inFrame = false;
  }
  d.tileErrors.swap(d.errorsGlobal);

  FrameStats stats;
  stats.frameId = d.frame.frameId;
  stats.tilesSet = d.tilesSet;
  stats.tilesCompleted = d.tilesCompleted;
  const messaging::Messenger::ObjectTraffic tiles = d.messenger.traffic(d.options.objectId);
  const messaging::MessengerCounters all = d.messenger.counters();
  stats.tileBytesSent = tiles.bytesSent - d.trafficAtBegin.bytesSent;
  stats.tileBytesReceived = tiles.bytesReceived - d.trafficAtBegin.bytesReceived;
  stats.otherBytesSent = all.wireBytesSent - d.countersAtBegin.wireBytesSent - stats.tileBytesSent;
  stats.otherBytesReceived =
      all.wireBytesReceived - d.countersAtBegin.wireBytesReceived - stats.tileBytesReceived;
  stats.staleInputs = d.staleInputs;
  stats.earlyInputs = d.earlyInputs;
  const std::int64_t lastSet = d.lastSetTileNs;
  stats.lastSetTileNs = lastSet;
  const auto ms = [](std::int64_t ns) { return static_cast<double>(ns) * 1e-6; };
  stats.unpackMs = ms(d.unpackNs);
  stats.operationMs = ms(d.operationNs);
  stats.toneMapMs = ms(d.toneMapNs);
  stats.pixelOpsMs = ms(d.pixelOpsNs);
  if (lastSet != 0)
    stats.lastSetTileToCompleteMs =
        std::chrono::duration<double, std::milli>(complete.time_since_epoch() -
                                                  base::Clock::duration(lastSet))
            .count();

  stats.gatherBytesSent = counts.bytesSent;
  stats.gatherBytesReceived = counts.bytesReceived;
  stats.pixelBytesReceived = counts.pixelBytesReceived;
  stats.frameMs = base::msBetween(d.frameStart, base::Clock::now());
  d.lastStats = stats;
}

const TileGrid& DistributedFrameBuffer::grid() const { return impl_->grid; }
int DistributedFrameBuffer::rank() const { return impl_->rank; }
int DistributedFrameBuffer::ranks() const { return impl_->size; }
int DistributedFrameBuffer::ownerOf(int tileIndex) const {
  return impl_->owner.at(static_cast<size_t>(tileIndex));
}
std::uint32_t DistributedFrameBuffer::accumulationId() const { return impl_->accumulationId; }
const std::vector<float>& DistributedFrameBuffer::tileErrors() const { return impl_->tileErrors; }
const std::vector<std::uint32_t>& DistributedFrameBuffer::imageRgba8() const {
  return impl_->imageRgba8;
}
const std::vector<float>& DistributedFrameBuffer::imageRgbaF32() const {
  return impl_->imageRgbaF32;
}
FrameStats DistributedFrameBuffer::stats() const { return impl_->lastStats; }

std::size_t DistributedFrameBuffer::heldInputs() const {
  std::lock_guard lock(impl_->frameMutex);
  std::size_t held = 0;
  for (const auto& [frame, inputs] : impl_->early) held += inputs.size();
  return held;
}

}  // namespace dfb
