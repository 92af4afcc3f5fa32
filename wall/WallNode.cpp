#include "wall/WallNode.h"

#include <algorithm>
#include <limits>
#include <string>

#include "dfb/BoundedWait.h"
#include "dfb/Error.h"
#include "dfb/Timing.h"
#include "wall/Capture.h"
#include "wall/Error.h"
#include "wall/FrameCredits.h"
#include "wall/PieceMessage.h"
#include "wall/Png.h"
#include "wall/Routing.h"

namespace wall {
namespace {

using dfb::Clock;
using dfb::msBetween;
using dfb::nsBetween;

// While a frame's pieces arrive, the presenting thread is woken to upload them this many times
// (and once more when the frame is complete).
constexpr size_t kUploadBatches = 8;

}  // namespace

WallNode::WallNode(dfb::Messenger& messenger, const Layout& layout, int process, MPI_Comm wallComm,
                   std::vector<std::unique_ptr<Presenter>> presenters, WallNodeOptions options)
    : messenger_(messenger),
      layout_(layout),
      process_(process),
      presenters_(std::move(presenters)),
      options_(std::move(options)),
      mine_(layout.displaysOfProcess(process)) {
  if (presenters_.size() != mine_.size())
    throw Error("wall process " + std::to_string(process) + " drives " +
                std::to_string(mine_.size()) + " displays but got " +
                std::to_string(presenters_.size()) + " presenters");
  positionOfDisplay_.assign(layout.displays.size(), -1);
  for (size_t i = 0; i < mine_.size(); ++i) {
    positionOfDisplay_[static_cast<size_t>(mine_[i])] = static_cast<int>(i);
    const dfb::Region& rect = layout.displays[static_cast<size_t>(mine_[i])].rect;
    std::vector<dfb::Region> rects;
    TileWindow window;
    if (options_.gatherMode) {
      rects.push_back({0, 0, rect.width(), rect.height()});
      window = {0, 0, 1};
    } else {
      for (const DisplayTile& t : tilesOfDisplay(layout, mine_[i], options_.tileSize))
        rects.push_back(t.piece.local);
      const int tileSize = options_.tileSize;
      window = {rect.x0 / tileSize, rect.y0 / tileSize,
                (rect.x1 - 1) / tileSize - rect.x0 / tileSize + 1};
    }
    expectedPieces_.push_back(static_cast<int>(rects.size()));
    uploadBatch_ += rects.size();
    pieceRects_.push_back(std::move(rects));
    tileWindows_.push_back(window);
  }
  uploadBatch_ = std::max<size_t>(1, uploadBatch_ / kUploadBatches);
  dfb::checkMpi(MPI_Comm_dup(wallComm, &comm_), "MPI_Comm_dup");
  messenger_.registerObject(kWallNodeObject, this);
  MPI_Request barrier;
  dfb::checkMpi(MPI_Ibarrier(comm_, &barrier), "MPI_Ibarrier");
  dfb::waitWithDeadline(barrier, Clock::now() + options_.timeout,
                        "starting the wall: another wall process did not join within " +
                            std::to_string(options_.timeout.count()) + " ms");
}

WallNode::~WallNode() {
  messenger_.unregisterObject(kWallNodeObject);
  MPI_Comm_free(&comm_);
}

WallNode::Slot& WallNode::slotFor(std::uint32_t frameId) {
  auto found = slots_.find(frameId);
  if (found != slots_.end()) return found->second;
  Slot slot;
  if (!spare_.empty()) {
    slot = std::move(spare_.back());
    spare_.pop_back();
  } else {
    for (int d : mine_) {
      const dfb::Region& r = layout_.displays[static_cast<size_t>(d)].rect;
      slot.displays.emplace_back(r.width(), r.height());
    }
  }
  slot.received.assign(mine_.size(), 0);
  slot.claimed.resize(mine_.size());
  for (size_t i = 0; i < mine_.size(); ++i)
    slot.claimed[i].assign(static_cast<size_t>(expectedPieces_[i]), false);
  slot.toUpload.clear();
  slot.displaysComplete = 0;
  return slots_.emplace(frameId, std::move(slot)).first->second;
}

int WallNode::expectedPieceIndex(size_t position, const dfb::Region& local) const {
  const std::vector<dfb::Region>& rects = pieceRects_[position];
  if (options_.gatherMode) return local == rects.front() ? 0 : -1;
  const dfb::Region& rect = layout_.displays[static_cast<size_t>(mine_[position])].rect;
  const TileWindow& w = tileWindows_[position];
  if (local.x0 < 0 || local.y0 < 0 || local.x0 >= rect.width() || local.y0 >= rect.height())
    return -1;
  const int tx = (rect.x0 + local.x0) / options_.tileSize - w.tx0;
  const int ty = (rect.y0 + local.y0) / options_.tileSize - w.ty0;
  const size_t index =
      static_cast<size_t>(ty) * static_cast<size_t>(w.columns) + static_cast<size_t>(tx);
  return index < rects.size() && rects[index] == local ? static_cast<int>(index) : -1;
}

void WallNode::incoming(int fromRank, dfb::Bytes&& payload) {
  try {
    const std::int64_t start = dfb::threadCpuNs();  // stage CPU time (dfb/Timing.h)
    const PieceHeader h = readPieceHeader(payload);
    const std::int64_t unpacked = dfb::threadCpuNs();
    const int position =
        h.display >= 0 && static_cast<size_t>(h.display) < positionOfDisplay_.size()
            ? positionOfDisplay_[static_cast<size_t>(h.display)]
            : -1;
    if (position < 0)
      throw Error("rank " + std::to_string(fromRank) + " sent a piece of display " +
                  std::to_string(h.display) + ", which wall process " + std::to_string(process_) +
                  " does not drive");
    const size_t at = static_cast<size_t>(position);
    const dfb::Region local{h.x0, h.y0, h.x1, h.y1};
    const std::string& name = layout_.displays[static_cast<size_t>(h.display)].name;
    Image* image = nullptr;
    int piece = -1;
    {
      // Everything about the piece is checked, and the piece claimed, before a pixel is copied:
      // a duplicate or a stray rectangle never touches a buffer the presenter may be reading.
      std::lock_guard lock(mutex_);
      if (static_cast<std::int64_t>(h.frameId) <= lastPresented_)
        throw Error("rank " + std::to_string(fromRank) + " sent a piece for frame " +
                    std::to_string(h.frameId) + ", already presented");
      if (static_cast<std::int64_t>(h.frameId) > lastPresented_ + options_.framesAhead)
        throw Error("rank " + std::to_string(fromRank) + " sent a piece for frame " +
                    std::to_string(h.frameId) + ", more than " +
                    std::to_string(options_.framesAhead) + " frames past the last presented (" +
                    std::to_string(lastPresented_) + ")");
      piece = expectedPieceIndex(at, local);
      if (piece < 0)
        throw Error("rank " + std::to_string(fromRank) + " sent display '" + name + "' a piece [" +
                    std::to_string(local.x0) + ", " + std::to_string(local.x1) + ") x [" +
                    std::to_string(local.y0) + ", " + std::to_string(local.y1) +
                    ") that is none of its expected pieces");
      Slot& slot = slotFor(h.frameId);
      if (slot.claimed[at][static_cast<size_t>(piece)])
        throw Error("display '" + name + "' got piece [" + std::to_string(local.x0) + ", " +
                    std::to_string(local.x1) + ") x [" + std::to_string(local.y0) + ", " +
                    std::to_string(local.y1) + ") of frame " + std::to_string(h.frameId) +
                    " twice");
      slot.claimed[at][static_cast<size_t>(piece)] = true;
      image = &slot.displays[at];
      bytesReceived_ += payload.size();
    }
    // Claimed pieces are disjoint, and the presenting thread reads a slot only once every piece
    // is counted below, so this copy needs no lock.
    copyPiece(payload, h, *image);
    const std::int64_t assembledCpu = dfb::threadCpuNs();
    const auto assembled = Clock::now();
    std::lock_guard lock(mutex_);
    unpackNs_ += unpacked - start;
    assembleNs_ += assembledCpu - unpacked;
    Slot& slot = slots_.at(h.frameId);
    const int got = ++slot.received[at];
    slot.toUpload.emplace_back(position, piece);
    // The presenting thread drains the list when it wakes: woken once per batch, not per piece
    // (a wake-up costs about what uploading a few pieces does).
    bool wake = slot.toUpload.size() == uploadBatch_;
    if (got == expectedPieces_[at] && ++slot.displaysComplete == static_cast<int>(mine_.size())) {
      slot.completeNs = nsBetween(Clock::time_point{}, assembled);
      wake = true;
    }
    if (wake) complete_.notify_all();
  } catch (const std::exception& e) {
    std::lock_guard lock(mutex_);
    if (error_.empty()) error_ = e.what();
    complete_.notify_all();  // presentFrame wakes and throws it at once, not at its deadline
  }
}

void WallNode::stopAfter(std::uint32_t lastFrame) {
  std::lock_guard lock(mutex_);
  stopAfter_ = lastFrame;
  complete_.notify_all();
}

void WallNode::keepWaiting() {
  std::lock_guard lock(mutex_);
  waitFrom_ = Clock::now();
  complete_.notify_all();
}

void WallNode::requestCapture(std::uint32_t frameId, std::uint64_t sequence) {
  std::lock_guard lock(mutex_);
  if (sequence > captureAsked_) {
    captureAsked_ = sequence;
    captureAskedFrame_ = frameId;
  }
}

void WallNode::pollWindows() {
  if (!options_.onKeys) return;
  std::vector<WallKey> keys;
  for (auto& presenter : presenters_) {
    presenter->pollEvents();
    for (WallKey k : presenter->takeKeys()) keys.push_back(k);
  }
  if (!keys.empty()) options_.onKeys(keys);
}

void WallNode::upload(const Slot& slot, std::vector<std::pair<int, int>>& batch) {
  // By display, so a process with several windows switches GL contexts once per display, and
  // neighbours in a tile row (consecutive indices, same rows) merged into one upload.
  std::sort(batch.begin(), batch.end());
  for (size_t i = 0; i < batch.size();) {
    const size_t at = static_cast<size_t>(batch[i].first);
    const std::vector<dfb::Region>& rects = pieceRects_[at];
    dfb::Region run = rects[static_cast<size_t>(batch[i].second)];
    size_t next = i + 1;
    for (; next < batch.size() && batch[next].first == batch[i].first &&
           batch[next].second == batch[next - 1].second + 1;
         ++next) {
      const dfb::Region& r = rects[static_cast<size_t>(batch[next].second)];
      if (r.x0 != run.x1 || r.y0 != run.y0 || r.y1 != run.y1) break;
      run.x1 = r.x1;
    }
    const Image& image = slot.displays[at];
    presenters_[at]->upload(image.pixels.data(), image.width, run);
    i = next;
  }
  batch.clear();
}

PresentReport WallNode::presentFrame(std::uint32_t frameId) {
  PresentReport report;
  const auto start = Clock::now();
  auto deadline = start + options_.timeout;
  std::int64_t uploadNs = 0;
  // The textures are free: the previous frame was drawn before its swap.
  for (size_t i = 0; i < mine_.size(); ++i) {
    const dfb::Region& r = layout_.displays[static_cast<size_t>(mine_[i])].rect;
    presenters_[i]->beginFrame(r.width(), r.height());
  }
  Slot* slot = nullptr;
  {
    std::unique_lock lock(mutex_);
    const auto stopsBefore = [&] { return stopAfter_ >= 0 && frameId > stopAfter_; };
    const auto ready = [&] {
      if (!error_.empty() || stopsBefore()) return true;
      auto found = slots_.find(frameId);
      return found != slots_.end() &&
             found->second.displaysComplete == static_cast<int>(mine_.size()) &&
             found->second.toUpload.empty();
    };
    // Pieces that arrived are uploaded while the rest are still on their way; keepWaiting()
    // moves the deadline while the renderers idle.
    while (true) {
      if (error_.empty() && !stopsBefore()) {
        auto found = slots_.find(frameId);
        if (found != slots_.end() && !found->second.toUpload.empty()) {
          uploading_.swap(found->second.toUpload);
          const Slot& arriving = found->second;  // map nodes stay put; only this thread erases
          lock.unlock();                         // pieces keep arriving meanwhile
          const auto uploadStart = Clock::now();
          upload(arriving, uploading_);
          uploadNs += nsBetween(uploadStart, Clock::now());
          lock.lock();
          continue;
        }
      }
      if (ready()) break;
      deadline = std::max(start, waitFrom_) + options_.timeout;
      if (Clock::now() >= deadline) break;
      if (!options_.onKeys) {
        complete_.wait_until(lock, deadline);
        continue;
      }
      complete_.wait_until(lock, std::min(deadline, Clock::now() + options_.eventPoll));
      if (ready()) continue;  // upload what came, then leave
      lock.unlock();          // GLFW's callbacks run in here; pieces keep arriving meanwhile
      pollWindows();
      lock.lock();
    }
    if (!error_.empty()) throw Error("wall process " + std::to_string(process_) + ": " + error_);
    if (stopsBefore()) {
      report.stopped = true;
      return report;
    }
    if (!ready()) {
      std::string missing;
      auto found = slots_.find(frameId);
      for (size_t i = 0; i < mine_.size(); ++i) {
        const int got = found == slots_.end() ? 0 : found->second.received[i];
        if (got < expectedPieces_[i])
          missing += " '" + layout_.displays[static_cast<size_t>(mine_[i])].name + "' has " +
                     std::to_string(got) + "/" + std::to_string(expectedPieces_[i]) + " pieces;";
      }
      throw dfb::DeadlineError("frame " + std::to_string(frameId) +
                               " not complete on wall process " + std::to_string(process_) +
                               " after " + std::to_string(options_.timeout.count()) +
                               " ms:" + missing);
    }
    slot = &slots_.at(frameId);
    report.bytesReceived = bytesReceived_;
    bytesReceived_ = 0;
    report.unpackMs = static_cast<double>(unpackNs_) * 1e-6;
    report.assembleMs = static_cast<double>(assembleNs_) * 1e-6;
    unpackNs_ = assembleNs_ = 0;
    report.completeNs = slot->completeNs;
  }
  const auto arrived = Clock::now();
  // Every display draws the frame into its back buffer before the barrier, so what follows the
  // barrier is only the swap: the displays change at (nearly) the same moment.
  for (auto& presenter : presenters_) presenter->draw();
  const auto drawn = Clock::now();

  // The swap barrier: no display shows frame F before every display has it drawn. It is a
  // reduction rather than a plain barrier so every wall process also learns when the last
  // display had the frame complete (for the statistics), at no extra round trip.
  // The capture requests ride along: the highest sequence any process was asked for (for this
  // frame or an earlier one), so every process captures the same frame. So do the previous
  // frame's swap times (latest and, negated, earliest): how far apart the displays changed.
  std::int64_t mine[4] = {report.completeNs, 0, lastSwapNs_, -lastSwapNs_}, agreed[4] = {};
  {
    std::lock_guard lock(mutex_);
    if (captureAsked_ > captureDone_ && frameId >= captureAskedFrame_)
      mine[1] = static_cast<std::int64_t>(captureAsked_);
  }
  MPI_Request barrier;
  dfb::checkMpi(MPI_Iallreduce(mine, agreed, 4, MPI_INT64_T, MPI_MAX, comm_, &barrier),
                "MPI_Iallreduce");
  dfb::waitWithDeadline(barrier, deadline,
                        "swap barrier of frame " + std::to_string(frameId) +
                            ": another wall process did not complete it within " +
                            std::to_string(options_.timeout.count()) + " ms");
  const auto released = Clock::now();
  report.wallCompleteNs = agreed[0];
  if (lastSwapNs_ != 0)
    report.previousSwapSpreadMs = static_cast<double>(agreed[2] + agreed[3]) * 1e-6;
  const bool asked = agreed[1] > static_cast<std::int64_t>(captureDone_);
  if (asked) captureDone_ = static_cast<std::uint64_t>(agreed[1]);
  for (auto& presenter : presenters_) presenter->swap();
  lastSwapNs_ = nsBetween(Clock::time_point{}, Clock::now());
  // An operator closing a window asks the whole job to stop, a key asks for a camera change or a
  // stop; the app decides how.
  for (size_t i = 0; i < mine_.size(); ++i) {
    if (presenters_[i]->closeRequested())
      report.closedDisplay = layout_.displays[static_cast<size_t>(mine_[i])].name;
  }
  pollWindows();
  const auto presented = Clock::now();

  bool last = frameId == options_.lastFrame;
  {
    std::lock_guard lock(mutex_);
    last = last || frameId == stopAfter_;
  }
  const bool captureThis = !options_.captureDir.empty() &&
                           (last || asked ||
                            (options_.captureEvery > 0 &&
                             frameId % static_cast<std::uint32_t>(options_.captureEvery) == 0));
  if (captureThis) capture(frameId);

  {
    std::lock_guard lock(mutex_);
    lastPresented_ = frameId;
    spare_.push_back(std::move(*slot));
    slots_.erase(frameId);
  }
  if (process_ == 0) acknowledgeFrame(messenger_, frameId, report.wallCompleteNs);
  report.waitMs = msBetween(start, arrived);
  report.uploadMs = static_cast<double>(uploadNs) * 1e-6;
  report.drawMs = msBetween(arrived, drawn);
  report.barrierMs = msBetween(drawn, released);
  report.presentMs = msBetween(released, presented);
  return report;
}

void WallNode::finish() {
  std::int64_t last = 0;
  {
    std::lock_guard lock(mutex_);
    last = lastPresented_;
  }
  if (!options_.captureDir.empty() && last > 0 && last != lastCaptured_)
    capture(static_cast<std::uint32_t>(last));
}

// Each process writes its displays' captures; wall process 0 also gathers every display's pixels
// for the whole-wall preview. What is captured is what the presenter shows, read back.
void WallNode::capture(std::uint32_t frameId) {
  lastCaptured_ = frameId;
  std::vector<std::uint32_t> mine;
  for (size_t i = 0; i < mine_.size(); ++i) {
    const Image shown = presenters_[i]->readBack();
    writeDisplayCapture(options_.captureDir, layout_, mine_[i], frameId, shown.pixels.data());
    mine.insert(mine.end(), shown.pixels.begin(), shown.pixels.end());
  }
  int size = 0, rank = 0;
  MPI_Comm_size(comm_, &size);
  MPI_Comm_rank(comm_, &rank);
  const auto deadline = Clock::now() + options_.timeout;
  const std::string late = "capture of frame " + std::to_string(frameId) +
                           ": another wall process did not join within " +
                           std::to_string(options_.timeout.count()) + " ms";
  const int count = static_cast<int>(mine.size());
  std::vector<int> counts(static_cast<size_t>(size)), offsets(static_cast<size_t>(size));
  MPI_Request request;
  dfb::checkMpi(MPI_Igather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm_, &request),
                "MPI_Igather");
  dfb::waitWithDeadline(request, deadline, late);
  std::vector<std::uint32_t> all;
  if (rank == 0) {
    std::int64_t total = 0;
    for (int r = 0; r < size; ++r) {
      offsets[static_cast<size_t>(r)] = static_cast<int>(total);
      total += counts[static_cast<size_t>(r)];
    }
    // MPI counts are ints; the layout's canvas cap keeps every display's pixels far below.
    if (total > std::numeric_limits<int>::max())
      throw Error("capture of frame " + std::to_string(frameId) + ": " + std::to_string(total) +
                  " pixels do not fit one MPI gather");
    all.resize(static_cast<size_t>(total));
  }
  dfb::checkMpi(MPI_Igatherv(mine.data(), count, MPI_UINT32_T, all.data(), counts.data(),
                             offsets.data(), MPI_UINT32_T, 0, comm_, &request),
                "MPI_Igatherv");
  dfb::waitWithDeadline(request, deadline, late);
  if (rank != 0) return;
  std::vector<const std::uint32_t*> pixels(layout_.displays.size(), nullptr);
  for (int p = 0; p < size; ++p) {
    const std::uint32_t* at = all.data() + offsets[static_cast<size_t>(p)];
    for (int d : layout_.displaysOfProcess(p)) {
      pixels[static_cast<size_t>(d)] = at;
      at += static_cast<size_t>(layout_.displays[static_cast<size_t>(d)].rect.pixelCount());
    }
  }
  writePng(wallPreviewPath(options_.captureDir, frameId), composeWallPreview(layout_, pixels));
}

}  // namespace wall
