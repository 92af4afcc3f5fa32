#pragma once
// A wall process: receives the pieces of its displays' frames, assembles them in per-frame back
// buffers, and presents a frame only when every display of every wall process has it complete
// (swap barrier among the wall ranks only), then acknowledges it to the renderers.
//
// Tide's order, so the displays change together: while frame F's pieces arrive, each is
// uploaded to its display's texture as soon as the presenting thread is free; once all are in,
// every display draws F into its back buffer (finished); then the swap barrier; then every
// display swaps, which is all that is left between the barrier and the frame being visible.
//
// The layout says exactly which pieces each display gets per frame (one per canvas tile that
// touches it, or one whole-display piece in gather mode), so completion is counted in pieces,
// never in pixels, and a duplicate is an error rather than a miscount.
//
// The node talks to the other wall processes only through wall::WallPeers
// (wall/display/WallPeers.h), and takes pieces from whoever calls incoming() (the job's messenger,
// where the node is registered under kWallNodeObject) or receivePiece() (a service link): one node
// for both transports.
//
// Threading: incoming() and receivePiece() run on the receiving threads, several pieces at once
// (each is checked and claimed under the lock, then copied unlocked: claimed pieces are
// disjoint); everything else on the thread that made the node, which owns the presenters (GL
// contexts).
#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "base/ConfinedFolder.h"
#include "messaging/Messenger.h"
#include "wall/display/Capture.h"
#include "wall/display/Presenter.h"
#include "wall/display/WallPeers.h"
#include "wall/image/Image.h"
#include "wall/layout/Layout.h"

namespace wall {

struct WallNodeOptions {
  int tileSize = 64;
  bool gatherMode = false;  // one whole-display piece per frame from rank 0
  std::string captureDir;   // empty: no captures; with captureRoot, a folder beneath it
  int captureEvery = 0;     // capture every K-th frame; 0: only the last
  // A service wall's job: captures only beneath this folder (captureDir as
  // wall::resolveCaptureRequest returned it), at most captureQuota bytes (0: no limit).
  std::shared_ptr<const base::ConfinedFolder> captureRoot;
  std::uint64_t captureQuota = 0;
  std::uint32_t lastFrame = 0;
  // A service wall process that (re)joins a running job presents from this frame on; pieces of
  // earlier frames (sent before the job knew it was back) are dropped without a word. 0: not
  // known yet (every piece is dropped until startAt()).
  std::uint32_t firstFrame = 1;
  std::chrono::milliseconds timeout{60000};
  // Pieces of frames more than this far past the last presented one are refused (an error):
  // the renderers run at most frames-in-flight ahead, so anything further is a corrupt or
  // hostile message, and buffering it would hold a display buffer forever.
  std::uint32_t framesAhead = 8;
  // Windows: keys pressed in this process's windows go here, on the calling (main) thread, as
  // they come, also while presentFrame waits for a frame (every `eventPoll` then: a converged,
  // idle wall still hears its keyboard). Empty: keys are ignored.
  std::function<void(const std::vector<WallKey>&)> onKeys;
  // Or the caller polls its windows itself (all of its displays, also those the node does not
  // present, and the mouse too): called on the main thread when onKeys would be. A service wall
  // of one job at a time steers its job so.
  std::function<void()> pollInput;
  std::chrono::milliseconds eventPoll{50};
  // A service wall outlives its render jobs: a frame this process cannot complete (a bad piece,
  // its deadline, abort()) is given up in the swap barrier on every process and presentFrame
  // returns `abandoned` instead of throwing. onAbandon runs first, with the reason (so the
  // service can tell the other processes at once rather than at their deadlines).
  bool abandonOnFailure = false;
  std::function<void(const std::string& reason)> onAbandon;
  // Called on the presenting thread at least every `aliveEvery` while presentFrame waits, and
  // around each frame's work: a service wall process whose presenting thread stops calling it
  // (a driver that hangs) stops saying it is alive, and the wall drops it.
  std::function<void()> alive;
  std::chrono::milliseconds aliveEvery{250};
  // The wall's presented frames before this node's first (a service wall counts them across its
  // jobs): see PresentReport::wallFrame.
  std::uint64_t wallFramesBefore = 0;
};

// The one rule for WallNodeOptions::framesAhead: render rank 0 starts frame F once frame
// F - framesInFlight is presented, so pieces can be framesInFlight + 1 frames ahead of this
// process's last presented frame, one more while it is between the swap barrier and noting the
// frame presented.
constexpr std::uint32_t framesAheadFor(int framesInFlight) {
  return static_cast<std::uint32_t>(framesInFlight) + 2;
}

struct PresentReport {
  double waitMs = 0;     // until every piece of this process's displays had arrived (and was
                         // uploaded: uploads happen while waiting)
  double uploadMs = 0;   // of waitMs, uploading pieces to the displays' textures
  double drawMs = 0;     // drawing every display's back buffer, before the barrier
  double barrierMs = 0;  // in the swap barrier
  double presentMs = 0;  // swapping every display (after the barrier), window events
  std::uint64_t bytesReceived = 0;
  // Since the previous presentFrame, CPU time of the thread that received the pieces: unpacking
  // them and copying them into the back buffers. completeNs: steady_clock time the last piece
  // of this frame arrived.
  double unpackMs = 0, assembleMs = 0;
  std::int64_t completeNs = 0;
  // The latest completeNs over every wall process (agreed in the swap barrier).
  std::int64_t wallCompleteNs = 0;
  // The previous frame's swaps: latest minus earliest end of a swap over every wall process
  // (agreed in this frame's barrier; one host's clock, meaningful where the wall ranks share
  // one). Negative: not known (the first frame).
  double previousSwapSpreadMs = -1;
  // The frame was not presented: the run stops before it (see stopAfter).
  bool stopped = false;
  // The name of a display whose window an operator closed (empty: none).
  std::string closedDisplay;
  // With abandonOnFailure: the frame was given up (by this process: `failure` says why, or by
  // another) and not presented; the displays still show the last presented frame.
  bool abandoned = false;
  std::string failure;
  // The wall's count of presented frames, this one included: one more than the highest count
  // any process brought to the swap barrier, so every process names a frame alike, also one
  // that missed frames (rejoined) or a job that is not the wall's first (serve --capture).
  std::uint64_t wallFrame = 0;
};

class WallNode : public messaging::MessageHandler {
 public:
  // This is wall process peers.process(); `presenters` (not owned: a service wall keeps them
  // from one render job to the next) has one per display of it, in
  // layout.displaysOfProcess(process) order.
  WallNode(const Layout& layout, WallPeers& peers, std::vector<Presenter*> presenters,
           WallNodeOptions options);
  ~WallNode() override;

  // Waits for frame `frameId` on this process's displays, joins the swap barrier, presents,
  // captures when asked, and (process 0) acknowledges the frame. Throws base::Error on timeout
  // or a protocol error. A window an operator closed is reported, not thrown.
  PresentReport presentFrame(std::uint32_t frameId);
  // Thread-safe: the run ends after frame `lastFrame`; a presentFrame for a later frame returns
  // at once (or wakes up) with `stopped` set. Every wall process must be told the same frame.
  void stopAfter(std::uint32_t lastFrame);
  // Thread-safe: an error of the sender found outside the node (a malformed batch); presentFrame
  // throws it, or with abandonOnFailure gives the frame up.
  void reportError(const std::string& why);
  // Thread-safe, with abandonOnFailure: the render job is gone; the frame being waited for (or
  // the next one) is given up on every process and presentFrame returns `abandoned`.
  void abort(const std::string& reason);
  // Thread-safe: the renderers idle (a converged wall waits for a change), so the wait for the
  // next frame's pieces starts over: its deadline is `timeout` from now. Render rank 0 repeats
  // this well within the timeout while it idles; a rank that dies still ends the wait.
  void keepWaiting();
  // Thread-safe: the first frame, for a node made with firstFrame 0 (a process that rejoins a
  // running job learns it once it is ready to take pieces).
  void startAt(std::uint32_t firstFrame);
  // Until startAt() was called (its frame), the run was stopped or aborted, or `deadline` (0).
  std::uint32_t waitForStart(std::chrono::steady_clock::time_point deadline);
  // Thread-safe: capture frame `frameId` or, when it is presented already, the first frame
  // after it; `sequence` numbers the requests (1, 2, ...). Every wall process captures the same
  // frame: the swap barrier agrees on the highest sequence any process has been asked for.
  void requestCapture(std::uint32_t frameId, std::uint64_t sequence);
  // Collective over the wall ranks, after the last presentFrame: captures the last presented
  // frame when captures were asked for and it was not captured yet (a run stopped early).
  void finish();

  // Puts back on every display the last frame presented here (after an abandoned one, whose
  // draw() may already show on an offscreen drawable). Nothing when none was presented.
  void showLastPresented();

  // A piece message (wall/route/PieceMessage.h) from rank `fromRank` of the job's messenger.
  void incoming(int fromRank, messaging::Bytes&& payload) override;
  bool concurrent() const override { return true; }
  // A piece of frame `frameId` for display `display` (layout index), rectangle `local` in the
  // display's coordinates, from `sender` (named in messages). Checked and claimed under the
  // lock; then `fill(image)` writes its pixels into the display's back buffer, only inside
  // `local`, unlocked (it may decode). `bytes`: what it took on the wire, for the statistics.
  // A piece that is not one this node expects, or a `fill` that throws, is an error that
  // presentFrame throws (the sender is broken); returns false then, with the message in `why`.
  // `unpackNs`: CPU time the caller spent reading the piece's header (the statistics' unpack).
  bool receivePiece(const std::string& sender, std::uint32_t frameId, int display,
                    const dfb::Region& local, const std::function<void(Image&)>& fill,
                    std::size_t bytes, std::string* why = nullptr, std::int64_t unpackNs = 0);

 private:
  // Handles window events and hands pressed keys to options_.onKeys (main thread, unlocked).
  void pollWindows();
  struct Slot {
    std::vector<Image> displays;             // by position in mine_
    std::vector<int> received;               // pieces copied in, by position in mine_
    std::vector<std::vector<bool>> claimed;  // by position, by expected piece: arrived once
    // Pieces copied in but not yet uploaded to their display's texture: (position, piece).
    std::vector<std::pair<int, int>> toUpload;
    int displaysComplete = 0;
    std::int64_t completeNs = 0;
  };
  Slot& slotFor(std::uint32_t frameId);  // with mutex_ held
  void dropSlot(std::uint32_t frameId);  // its buffers back to the spares
  // Which of display `position`'s expected pieces `local` is, or -1 when it is none of them.
  int expectedPieceIndex(size_t position, const dfb::Region& local) const;
  void capture(std::uint32_t frameId);
  // Uploads the pieces in `batch` of `slot` (main thread, unlocked): they are counted, so no
  // thread writes them any more.
  void upload(const Slot& slot, std::vector<std::pair<int, int>>& batch);

  const Layout& layout_;
  WallPeers& peers_;
  int process_;
  std::vector<Presenter*> presenters_;
  WallNodeOptions options_;
  CaptureWriter captures_;
  std::vector<int> mine_;               // display indices of this process
  std::vector<int> positionOfDisplay_;  // layout index -> position in mine_, or -1
  std::vector<int> expectedPieces_;     // by position in mine_
  // By position: the display's pieces (display coordinates) in tilesOfDisplay order, and the
  // tile-grid window they come from, so a piece finds its index without a search.
  std::vector<std::vector<dfb::Region>> pieceRects_;
  struct TileWindow {
    int tx0 = 0, ty0 = 0, columns = 1;
  };
  std::vector<TileWindow> tileWindows_;

  std::mutex mutex_;
  std::condition_variable complete_;
  std::map<std::uint32_t, Slot> slots_;
  std::vector<Slot> spare_;                     // buffers of presented frames, reused
  std::optional<Slot> shown_;                   // the last presented frame (showLastPresented)
  std::vector<std::pair<int, int>> uploading_;  // main thread: the batch being uploaded
  size_t uploadBatch_ = 0;  // pieces queued for upload that wake the presenting thread
  std::int64_t lastPresented_ = 0;
  std::int64_t stopAfter_ = -1;  // -1: no early stop
  std::int64_t lastCaptured_ = 0;
  std::chrono::steady_clock::time_point waitFrom_{};  // keepWaiting: deadlines count from here
  // Capture requests not yet captured: sequence -> frame. Each is taken at its frame (or the
  // first presented after it), also when a later request came first.
  std::map<std::uint64_t, std::uint32_t> captureAsks_;
  // Highest sequence captured (the same on every process); presenting thread only.
  std::uint64_t captureDone_ = 0;
  std::int64_t lastSwapNs_ = 0;  // steady_clock time the last frame's swaps ended here
  std::uint64_t wallFrame_ = 0;  // PresentReport::wallFrame of the last presented frame
  std::string error_;
  bool aborted_ = false;
  std::string abortReason_;
  std::uint64_t bytesReceived_ = 0;
  std::int64_t unpackNs_ = 0, assembleNs_ = 0;
  std::uint32_t firstFrame_ = 1;    // 0: not known yet (startAt)
  std::uint64_t staleDropped_ = 0;  // pieces of frames before firstFrame_
};

}  // namespace wall
