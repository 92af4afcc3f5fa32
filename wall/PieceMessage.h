#pragma once
// The wall's wire protocol: pieces of finished tiles travelling from tile owners (or, in gather
// mode, from rank 0) to the wall rank of their display, and the frame acknowledgement wall
// process 0 sends back to render rank 0 once every display has presented a frame.
#include <cstdint>

#include "dfb/Compression.h"
#include "dfb/Messenger.h"
#include "dfb/Tile.h"

namespace wall {

// Distributed-object ids on the job's messenger.
constexpr dfb::ObjectId kWallNodeObject = 0x3A11'0001;
constexpr dfb::ObjectId kFrameCreditsObject = 0x3A11'0002;

struct PieceHeader {
  std::uint32_t magic;
  std::uint32_t frameId;
  std::int32_t display;
  std::int32_t x0, y0, x1, y1;  // in the display's own coordinates
  std::uint32_t planeDelta;     // 1: pixels went through dfb::planeDeltaEncode
};
static_assert(sizeof(PieceHeader) == 32, "the piece header is part of the protocol");
constexpr std::uint32_t kPieceMagic = 0x50494543;  // "PIEC"

// Packs the `local` rectangle of display `display`, taking its pixels from `source`, an image of
// `sourceWidth` pixels per row whose pixel (sourceX, sourceY) is the piece's top-left.
dfb::Bytes packPiece(std::uint32_t frameId, int display, const dfb::Region& local,
                     const std::uint32_t* source, int sourceWidth, int sourceX, int sourceY,
                     bool planeDelta);

// Unpacks into `pixels` (rows of local.width()); throws wall::Error on a malformed message.
PieceHeader unpackPiece(const dfb::Bytes& bytes, std::vector<std::uint32_t>& pixels);

}  // namespace wall
