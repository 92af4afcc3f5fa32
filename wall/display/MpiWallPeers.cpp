#include <string>

#include "base/Collectives.h"
#include "base/Error.h"
#include "wall/display/WallPeers.h"
#include "wall/route/FrameCredits.h"

namespace wall {

MpiWallPeers::MpiWallPeers(messaging::Messenger& messenger, MPI_Comm wallComm,
                           std::chrono::milliseconds timeout)
    : MpiWallPeers(wallComm, timeout, [&messenger](std::uint32_t frameId, std::int64_t ns) {
        acknowledgeFrame(messenger, frameId, ns);
      }) {}

MpiWallPeers::MpiWallPeers(MPI_Comm wallComm, std::chrono::milliseconds timeout,
                           std::function<void(std::uint32_t, std::int64_t)> onPresented)
    : onPresented_(std::move(onPresented)) {
  base::checkMpi(MPI_Comm_dup(wallComm, &comm_), "MPI_Comm_dup");
  MPI_Comm_rank(comm_, &rank_);
  MPI_Comm_size(comm_, &size_);
  base::barrier(comm_, {.until = timeout,
                        .late = "starting the wall: another wall process did not join within " +
                                std::to_string(timeout.count()) + " ms"});
}

MpiWallPeers::~MpiWallPeers() { MPI_Comm_free(&comm_); }

void MpiWallPeers::agreeMax(std::uint32_t frameId, std::int64_t* values, int count,
                            Clock::time_point deadline) {
  std::vector<std::int64_t> mine(values, values + count);
  base::allreduce(mine.data(), values, count, MPI_INT64_T, MPI_MAX, comm_,
                  {.until = deadline,
                   .late = "swap barrier of frame " + std::to_string(frameId) +
                           ": another wall process did not complete it in time"});
}

std::vector<std::vector<std::uint32_t>> MpiWallPeers::gatherToFirst(std::uint32_t frameId,
                                                                    std::vector<std::uint32_t> mine,
                                                                    Clock::time_point deadline) {
  // MPI counts are ints; the layout's canvas cap keeps every display's pixels far below.
  return base::gatherv(mine, 0, comm_,
                       {.until = deadline,
                        .late = "gathering the wall's pixels of frame " + std::to_string(frameId) +
                                ": another wall process did not join in time",
                        .tooLarge = "the wall's pixels of frame " + std::to_string(frameId) +
                                    " do not fit one MPI gather"});
}

void MpiWallPeers::presented(std::uint32_t frameId, std::int64_t completeNs) {
  onPresented_(frameId, completeNs);
}

}  // namespace wall
