#pragma once
// Render rank 0's side of the preview: collects the shrunk tiles the PreviewOps of all tile
// owners send (wall/route/PreviewOp.h), and once every tile of a frame is in, publishes that
// frame's whole-canvas preview. Readers (the control server's HTTP threads, a final --preview file)
// take the latest published one at any time.
//
// A cell that straddles two tiles (a tile size that is no multiple of the factor) is the
// pixel-count-weighted mean of the parts' averages, so it matches the box filter of the whole
// image within rounding; with a tile size that is a multiple of the factor (tiles of 64, any
// factor previewFactor picks up to 64) every cell lies in one tile and the preview equals
// downsample() of the full image exactly.
//
// Best effort, never ahead of the frames: the tile owners' previews travel over the messenger
// beside the frames, which reach the wall on their own way (a service wall's sockets), so one
// rank's cells may lag behind the others'. At most kFramesKept frames are assembled at once; when
// a newer frame starts beyond that, the oldest incomplete one is given up (its late cells are
// dropped) rather than the job ended.
//
// Registered under kPreviewObject on construction (before the job's start-up barrier);
// incoming() runs on the messenger's inbox thread, the rest on any thread.
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <vector>

#include "messaging/Messenger.h"
#include "wall/image/Image.h"
#include "wall/route/Preview.h"

namespace wall {

class PreviewAssembler : public messaging::MessageHandler {
 public:
  // `tilesOfFrame[t]`: whether canvas tile t (at `tileSize`) completes, hence sends its preview,
  // every frame (route mode renders only the tiles some display shows).
  PreviewAssembler(messaging::Messenger& messenger, PreviewGrid grid, int tileSize,
                   std::vector<bool> tilesOfFrame);
  ~PreviewAssembler() override;
  PreviewAssembler(const PreviewAssembler&) = delete;
  PreviewAssembler& operator=(const PreviewAssembler&) = delete;

  static constexpr std::size_t kFramesKept = 16;

  struct Snapshot {
    std::uint32_t frame = 0;  // 0: nothing assembled yet
    PreviewGrid grid;         // the canvas it shows
    Image image;              // grid.width() x grid.height(), raw (not decorated)
  };
  std::shared_ptr<const Snapshot> latest() const;
  // Waits until a frame at or after `frame` is published; false at the deadline.
  bool waitFor(std::uint32_t frame, std::chrono::steady_clock::time_point deadline) const;
  PreviewGrid grid() const;
  // The job's canvas changed (a service wall moved or resized its window) from frame
  // `fromFrame` on: cells of earlier frames are dropped from now on, the latest preview is blank
  // (frame fromFrame - 1) until the first frame of the new canvas is in.
  void restart(PreviewGrid grid, int tileSize, std::vector<bool> tilesOfFrame,
               std::uint32_t fromFrame);
  // Frames given up incomplete so far (their cells came too late).
  std::uint64_t framesGivenUp() const;

  void incoming(int fromRank, messaging::Bytes&& payload) override;

 private:
  struct Assembly {
    std::vector<std::uint32_t> sums;     // 4 per cell: channel sums weighted by pixel count
    std::vector<std::uint32_t> weights;  // pixels behind each cell so far
    std::vector<bool> seen;              // per tile
    int missing = 0;
  };
  // Under mutex_: frame's assembly, nullptr when it is given up already.
  Assembly* assemblyOf(std::uint32_t frame);
  void publish(std::uint32_t frame, const Assembly& a);  // under mutex_

  messaging::Messenger& messenger_;
  mutable std::mutex mutex_;
  mutable std::condition_variable published_;
  // The canvas, under mutex_.
  PreviewGrid grid_;
  dfb::TileGrid tiles_;
  std::vector<bool> tilesOfFrame_;
  int tilesPerFrame_ = 0;
  std::map<std::uint32_t, Assembly> pending_;
  std::shared_ptr<const Snapshot> latest_;
  std::uint32_t givenUpThrough_ = 0;  // frames up to this one are not assembled any more
  std::uint64_t framesGivenUp_ = 0;
};

}  // namespace wall
