#pragma once
// What the wall's own processes say to each other (wall/service/server/WallService.h): every
// process but the head (process 0) keeps one link to the head's directory socket, so the processes
// need no common MPI job and each may die, hang or be restarted alone.
//
//  - Join (member -> head): "I am process N of this layout, my piece socket is E" (its token
//    field unused: the handshake checked the token); Welcome or Refused back. A process that
//    restarts joins again with a new incarnation; the head forgets the old one.
//  - Beat (both ways, every quarter of the timeout): a member the head has not heard for the
//    timeout is dropped, and a head a member has not heard for the timeout is lost (the member
//    gives up its job and joins again, which also brings it back after a cut link).
//  - Dropped (head -> a member it no longer counts, e.g. after SIGSTOP/SIGCONT): join again.
//  - Command (both ways): the head's orders for a job and the members' answers; their layout is
//    the service's own.
//  - Barrier (both ways): a member's values for frame F's swap barrier, and the head's release
//    with the element-wise maximum over every process in F's barrier.
//  - Pixels (member -> head): its displays' pixels of a captured frame, for the wall preview.
//  - Thumbnail (member -> head): its displays' cell sums of a window's thumbnail, answering the
//    head's Command::Thumbnails (wall/image/Thumbnail.h).
#include <cstdint>
#include <string>
#include <vector>

#include "messaging/Compression.h"
#include "wall/image/Thumbnail.h"
#include "wall/layout/Layout.h"
#include "wall/service/protocol/Protocol.h"

namespace wall::service {

struct Join {
  std::string token;  // unused: the token is checked at the ZeroMQ handshake; sent empty
  std::uint32_t process = 0;
  std::string host;           // for the head's log
  std::string pieceEndpoint;  // "tcp://HOST:PORT" render jobs send this process's pieces to
  std::uint64_t layoutHash = 0;
  std::uint64_t incarnation = 0;  // random per start of the process and per join
};
messaging::Bytes packJoin(const Join& join);
Join parseJoin(const std::byte* data, std::size_t size);

// What makes two processes' layouts the same wall: canvas, displays (name, rectangle, process)
// and process count; not the file's name or comments.
std::uint64_t layoutHash(const Layout& layout);

struct BarrierValues {
  std::uint32_t frameId = 0;
  std::vector<std::int64_t> values;  // 1..16
};
messaging::Bytes packBarrier(std::uint64_t session, const BarrierValues& barrier);
BarrierValues parseBarrier(const std::byte* data, std::size_t size);

struct CapturePixels {
  std::uint32_t frameId = 0;
  std::vector<std::uint32_t> pixels;
};
messaging::Bytes packPixels(std::uint64_t session, std::uint32_t frameId,
                            const std::vector<std::uint32_t>& pixels);
CapturePixels parsePixels(const std::byte* data, std::size_t size);

// A process's part of job `session`'s window thumbnail: the sums of the cells its displays show
// of the window `window` (on the canvas), for the head's request `request`. The parser checks the
// window's size and that the cells lie in its grid of at most kMaxThumbnailSide cells a side,
// and that the message holds exactly their sums, before it allocates anything.
struct ThumbnailPart {
  std::uint32_t request = 0;
  dfb::Region window;
  CellSums cells;
};
messaging::Bytes packThumbnail(std::uint64_t session, const ThumbnailPart& part);
ThumbnailPart parseThumbnail(const std::byte* data, std::size_t size);

// Command: an opaque body the service lays out itself.
messaging::Bytes packCommandMessage(std::uint64_t session, const messaging::Bytes& body);
// The body of a Command message (after the header).
messaging::Bytes commandBody(const std::byte* data, std::size_t size);

}  // namespace wall::service
