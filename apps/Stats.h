#pragma once
// --stats FILE: the run's statistics as JSON Lines, streamed (docs/design.md, "Outputs").
//
//   {"run": {...}}                         first line: canvas, mode, renderer, ranks, ...
//   {"frame": 1, "frame_ms": ..., ...}     one line per frame, written as the frame's numbers
//                                          are known (the wall's acknowledgement included)
//   {"rank": 0, "role": "render", ...}     at the end, one line per rank: stage times, peak RSS
//   {"summary": {...}}                     last line: frames, median and MAD frame time, ...
//
// Each line is written whole with one write(2), so a run that is killed leaves every frame so
// far readable; a run that ends, or stops gracefully, has the summary line. Memory stays
// constant however long the run: medians come from a fixed-size histogram.
#include <cstdint>
#include <string>
#include <vector>

#include "apps/Job.h"

namespace app {

// Values' median and median absolute deviation with constant memory: a histogram of
// logarithmic bins, each 0.5% wide, between `low` and `high` (values outside are clamped).
// The results are bin centres: within 0.25% of the exact statistics.
class LogHistogram {
 public:
  LogHistogram(double low, double high);
  void add(double value);
  std::uint64_t count() const { return count_; }
  double median() const;
  double mad() const;

 private:
  double centre(size_t bin) const;
  double low_, logLow_, step_;
  std::vector<std::uint64_t> bins_;
  std::uint64_t count_ = 0;
};

class StatsStream {
 public:
  // Rank 0, at setup: creates (or truncates) the file. Throws base::Error naming it.
  explicit StatsStream(const std::string& path);
  ~StatsStream();
  StatsStream(const StatsStream&) = delete;
  StatsStream& operator=(const StatsStream&) = delete;

  void writeRun(const Job& job);
  void writeFrame(const FrameRecord& frame);
  // --connect: the wall lost processes or got them back (its roster `version`, applied from
  // frame `frame`): why, as the wall said it, and the displays that show nothing of the job now.
  void writeWallRoster(std::uint32_t version, std::uint32_t frame, const std::string& why,
                       const std::vector<std::string>& lostDisplays);
  // `ranks` has every rank's totals, by world rank; `stoppedEarly`: a graceful stop (signal,
  // closed window) ended the run, with `exitCode`.
  void writeEnd(const std::vector<RankTotals>& ranks, bool stoppedEarly, int exitCode);

 private:
  void writeLine(const std::string& json);
  std::string path_;
  int fd_ = -1;
  LogHistogram frameMs_{1e-3, 1e7}, compositeShare_{1e-6, 1e3}, requestMs_{1e-3, 1e7};
  std::int64_t maxRequestFrames_ = 0;
  std::uint64_t frames_ = 0;
  int job_bricks_ = 0;  // --bricks of the run (brick counts in the rank lines)
};

}  // namespace app
