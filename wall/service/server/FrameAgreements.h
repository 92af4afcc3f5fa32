#pragma once
// The swap barriers and capture gathers of one job on a service wall's head
// (wall/service/server/Desk.h), among processes that come and go: each frame's agreement waits for
// exactly the processes that take part in it at the moment (the desk says which: in the job, live,
// past their first frame), so dropping a process completes what it held up, and a process that
// joins later is not waited for before its first frame. Bookkeeping only: no sockets, no threads
// (the desk's thread).
//
// A job in a window leaves out processes whose displays it misses: they have no pieces to wait
// for, so they come to frame F's barrier as soon as F - 1 is released, whether or not the job
// renders F (it may idle, converged, or end at F - 1). Only a process in the window *paces* the
// job: a barrier opens (its overdue clock starts) at the first pacing arrival, and one no pacing
// process came to, at this frame or a later one, is released only where the caller says so (a
// frame the job does not render, its processes told to stop or abort first; a frame no process of
// the window can show).
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <utility>
#include <vector>

namespace wall::service {

class FrameAgreements {
 public:
  using Clock = std::chrono::steady_clock;
  // Whether process p takes part in frame F's agreements now.
  using TakesPart = std::function<bool(int process, std::uint32_t frameId)>;

  explicit FrameAgreements(int processCount) : processCount_(processCount) {}
  void clear();

  // Process p's values for frame F's barrier (the element-wise maximum is kept), at `now`;
  // `paces`: p is in the job's window (above). False when their count differs from the first
  // arrival's: the caller treats p as broken.
  bool arrive(int process, std::uint32_t frameId, const std::vector<std::int64_t>& values,
              Clock::time_point now, bool paces = true);
  struct Release {
    std::uint32_t frameId = 0;
    std::vector<std::int64_t> values;
    std::vector<int> processes;  // those that arrived, to be released
  };
  // Whether frame F's barrier goes without a pacing process (above).
  using GoesUnpaced = std::function<bool(std::uint32_t frameId)>;
  // Every barrier whose taking-part processes have all arrived and that is paced (a pacing
  // process came to it or to a later one) or goes unpaced, removed from the board.
  std::vector<Release> complete(const TakesPart& takesPart, const GoesUnpaced& goesUnpaced = {});

  // Barriers that opened (above) before `openedBefore` and that still wait: the
  // processes taking part that have not arrived (a process that beats but never arrives would
  // otherwise hold every frame).
  struct Overdue {
    std::uint32_t frameId = 0;
    std::vector<int> missing;
  };
  std::vector<Overdue> overdue(const TakesPart& takesPart, Clock::time_point openedBefore) const;
  // Barriers waiting now.
  std::size_t open() const { return barriers_.size(); }

  // A process's pixels of captured frame F; the head's own with its deadline.
  void pixels(int process, std::uint32_t frameId, std::vector<std::uint32_t> pixels);
  void headPixels(std::uint32_t frameId, std::vector<std::uint32_t> pixels,
                  Clock::time_point deadline);
  struct Gathered {
    std::uint32_t frameId = 0;
    std::vector<std::vector<std::uint32_t>> pixels;  // by process; empty: not sent in time
  };
  // Every gather the head asked for that has every taking-part process's pixels, or whose
  // deadline passed, removed from the board.
  std::vector<Gathered> gathered(const TakesPart& takesPart, Clock::time_point now);

 private:
  struct Barrier {
    std::vector<std::int64_t> values;
    std::vector<bool> arrived;
    std::optional<Clock::time_point> opened;  // the first pacing arrival, here or later
  };
  struct Gather {
    std::vector<std::vector<std::uint32_t>> pixels;
    std::vector<bool> got;
    bool headAsked = false;
    Clock::time_point deadline;
  };
  Gather& gatherOf(std::uint32_t frameId);

  int processCount_;
  std::map<std::uint32_t, Barrier> barriers_;
  std::optional<std::uint32_t> pacedUpTo_;  // the latest frame a pacing process came to
  std::map<std::uint32_t, Gather> gathers_;
};

}  // namespace wall::service
