#include "wall/WallNode.h"

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
    expectedPieces_.push_back(
        options_.gatherMode
            ? 1
            : static_cast<int>(tilesOfDisplay(layout, mine_[i], options_.tileSize).size()));
  }
  dfb::checkMpi(MPI_Comm_dup(wallComm, &comm_), "MPI_Comm_dup");
  messenger_.registerObject(kWallNodeObject, this);
  dfb::checkMpi(MPI_Barrier(comm_), "MPI_Barrier");
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
  slot.displaysComplete = 0;
  return slots_.emplace(frameId, std::move(slot)).first->second;
}

void WallNode::incoming(int fromRank, dfb::Bytes&& payload) {
  try {
    const auto start = Clock::now();
    const PieceHeader h = readPieceHeader(payload);
    const auto unpacked = Clock::now();
    const int position =
        h.display >= 0 && static_cast<size_t>(h.display) < positionOfDisplay_.size()
            ? positionOfDisplay_[static_cast<size_t>(h.display)]
            : -1;
    if (position < 0)
      throw Error("rank " + std::to_string(fromRank) + " sent a piece of display " +
                  std::to_string(h.display) + ", which wall process " + std::to_string(process_) +
                  " does not drive");
    Image* image = nullptr;
    {
      std::lock_guard lock(mutex_);
      if (static_cast<std::int64_t>(h.frameId) <= lastPresented_)
        throw Error("a piece for frame " + std::to_string(h.frameId) + ", already presented");
      image = &slotFor(h.frameId).displays[static_cast<size_t>(position)];
      bytesReceived_ += payload.size();
    }
    // Only this thread writes slots; the presenting thread reads one only once it is complete.
    copyPiece(payload, h, *image);
    const auto assembled = Clock::now();
    std::lock_guard lock(mutex_);
    unpackNs_ += nsBetween(start, unpacked);
    assembleNs_ += nsBetween(unpacked, assembled);
    Slot& slot = slots_.at(h.frameId);
    const int got = ++slot.received[static_cast<size_t>(position)];
    const int expected = expectedPieces_[static_cast<size_t>(position)];
    if (got > expected)
      throw Error("display '" + layout_.displays[static_cast<size_t>(h.display)].name + "' got " +
                  std::to_string(got) + " pieces of frame " + std::to_string(h.frameId) +
                  ", expected " + std::to_string(expected));
    if (got == expected && ++slot.displaysComplete == static_cast<int>(mine_.size())) {
      slot.completeNs = nsBetween(Clock::time_point{}, assembled);
      complete_.notify_all();
    }
  } catch (const std::exception& e) {
    std::lock_guard lock(mutex_);
    if (error_.empty()) error_ = e.what();
    complete_.notify_all();
  }
}

PresentReport WallNode::presentFrame(std::uint32_t frameId) {
  PresentReport report;
  const auto start = Clock::now();
  const auto deadline = start + options_.timeout;
  Slot* slot = nullptr;
  {
    std::unique_lock lock(mutex_);
    const bool ready = complete_.wait_until(lock, deadline, [&] {
      if (!error_.empty()) return true;
      auto found = slots_.find(frameId);
      return found != slots_.end() &&
             found->second.displaysComplete == static_cast<int>(mine_.size());
    });
    if (!error_.empty()) throw Error("wall process " + std::to_string(process_) + ": " + error_);
    if (!ready) {
      std::string missing;
      auto found = slots_.find(frameId);
      for (size_t i = 0; i < mine_.size(); ++i) {
        const int got = found == slots_.end() ? 0 : found->second.received[i];
        if (got < expectedPieces_[i])
          missing += " '" + layout_.displays[static_cast<size_t>(mine_[i])].name + "' has " +
                     std::to_string(got) + "/" + std::to_string(expectedPieces_[i]) + " pieces;";
      }
      throw Error("frame " + std::to_string(frameId) + " not complete on wall process " +
                  std::to_string(process_) + " after " + std::to_string(options_.timeout.count()) +
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

  // The swap barrier: no display shows frame F before every display has it.
  MPI_Request barrier;
  dfb::checkMpi(MPI_Ibarrier(comm_, &barrier), "MPI_Ibarrier");
  dfb::waitWithDeadline(barrier, deadline,
                        "swap barrier of frame " + std::to_string(frameId) +
                            ": another wall process did not complete it within " +
                            std::to_string(options_.timeout.count()) + " ms");
  const auto released = Clock::now();
  for (size_t i = 0; i < mine_.size(); ++i) {
    const Image& image = slot->displays[i];
    presenters_[i]->present(image.pixels.data(), image.width, image.height);
  }
  // An operator closing any window stops the whole wall: the app turns this into a job abort.
  for (size_t i = 0; i < mine_.size(); ++i)
    if (presenters_[i]->closeRequested())
      throw Error("the window of display '" + layout_.displays[static_cast<size_t>(mine_[i])].name +
                  "' was closed; stopping the wall");
  const auto presented = Clock::now();

  const bool captureThis = !options_.captureDir.empty() &&
                           (frameId == options_.lastFrame ||
                            (options_.captureEvery > 0 &&
                             frameId % static_cast<std::uint32_t>(options_.captureEvery) == 0));
  if (captureThis) capture(frameId);

  {
    std::lock_guard lock(mutex_);
    lastPresented_ = frameId;
    spare_.push_back(std::move(*slot));
    slots_.erase(frameId);
  }
  if (process_ == 0) acknowledgeFrame(messenger_, frameId);
  report.waitMs = msBetween(start, arrived);
  report.barrierMs = msBetween(arrived, released);
  report.presentMs = msBetween(released, presented);
  return report;
}

// Each process writes its displays' captures; wall process 0 also gathers every display's pixels
// for the whole-wall preview. What is captured is what the presenter shows, read back.
void WallNode::capture(std::uint32_t frameId) {
  std::vector<std::uint32_t> mine;
  for (size_t i = 0; i < mine_.size(); ++i) {
    const Image shown = presenters_[i]->readBack();
    writeDisplayCapture(options_.captureDir, layout_, mine_[i], frameId, shown.pixels.data());
    mine.insert(mine.end(), shown.pixels.begin(), shown.pixels.end());
  }
  int size = 0, rank = 0;
  MPI_Comm_size(comm_, &size);
  MPI_Comm_rank(comm_, &rank);
  const int count = static_cast<int>(mine.size());
  std::vector<int> counts(static_cast<size_t>(size)), offsets(static_cast<size_t>(size));
  dfb::checkMpi(MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm_), "MPI_Gather");
  std::vector<std::uint32_t> all;
  if (rank == 0) {
    int total = 0;
    for (int r = 0; r < size; ++r) {
      offsets[static_cast<size_t>(r)] = total;
      total += counts[static_cast<size_t>(r)];
    }
    all.resize(static_cast<size_t>(total));
  }
  dfb::checkMpi(MPI_Gatherv(mine.data(), count, MPI_UINT32_T, all.data(), counts.data(),
                            offsets.data(), MPI_UINT32_T, 0, comm_),
                "MPI_Gatherv");
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
