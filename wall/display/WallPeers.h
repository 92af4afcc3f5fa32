#pragma once
// How the wall processes of one wall agree with each other, whatever carries their messages: the
// swap barrier (a reduction, so it also carries the frame's completion time and capture
// requests), the gather of every display's pixels for the whole-wall capture, and the credit to
// the renderers once a frame is presented everywhere. The wall node (wall/display/WallNode.h) uses
// only this, so the same node runs inside one MPI job with its renderers (MpiWallPeers below) and
// as a persistent service that render jobs connect to (wall/service/).
//
// Threading: called from the wall node's presenting thread only.
#include <mpi.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <vector>

#include "messaging/Messenger.h"

namespace wall {

class WallPeers {
 public:
  using Clock = std::chrono::steady_clock;
  virtual ~WallPeers() = default;

  virtual int process() const = 0;
  virtual int processCount() const = 0;
  // Every wall process calls this for the same frame with its `count` values; each gets the
  // element-wise maximum over all of them in `values`. Throws base::DeadlineError once
  // `deadline` passes without every process having joined.
  virtual void agreeMax(std::uint32_t frameId, std::int64_t* values, int count,
                        Clock::time_point deadline) = 0;
  // Process 0 gets every process's `mine` (its displays' pixels of captured frame `frameId`) in
  // process order; the others get nothing. Same deadline rule. A service wall leaves a lost
  // process's entry empty.
  virtual std::vector<std::vector<std::uint32_t>> gatherToFirst(std::uint32_t frameId,
                                                                std::vector<std::uint32_t> mine,
                                                                Clock::time_point deadline) = 0;
  // Process 0, after every display presented `frameId`: the renderers' credit for a later frame.
  virtual void presented(std::uint32_t frameId, std::int64_t completeNs) = 0;
};

// The wall ranks of one MPI job with their renderers: collectives on a duplicate of `wallComm`
// with bounded waits, the credit to render rank 0 through `messenger` (wall/route/FrameCredits.h).
// The constructor is collective over `wallComm` (a bounded barrier: every wall process is up).
class MpiWallPeers : public WallPeers {
 public:
  MpiWallPeers(messaging::Messenger& messenger, MPI_Comm wallComm,
               std::chrono::milliseconds timeout);
  // The same, with the credit handed to `onPresented` instead (a service wall's job link).
  MpiWallPeers(MPI_Comm wallComm, std::chrono::milliseconds timeout,
               std::function<void(std::uint32_t frameId, std::int64_t completeNs)> onPresented);
  ~MpiWallPeers() override;
  MpiWallPeers(const MpiWallPeers&) = delete;
  MpiWallPeers& operator=(const MpiWallPeers&) = delete;

  int process() const override { return rank_; }
  int processCount() const override { return size_; }
  void agreeMax(std::uint32_t frameId, std::int64_t* values, int count,
                Clock::time_point deadline) override;
  std::vector<std::vector<std::uint32_t>> gatherToFirst(std::uint32_t frameId,
                                                        std::vector<std::uint32_t> mine,
                                                        Clock::time_point deadline) override;
  void presented(std::uint32_t frameId, std::int64_t completeNs) override;

 private:
  std::function<void(std::uint32_t, std::int64_t)> onPresented_;
  MPI_Comm comm_ = MPI_COMM_NULL;
  int rank_ = 0, size_ = 1;
};

}  // namespace wall
