#pragma once
// The preview's pixel op: on the tile owner, after tone mapping, the finished tile shrunk by the
// preview's box filter (wall/route/Preview.h) goes to render rank 0, which assembles the whole-wall
// preview (PreviewAssembler). The factor follows the canvas (previewFactor): on a 3840-pixel
// canvas a 64x64 tile becomes 16x16 cells, 1/16 of its bytes; a canvas of at most 1024 pixels a
// side is its own preview (factor 1), which costs what gathering it would. Counted apart from
// the frame's pixels either way. Runs beside the display-routing op, in route and gather mode.
//
// Thread-safe: the DFB runs it for different tiles concurrently.
#include <atomic>
#include <cstdint>

#include "base/ObjectIds.h"
#include "dfb/PixelOp.h"
#include "messaging/Messenger.h"
#include "wall/route/Preview.h"

namespace wall {

// Distributed-object id of the preview assembler on render rank 0.
constexpr messaging::ObjectId kPreviewObject = base::objectId(base::MessageObject::kPreview);

struct PreviewHeader {
  std::uint32_t magic;
  std::uint32_t frameId;
  std::int32_t x0, y0, x1, y1;  // the tile, in canvas pixels; its cells follow, row-major
};
static_assert(sizeof(PreviewHeader) == 24, "the preview header is part of the protocol");
constexpr std::uint32_t kPreviewMagic = 0x50524556;  // "PREV"

class PreviewOp : public dfb::PixelOp {
 public:
  // `toRank`: where the assembler lives (render rank 0, in the messenger's ranks).
  PreviewOp(messaging::Messenger& messenger, PreviewGrid grid, int toRank = 0)
      : messenger_(messenger), grid_(grid), toRank_(toRank) {}
  void process(dfb::FinishedTile& tile) override;

  // Bytes of preview messages handed to the messenger since the last call (headers included,
  // before compression; those to this rank itself included: they are pixels reaching rank 0).
  std::uint64_t takeBytesSent() { return bytesSent_.exchange(0); }

 private:
  messaging::Messenger& messenger_;
  PreviewGrid grid_;
  int toRank_;
  std::atomic<std::uint64_t> bytesSent_{0};
};

}  // namespace wall
