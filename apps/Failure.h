#pragma once
// The one failure path of a running job (docs/design.md, "Failures"): whatever fails on
// whichever thread of whichever rank — an exception, a closed window, a capture that cannot be
// written, a malformed message, a deadline — ends here. The cause is printed once, naming the
// rank and its host, and MPI_Abort ends every rank. Nothing runs on the way: no destructor, no
// collective, so no rank waits for one that will never answer.
#include <exception>
#include <functional>
#include <mutex>
#include <string>

namespace app {

class FailurePath {
 public:
  explicit FailurePath(int worldRank);
  FailurePath(const FailurePath&) = delete;
  FailurePath& operator=(const FailurePath&) = delete;

  // Thread-safe. A second failure on this rank (another thread) waits here until MPI_Abort
  // ends the process, so the rank prints one cause.
  [[noreturn]] void fail(const std::string& what);
  // As above; a passed deadline (base::DeadlineError) first asks `whoIsSilent` which ranks do
  // not answer, so the cause names the stalled rank rather than only the one that waited.
  [[noreturn]] void fail(const std::exception& e);
  // Set while the messenger runs (it answers the question), cleared before it stops.
  void setWhoIsSilent(std::function<std::string()> whoIsSilent);

  int rank() const { return rank_; }
  const std::string& host() const { return host_; }

 private:
  int rank_;
  std::string host_;
  std::mutex mutex_;
  std::function<std::string()> whoIsSilent_;
};

}  // namespace app
