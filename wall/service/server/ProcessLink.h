#pragma once
// How one process of a service wall reaches the head (process 0) for a job: the head's own
// process through the desk, in process (wall/service/server/Desk.h); every other process over its
// member link (wall/service/server/MemberLink.h). LinkPeers is the wall node's WallPeers on top of
// either, so the node runs the same whatever carries its barrier.
#include <chrono>
#include <cstdint>
#include <vector>

#include "wall/display/WallPeers.h"
#include "wall/service/protocol/LinkMessages.h"
#include "wall/service/protocol/ServiceCommands.h"

namespace wall::service {

class ProcessLink {
 public:
  using Clock = std::chrono::steady_clock;
  virtual ~ProcessLink() = default;
  // Thread-safe. Counts the times this process lost the head (0 for the head itself). A job's
  // node speaks for the epoch it started in: its answers and barriers after a loss (the head
  // may have re-admitted this process to the same job meanwhile) are dropped, never mistaken
  // for the new node's.
  virtual std::uint64_t epoch() const = 0;
  // Thread-safe. An answer to the head (Ready, Done, Failed, StopAsked) of `epoch`; dropped while
  // a member is not joined (the head forgot its job then) or in a later epoch.
  virtual void toHead(const ServiceCommand& command, std::uint64_t epoch) = 0;
  // Frame `frameId`'s swap barrier of job `session` (WallPeers::agreeMax). Returns once the head
  // released it, with the maximum over every process in it; throws base::Error when this process
  // lost the head or was dropped, or at `deadline`.
  virtual void agreeMax(std::uint64_t epoch, std::uint64_t session, std::uint32_t frameId,
                        std::int64_t* values, int count, Clock::time_point deadline) = 0;
  // WallPeers::gatherToFirst: the head's process gets every process's pixels (empty for a
  // process that is lost or did not send them by `deadline`); the others send theirs.
  virtual std::vector<std::vector<std::uint32_t>> gatherToFirst(std::uint64_t epoch,
                                                                std::uint64_t session,
                                                                std::uint32_t frameId,
                                                                std::vector<std::uint32_t> mine,
                                                                Clock::time_point deadline) = 0;
  // The head's process presented `frameId` on every display still in the wall: the job's
  // credit. Nothing on members.
  virtual void presented(std::uint64_t session, std::uint32_t frameId, std::int64_t completeNs) = 0;
  // Thread-safe. This process's cells of job `session`'s window thumbnail, answering the head's
  // Command::Thumbnails (dropped while a member is not joined).
  virtual void thumbnail(std::uint64_t session, const ThumbnailPart& part) = 0;
};

class LinkPeers : public WallPeers {
 public:
  LinkPeers(ProcessLink& link, std::uint64_t epoch, std::uint64_t session, int process,
            int processCount)
      : link_(link),
        epoch_(epoch),
        session_(session),
        process_(process),
        processCount_(processCount) {}
  int process() const override { return process_; }
  int processCount() const override { return processCount_; }
  void agreeMax(std::uint32_t frameId, std::int64_t* values, int count,
                Clock::time_point deadline) override {
    link_.agreeMax(epoch_, session_, frameId, values, count, deadline);
  }
  std::vector<std::vector<std::uint32_t>> gatherToFirst(std::uint32_t frameId,
                                                        std::vector<std::uint32_t> mine,
                                                        Clock::time_point deadline) override {
    return link_.gatherToFirst(epoch_, session_, frameId, std::move(mine), deadline);
  }
  void presented(std::uint32_t frameId, std::int64_t completeNs) override {
    link_.presented(session_, frameId, completeNs);
  }

 private:
  ProcessLink& link_;
  std::uint64_t epoch_, session_;
  int process_, processCount_;
};

}  // namespace wall::service
