#include "wall/display/WallNode.h"

#include <algorithm>
#include <limits>
#include <string>

#include "base/BoundedWait.h"
#include "base/Error.h"
#include "base/Timing.h"
#include "wall/route/FrameCredits.h"
#include "wall/route/PieceMessage.h"
#include "wall/route/Routing.h"

namespace wall {
namespace {

using base::Clock;
using base::msBetween;
using base::nsBetween;

// While a frame's pieces arrive, the presenting thread is woken to upload them this many times
// (and once more when the frame is complete).
constexpr size_t kUploadBatches = 8;
// Values of the swap barrier's reduction (presentFrame).
constexpr int kAgreed = 6;
// Capture requests not captured yet that a node keeps.
constexpr std::size_t kMaxCaptureAsks = 64;

}  // namespace

WallNode::WallNode(const Layout& layout, WallPeers& peers, std::vector<Presenter*> presenters,
                   WallNodeOptions options)
    : layout_(layout),
      peers_(peers),
      process_(peers.process()),
      presenters_(std::move(presenters)),
      options_(std::move(options)),
      captures_(options_.captureRoot ? CaptureWriter(options_.captureRoot, options_.captureDir,
                                                     options_.captureQuota)
                                     : CaptureWriter(options_.captureDir)),
      mine_(layout.displaysOfProcess(process_)) {
  const int process = process_;
  wallFrame_ = options_.wallFramesBefore;
  if (presenters_.size() != mine_.size())
    throw base::Error("wall process " + std::to_string(process) + " drives " +
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
  lastPresented_ = static_cast<std::int64_t>(std::max<std::uint32_t>(options_.firstFrame, 1)) - 1;
  firstFrame_ = options_.firstFrame;
}

WallNode::~WallNode() = default;

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

void WallNode::incoming(int fromRank, messaging::Bytes&& payload) {
  const std::int64_t start = base::threadCpuNs();  // stage CPU time (base/Timing.h)
  PieceHeader h{};
  try {
    h = readPieceHeader(payload);
  } catch (const std::exception& e) {
    std::lock_guard lock(mutex_);
    if (error_.empty()) error_ = e.what();
    complete_.notify_all();
    return;
  }
  receivePiece(
      "rank " + std::to_string(fromRank), h.frameId, h.display, {h.x0, h.y0, h.x1, h.y1},
      [&](Image& image) { copyPiece(payload, h, image); }, payload.size(), nullptr,
      base::threadCpuNs() - start);
}

bool WallNode::receivePiece(const std::string& sender, std::uint32_t frameId, int display,
                            const dfb::Region& local, const std::function<void(Image&)>& fill,
                            std::size_t bytes, std::string* why, std::int64_t unpackNs) {
  try {
    const std::int64_t start = base::threadCpuNs();
    const int position = display >= 0 && static_cast<size_t>(display) < positionOfDisplay_.size()
                             ? positionOfDisplay_[static_cast<size_t>(display)]
                             : -1;
    if (position < 0)
      throw base::Error(sender + " sent a piece of display " + std::to_string(display) +
                        ", which wall process " + std::to_string(process_) + " does not drive");
    const size_t at = static_cast<size_t>(position);
    const std::string& name = layout_.displays[static_cast<size_t>(display)].name;
    Image* image = nullptr;
    int piece = -1;
    {
      // Everything about the piece is checked, and the piece claimed, before a pixel is copied:
      // a duplicate or a stray rectangle never touches a buffer the presenter may be reading.
      std::lock_guard lock(mutex_);
      if (firstFrame_ == 0 || frameId < firstFrame_) {
        ++staleDropped_;
        return true;
      }
      if (static_cast<std::int64_t>(frameId) <= lastPresented_)
        throw base::Error(sender + " sent a piece for frame " + std::to_string(frameId) +
                          ", already presented");
      if (static_cast<std::int64_t>(frameId) > lastPresented_ + options_.framesAhead)
        throw base::Error(sender + " sent a piece for frame " + std::to_string(frameId) +
                          ", more than " + std::to_string(options_.framesAhead) +
                          " frames past the last presented (" + std::to_string(lastPresented_) +
                          ")");
      piece = expectedPieceIndex(at, local);
      if (piece < 0)
        throw base::Error(sender + " sent display '" + name + "' a piece [" +
                          std::to_string(local.x0) + ", " + std::to_string(local.x1) + ") x [" +
                          std::to_string(local.y0) + ", " + std::to_string(local.y1) +
                          ") that is none of its expected pieces");
      Slot& slot = slotFor(frameId);
      if (slot.claimed[at][static_cast<size_t>(piece)])
        throw base::Error("display '" + name + "' got piece [" + std::to_string(local.x0) + ", " +
                          std::to_string(local.x1) + ") x [" + std::to_string(local.y0) + ", " +
                          std::to_string(local.y1) + ") of frame " + std::to_string(frameId) +
                          " twice");
      slot.claimed[at][static_cast<size_t>(piece)] = true;
      image = &slot.displays[at];
      bytesReceived_ += bytes;
    }
    // Claimed pieces are disjoint, and the presenting thread reads a slot only once every piece
    // is counted below, so this copy needs no lock.
    fill(*image);
    const std::int64_t assembledCpu = base::threadCpuNs();
    const auto assembled = Clock::now();
    std::lock_guard lock(mutex_);
    unpackNs_ += unpackNs;
    assembleNs_ += assembledCpu - start;
    Slot& slot = slots_.at(frameId);
    const int got = ++slot.received[at];
    slot.toUpload.emplace_back(position, piece);
    // The presenting thread drains the list when it wakes: woken once per batch, not per piece
    // (a wake-up costs about what uploading a few pieces does).
    bool wake = slot.toUpload.size() == uploadBatch_;
    if (got == expectedPieces_[at] && ++slot.displaysComplete == static_cast<int>(mine_.size())) {
      slot.completeNs = base::nsBetween(Clock::time_point{}, assembled);
      wake = true;
    }
    if (wake) complete_.notify_all();
    return true;
  } catch (const std::exception& e) {
    std::lock_guard lock(mutex_);
    if (error_.empty()) error_ = e.what();
    if (why) *why = e.what();
    complete_.notify_all();  // presentFrame wakes and throws it at once, not at its deadline
    return false;
  }
}

void WallNode::dropSlot(std::uint32_t frameId) {
  std::lock_guard lock(mutex_);
  auto found = slots_.find(frameId);
  if (found == slots_.end()) return;
  spare_.push_back(std::move(found->second));
  slots_.erase(found);
}

void WallNode::reportError(const std::string& why) {
  std::lock_guard lock(mutex_);
  if (error_.empty()) error_ = why;
  complete_.notify_all();
}

void WallNode::abort(const std::string& reason) {
  std::lock_guard lock(mutex_);
  if (!aborted_) abortReason_ = reason;
  aborted_ = true;
  complete_.notify_all();
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

void WallNode::startAt(std::uint32_t firstFrame) {
  std::lock_guard lock(mutex_);
  if (firstFrame_ != 0) return;
  firstFrame_ = std::max<std::uint32_t>(firstFrame, 1);
  lastPresented_ = static_cast<std::int64_t>(firstFrame_) - 1;
  complete_.notify_all();
}

std::uint32_t WallNode::waitForStart(Clock::time_point deadline) {
  std::unique_lock lock(mutex_);
  complete_.wait_until(lock, deadline, [&] {
    return firstFrame_ != 0 || aborted_ || stopAfter_ >= 0 || !error_.empty();
  });
  return aborted_ || stopAfter_ >= 0 || !error_.empty() ? 0 : firstFrame_;
}

void WallNode::requestCapture(std::uint32_t frameId, std::uint64_t sequence) {
  std::lock_guard lock(mutex_);
  // Whoever asks bounds its requests (the service's head does); this bound is the node's own.
  if (captureAsks_.size() >= kMaxCaptureAsks) return;
  captureAsks_.emplace(sequence, frameId);  // a sequence seen before changes nothing
}

void WallNode::pollWindows() {
  if (options_.pollInput) options_.pollInput();
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
  if (options_.alive) options_.alive();
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
      if (!error_.empty() || aborted_ || stopsBefore()) return true;
      // A process none of whose displays a job's window touches has every frame at once: it
      // only takes part in the swap barrier (and the capture gather).
      if (mine_.empty()) return true;
      auto found = slots_.find(frameId);
      return found != slots_.end() &&
             found->second.displaysComplete == static_cast<int>(mine_.size()) &&
             found->second.toUpload.empty();
    };
    // Pieces that arrived are uploaded while the rest are still on their way; keepWaiting()
    // moves the deadline while the renderers idle.
    while (true) {
      if (error_.empty() && !aborted_ && !stopsBefore()) {
        auto found = slots_.find(frameId);
        if (found != slots_.end() && !found->second.toUpload.empty()) {
          uploading_.swap(found->second.toUpload);
          const Slot& arriving = found->second;  // map nodes stay put; only this thread erases
          lock.unlock();                         // pieces keep arriving meanwhile
          const auto uploadStart = Clock::now();
          upload(arriving, uploading_);
          uploadNs += base::nsBetween(uploadStart, Clock::now());
          lock.lock();
          continue;
        }
      }
      if (ready()) break;
      deadline = std::max(start, waitFrom_) + options_.timeout;
      if (Clock::now() >= deadline) break;
      if (options_.alive) options_.alive();
      if (!options_.onKeys && !options_.pollInput) {
        complete_.wait_until(lock, options_.alive
                                       ? std::min(deadline, Clock::now() + options_.aliveEvery)
                                       : deadline);
        continue;
      }
      complete_.wait_until(lock, std::min(deadline, Clock::now() + options_.eventPoll));
      if (ready()) continue;  // upload what came, then leave
      lock.unlock();          // GLFW's callbacks run in here; pieces keep arriving meanwhile
      pollWindows();
      lock.lock();
    }
    if (!error_.empty() && !options_.abandonOnFailure)
      throw base::Error("wall process " + std::to_string(process_) + ": " + error_);
    if (stopsBefore()) {
      report.stopped = true;
      return report;
    }
    if (!error_.empty()) {
      report.failure = error_;
    } else if (aborted_) {
      report.failure = abortReason_;
    } else if (!ready()) {
      std::string missing;
      auto found = slots_.find(frameId);
      for (size_t i = 0; i < mine_.size(); ++i) {
        const int got = found == slots_.end() ? 0 : found->second.received[i];
        if (got < expectedPieces_[i])
          missing += " '" + layout_.displays[static_cast<size_t>(mine_[i])].name + "' has " +
                     std::to_string(got) + "/" + std::to_string(expectedPieces_[i]) + " pieces;";
      }
      const std::string late = "frame " + std::to_string(frameId) +
                               " not complete on wall process " + std::to_string(process_) +
                               " after " + std::to_string(options_.timeout.count()) +
                               " ms:" + missing;
      if (!options_.abandonOnFailure) throw base::DeadlineError(late);
      report.failure = late;
    }
    if (report.failure.empty()) {
      slot = &slotFor(frameId);  // made here for a process with no displays in the job
      report.bytesReceived = bytesReceived_;
      bytesReceived_ = 0;
      report.unpackMs = static_cast<double>(unpackNs_) * 1e-6;
      report.assembleMs = static_cast<double>(assembleNs_) * 1e-6;
      unpackNs_ = assembleNs_ = 0;
      report.completeNs = slot->completeNs;
    }
  }
  if (!report.failure.empty()) {
    // This process gives the frame up: it says so in the swap barrier, which every process
    // joins for this frame whether it has it or not, so none shows it and none waits in vain.
    if (options_.onAbandon) options_.onAbandon(report.failure);
    std::int64_t abandon[kAgreed] = {0, 0, lastSwapNs_, -lastSwapNs_, 1, 0};
    peers_.agreeMax(frameId, abandon, kAgreed, Clock::now() + options_.timeout);
    dropSlot(frameId);
    report.stopped = report.abandoned = true;
    return report;
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
  // frame or an earlier one) and has not captured, so every process captures the same frame; a
  // request for a later frame waits for it, even when it came before one for this frame (two
  // requests in a row, both here before either frame, are two captures). So do the previous
  // frame's swap times (latest and, negated, earliest): how far apart the displays changed.
  // Then: some process gave the frame up (abandonOnFailure): nobody shows it. The last: the
  // wall's frame count (PresentReport::wallFrame).
  std::int64_t agreed[kAgreed] = {report.completeNs, 0, lastSwapNs_,
                                  -lastSwapNs_,      0, static_cast<std::int64_t>(wallFrame_ + 1)};
  {
    std::lock_guard lock(mutex_);
    for (auto ask = captureAsks_.begin(); ask != captureAsks_.end();) {
      if (ask->first <= captureDone_) {
        ask = captureAsks_.erase(ask);  // captured, by this process's agreement with the others
        continue;
      }
      if (ask->second <= frameId)
        agreed[1] = std::max(agreed[1], static_cast<std::int64_t>(ask->first));
      ++ask;
    }
  }
  peers_.agreeMax(frameId, agreed, kAgreed, deadline);
  if (mine_.empty()) {
    // Out of the job's window this process came here before the job rendered the frame (it has
    // nothing to wait for); a service wall's head lets it go without the frame once the job
    // was told to stop before it or to abort (wall/service/server/FrameAgreements.h).
    std::lock_guard lock(mutex_);
    const bool unrendered = aborted_ || (stopAfter_ >= 0 && frameId > stopAfter_);
    if (unrendered) {
      slots_.erase(frameId);
      report.stopped = true;
      report.abandoned = aborted_;
      if (aborted_) report.failure = abortReason_;
      return report;
    }
  }
  if (agreed[4] != 0) {
    dropSlot(frameId);
    showLastPresented();  // what draw() put in the back buffer may show offscreen
    report.stopped = report.abandoned = true;
    report.failure = "another wall process gave frame " + std::to_string(frameId) + " up";
    return report;
  }
  const auto released = Clock::now();
  report.wallCompleteNs = agreed[0];
  wallFrame_ = report.wallFrame = static_cast<std::uint64_t>(agreed[5]);
  if (lastSwapNs_ != 0)
    report.previousSwapSpreadMs = static_cast<double>(agreed[2] + agreed[3]) * 1e-6;
  const bool asked = agreed[1] > static_cast<std::int64_t>(captureDone_);
  if (asked) captureDone_ = static_cast<std::uint64_t>(agreed[1]);
  for (auto& presenter : presenters_) presenter->swap();
  lastSwapNs_ = base::nsBetween(Clock::time_point{}, Clock::now());
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
    if (shown_) spare_.push_back(std::move(*shown_));
    shown_ = std::move(*slot);
    slots_.erase(frameId);
  }
  if (process_ == 0) peers_.presented(frameId, report.wallCompleteNs);
  report.waitMs = base::msBetween(start, arrived);
  report.uploadMs = static_cast<double>(uploadNs) * 1e-6;
  report.drawMs = base::msBetween(arrived, drawn);
  report.barrierMs = base::msBetween(drawn, released);
  report.presentMs = base::msBetween(released, presented);
  return report;
}

void WallNode::showLastPresented() {
  if (!shown_) return;
  for (size_t i = 0; i < mine_.size(); ++i) {
    const Image& image = shown_->displays[i];
    presenters_[i]->present(image.pixels.data(), image.width, image.height);
  }
}

void WallNode::finish() {
  std::int64_t last = 0;
  {
    std::lock_guard lock(mutex_);
    last = lastPresented_;
  }
  if (!options_.captureDir.empty() && last >= std::max<std::int64_t>(firstFrame_, 1) &&
      last != lastCaptured_)
    capture(static_cast<std::uint32_t>(last));
}

// Each process writes its displays' captures; wall process 0 also gathers every display's pixels
// for the whole-wall preview. What is captured is what the presenter shows, read back. A capture
// this process cannot write still takes part in the gather (so the head does not wait for it in
// vain), then throws CaptureError.
void WallNode::capture(std::uint32_t frameId) {
  lastCaptured_ = frameId;
  std::vector<std::uint32_t> mine;
  std::string failure;
  for (size_t i = 0; i < mine_.size(); ++i) {
    const Image shown = presenters_[i]->readBack();
    try {
      if (failure.empty()) captures_.writeDisplay(layout_, mine_[i], frameId, shown.pixels.data());
    } catch (const CaptureError& e) {
      failure = e.what();
    }
    mine.insert(mine.end(), shown.pixels.begin(), shown.pixels.end());
  }
  const std::vector<std::vector<std::uint32_t>> all =
      peers_.gatherToFirst(frameId, std::move(mine), Clock::now() + options_.timeout);
  if (!failure.empty()) throw CaptureError(failure);
  if (process_ != 0) return;
  std::vector<const std::uint32_t*> pixels(layout_.displays.size(), nullptr);
  for (int p = 0; p < static_cast<int>(all.size()); ++p) {
    const std::uint32_t* at = all[static_cast<size_t>(p)].data();
    if (all[static_cast<size_t>(p)].empty()) continue;  // a lost process: its displays stay dark
    std::size_t expected = 0;
    for (int d : layout_.displaysOfProcess(p))
      expected += static_cast<size_t>(layout_.displays[static_cast<size_t>(d)].rect.pixelCount());
    if (all[static_cast<size_t>(p)].size() != expected)
      throw base::Error("capture of frame " + std::to_string(frameId) + ": wall process " +
                        std::to_string(p) + " sent " +
                        std::to_string(all[static_cast<size_t>(p)].size()) +
                        " pixels for its displays' " + std::to_string(expected));
    for (int d : layout_.displaysOfProcess(p)) {
      pixels[static_cast<size_t>(d)] = at;
      at += static_cast<size_t>(layout_.displays[static_cast<size_t>(d)].rect.pixelCount());
    }
  }
  captures_.writeWallPreview(frameId, composeWallPreview(layout_, pixels));
}

}  // namespace wall
