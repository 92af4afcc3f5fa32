#pragma once
// The wall's wire protocol: pieces of finished tiles travelling from tile owners (or, in gather
// mode, from rank 0) to the wall rank of their display, and the frame acknowledgement wall
// process 0 sends back to render rank 0 once every display has presented a frame.
#include <cstdint>

#include "base/ObjectIds.h"
#include "dfb/Tile.h"
#include "messaging/Compression.h"
#include "messaging/Messenger.h"
#include "wall/image/Image.h"

namespace wall {

// Distributed-object ids on the job's messenger.
constexpr messaging::ObjectId kWallNodeObject = base::objectId(base::MessageObject::kWallNode);
constexpr messaging::ObjectId kFrameCreditsObject =
    base::objectId(base::MessageObject::kFrameCredits);

struct PieceHeader {
  std::uint32_t magic;
  std::uint32_t frameId;
  std::int32_t display;
  std::int32_t x0, y0, x1, y1;  // in the display's own coordinates
  std::uint32_t planeDelta;     // 1: pixels went through messaging::planeDeltaEncode
};
static_assert(sizeof(PieceHeader) == 32, "the piece header is part of the protocol");
constexpr std::uint32_t kPieceMagic = 0x50494543;  // "PIEC"

// Packs the `local` rectangle of display `display`, taking its pixels from `source`, an image of
// `sourceWidth` pixels per row whose pixel (sourceX, sourceY) is the piece's top-left.
messaging::Bytes packPiece(std::uint32_t frameId, int display, const dfb::Region& local,
                           const std::uint32_t* source, int sourceWidth, int sourceX, int sourceY,
                           bool planeDelta);

// The header of a piece message, checked against the message's size; throws base::Error on a
// malformed message.
PieceHeader readPieceHeader(const messaging::Bytes& bytes);
// Copies the piece's pixels to their place in its display's image (no intermediate buffer
// unless the plane-delta filter must be undone); throws base::Error if they do not fit.
void copyPiece(const messaging::Bytes& bytes, const PieceHeader& header, Image& display);

}  // namespace wall
