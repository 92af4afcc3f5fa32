#include "base/BoundedWait.h"

#include <algorithm>
#include <thread>

#include "base/Error.h"

namespace base {

void waitWithDeadline(MPI_Request& request, std::chrono::steady_clock::time_point deadline,
                      const std::string& timeoutMessage) {
  // Short sleeps: other ranks share these cores, and a collective rarely completes at once.
  waitWithDeadline(request, deadline, timeoutMessage, std::chrono::microseconds(20));
}

void waitWithDeadline(MPI_Request& request, std::chrono::steady_clock::time_point deadline,
                      const std::string& timeoutMessage, std::chrono::microseconds maxSleep) {
  waitWithDeadline(request, deadline, timeoutMessage, maxSleep, {});
}

void waitWithDeadline(MPI_Request& request, std::chrono::steady_clock::time_point deadline,
                      const std::string& timeoutMessage, std::chrono::microseconds maxSleep,
                      const std::function<std::string()>& unless) {
  auto sleep = std::min(std::chrono::microseconds(20), maxSleep);
  for (int done = 0;;) {
    checkMpi(MPI_Test(&request, &done, MPI_STATUS_IGNORE), "MPI_Test");
    if (done) return;
    if (std::chrono::steady_clock::now() > deadline) throw DeadlineError(timeoutMessage);
    if (unless)
      if (std::string why = unless(); !why.empty()) throw DeadlineError(why);
    std::this_thread::sleep_for(sleep);
    sleep = std::min(sleep * 2, maxSleep);
  }
}

}  // namespace base
