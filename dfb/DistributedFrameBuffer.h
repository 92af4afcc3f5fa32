#pragma once
// The Distributed FrameBuffer (paper, section 3).
//
// Every rank of `comm` holds a descriptor of every tile and computes its owner locally; the
// owner holds the tile's TileOperation. Renderers call setTile() from any number of threads; the
// tile travels to its owner (or is processed in place), the operation completes it, the pixel
// ops run on the owner, and end() returns once every tile of the frame is complete on its owner
// on every rank. Display formats RGBA8 / RGBAF32 gather the image to rank 0 of `comm` with one
// compressed MPI_Gatherv; NONE gathers nothing.
//
// Contracts:
//  - Construction, begin(), end() and destruction are collective over `comm`.
//  - setTile() is thread-safe and may be called between begin() and end() only (outside a
//    frame it throws).
//  - Every input, set here or received, passes one door (dfb/TileDoor.h) under the lock of the
//    tile it is for: region, channels (the operation's InputNeeds), frame, epoch, pass and tree
//    counts. A bad one is a base::Error naming the tile, the frame and the sender, thrown by
//    end() (or by the next begin() when it came between frames), never undefined behaviour.
//  - Tile messages carry their frame: inputs for a frame a rank has not begun yet are held and
//    applied at its begin(); inputs for a past frame are rejected and counted.
//  - Every wait is bounded by DfbOptions::frameTimeout; a timeout is a base::Error naming the
//    incomplete tiles, on every rank. A rank that finds a problem itself (a timeout, a bad
//    input) throws at once, without the frame-end collective, so the caller can end the job
//    (docs/design.md, "Failures"); the others fail at their own deadline if they are not ended
//    first.
//  - A tile gets its TileOperation the first frame it expects inputs: tiles no frame uses (no
//    display shows them) cost no memory.
#include <mpi.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "base/ObjectIds.h"
#include "dfb/PixelOp.h"
#include "dfb/Tile.h"
#include "dfb/TileOperation.h"
#include "messaging/Messenger.h"

namespace dfb {

enum class DisplayFormat { NONE, RGBA8, RGBAF32 };

// Owner of a tile among `ranks` ranks; must give the same answer on every rank.
using OwnershipFunction = std::function<int(int tileIndex, int tileCount, int ranks)>;
int roundRobinOwner(int tileIndex, int tileCount, int ranks);

struct DfbOptions {
  int width = 0, height = 0;
  int tileSize = 64;
  DisplayFormat format = DisplayFormat::RGBA8;
  TileOperationFactory operation = accumulateOperation();
  OwnershipFunction ownership = roundRobinOwner;
  // How many inputs each tile gets this frame; asked at begin(). Default: one. Zero leaves the
  // tile out of the frame (e.g. no display shows it): it completes at once, runs no pixel ops,
  // and gathers as transparent black.
  std::function<int(int tileIndex)> expectedInputs;
  // The first pixel op of every chain: linear color to display RGBA8 on the tile owner (run
  // when the format is RGBA8 or another pixel op follows; otherwise nothing reads its output).
  ToneMapSettings toneMap;
  // Gathered images (RGBA8, RGBAF32) are compressed; RGBA8 through the plane-delta filter first.
  bool compressGather = true;
  // Whether end() gathers the image to rank 0 every frame; false: only when gatherImage() is
  // called (a run that wants its last frame only: gathering every frame of a 2048^2 float canvas
  // was 5-8% of a frame).
  bool gatherEveryFrame = true;
  // Distinct per DFB sharing a messenger; the same on every rank.
  messaging::ObjectId objectId = base::objectId(base::MessageObject::kFrameBuffer);
  std::chrono::milliseconds frameTimeout{60000};
  // Inputs for a frame more than this many frames past the current one are an error instead of
  // being held (a corrupt frame id would otherwise hold memory forever).
  std::uint32_t framesAhead = 8;
};

struct FrameStats {
  std::uint32_t frameId = 0;
  std::uint64_t tilesSet = 0;                                  // setTile calls on this rank
  std::uint64_t tilesCompleted = 0;                            // owned tiles completed on this rank
  std::uint64_t tileBytesSent = 0, tileBytesReceived = 0;      // tile inputs, on the wire
  std::uint64_t otherBytesSent = 0, otherBytesReceived = 0;    // every other message, on the wire
  std::uint64_t gatherBytesSent = 0, gatherBytesReceived = 0;  // display-format gather
  std::uint64_t pixelBytesReceived = 0;  // final pixels into this rank (gather), uncompressed
  std::uint64_t staleInputs = 0, earlyInputs = 0;
  // last local setTile → frame complete on all ranks (with a display format: image gathered)
  double lastSetTileToCompleteMs = 0;
  double frameMs = 0;              // begin → end returned
  std::int64_t lastSetTileNs = 0;  // steady_clock time the last local setTile began; 0: none
  // Where the owner's CPU time went (each thread's CPU clock, summed over tiles): unpacking tile
  // messages, the tile operation, tone mapping, the rest of the pixel-op chain (e.g. a wall's
  // routing: cutting and sending).
  double unpackMs = 0, operationMs = 0, toneMapMs = 0, pixelOpsMs = 0;
};

class DistributedFrameBuffer final : public messaging::MessageHandler {
 public:
  DistributedFrameBuffer(messaging::Messenger& messenger, MPI_Comm comm, DfbOptions options);
  ~DistributedFrameBuffer() override;
  DistributedFrameBuffer(const DistributedFrameBuffer&) = delete;
  DistributedFrameBuffer& operator=(const DistributedFrameBuffer&) = delete;

  // Appended to the chain after tone mapping; call between frames.
  void addPixelOp(std::shared_ptr<PixelOp> op);
  // Between frames (after end(), before begin()): tone mapping from the next frame on, e.g. an
  // operator changed the exposure. Every rank must set the same.
  void setToneMap(const ToneMapSettings& toneMap);

  void begin(const FrameInfo& frame);
  // Takes the tile by value: move it in and a tile its owner processes here is never copied.
  void setTile(Tile tile);
  void end();

  const TileGrid& grid() const;
  int rank() const;  // in `comm`
  int ranks() const;
  int ownerOf(int tileIndex) const;
  // Sample pass of the current frame within its accumulation epoch (0 after a reset).
  std::uint32_t accumulationId() const;
  // Every tile's error estimate after the last end(), on every rank (for load balancing).
  const std::vector<float>& tileErrors() const;

  // Collective, after end(): gathers the last frame's image to rank 0 (gatherEveryFrame false).
  void gatherImage();
  // Rank 0 after end() (or gatherImage()): the whole image, row-major, y down. Empty elsewhere
  // or with NONE.
  const std::vector<std::uint32_t>& imageRgba8() const;
  const std::vector<float>& imageRgbaF32() const;

  FrameStats stats() const;  // of the last frame, this rank
  // Inputs that came for frames after the active one, held until their begin() (stats()
  // counts them as earlyInputs of that frame).
  std::size_t heldInputs() const;

  void incoming(int fromRank, messaging::Bytes&& payload) override;
  // Tile inputs are combined in any order, under each tile's own lock (as from the renderers'
  // threads), so the messenger hands several to this frame buffer at once.
  bool concurrent() const override { return true; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace dfb
