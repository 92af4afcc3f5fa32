#include <limits>
#include <string>

#include "base/BoundedWait.h"
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
  MPI_Request barrier;
  base::checkMpi(MPI_Ibarrier(comm_, &barrier), "MPI_Ibarrier");
  base::waitWithDeadline(barrier, Clock::now() + timeout,
                         "starting the wall: another wall process did not join within " +
                             std::to_string(timeout.count()) + " ms");
}

MpiWallPeers::~MpiWallPeers() { MPI_Comm_free(&comm_); }

void MpiWallPeers::agreeMax(std::uint32_t frameId, std::int64_t* values, int count,
                            Clock::time_point deadline) {
  std::vector<std::int64_t> mine(values, values + count);
  MPI_Request request;
  base::checkMpi(MPI_Iallreduce(mine.data(), values, count, MPI_INT64_T, MPI_MAX, comm_, &request),
                 "MPI_Iallreduce");
  base::waitWithDeadline(request, deadline,
                         "swap barrier of frame " + std::to_string(frameId) +
                             ": another wall process did not complete it in time");
}

std::vector<std::vector<std::uint32_t>> MpiWallPeers::gatherToFirst(std::uint32_t frameId,
                                                                    std::vector<std::uint32_t> mine,
                                                                    Clock::time_point deadline) {
  const std::string late = "gathering the wall's pixels of frame " + std::to_string(frameId) +
                           ": another wall process did not join in time";
  const int count = static_cast<int>(mine.size());
  std::vector<int> counts(static_cast<size_t>(size_)), offsets(static_cast<size_t>(size_));
  MPI_Request request;
  base::checkMpi(MPI_Igather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, comm_, &request),
                 "MPI_Igather");
  base::waitWithDeadline(request, deadline, late);
  std::vector<std::uint32_t> all;
  if (rank_ == 0) {
    std::int64_t total = 0;
    for (int r = 0; r < size_; ++r) {
      offsets[static_cast<size_t>(r)] = static_cast<int>(total);
      total += counts[static_cast<size_t>(r)];
    }
    // MPI counts are ints; the layout's canvas cap keeps every display's pixels far below.
    if (total > std::numeric_limits<int>::max())
      throw base::Error(std::to_string(total) + " pixels do not fit one MPI gather");
    all.resize(static_cast<size_t>(total));
  }
  base::checkMpi(MPI_Igatherv(mine.data(), count, MPI_UINT32_T, all.data(), counts.data(),
                              offsets.data(), MPI_UINT32_T, 0, comm_, &request),
                 "MPI_Igatherv");
  base::waitWithDeadline(request, deadline, late);
  std::vector<std::vector<std::uint32_t>> out;
  if (rank_ != 0) return out;
  for (int r = 0; r < size_; ++r) {
    const auto from = all.begin() + offsets[static_cast<size_t>(r)];
    out.emplace_back(from, from + counts[static_cast<size_t>(r)]);
  }
  return out;
}

void MpiWallPeers::presented(std::uint32_t frameId, std::int64_t completeNs) {
  onPresented_(frameId, completeNs);
}

}  // namespace wall
