#include "base/Timing.h"
#include "wall/route/PieceMessage.h"
#include "wall/route/PieceSink.h"

namespace wall {

MessengerPieceSink::MessengerPieceSink(messaging::Messenger& messenger, const Layout& layout,
                                       const RankRoles& roles)
    : messenger_(messenger) {
  for (const Display& d : layout.displays) {
    rankOfDisplay_.push_back(roles.rankOfProcess(d.process));
    // The filter only pays when Snappy follows it.
    planeDelta_.push_back(messenger.compresses(rankOfDisplay_.back()));
    otherHost_.push_back(!messenger.sameHost(rankOfDisplay_.back()));
  }
}

std::size_t MessengerPieceSink::send(std::uint32_t frameId, int display, const dfb::Region& local,
                                     const std::uint32_t* pixels, int stride) {
  const std::int64_t t0 = base::threadCpuNs();
  messaging::Bytes bytes = packPiece(frameId, display, local, pixels, stride, 0, 0,
                                     planeDelta_[static_cast<size_t>(display)]);
  const std::size_t size = bytes.size();
  const std::int64_t t1 = base::threadCpuNs();
  messenger_.send(rankOfDisplay_[static_cast<size_t>(display)], kWallNodeObject, std::move(bytes));
  cutNs_ += t1 - t0;
  sendNs_ += base::threadCpuNs() - t1;
  return size;
}

}  // namespace wall
