#pragma once
// Every wait has a bound (docs/design.md, invariant 6): completes a non-blocking MPI request,
// polling gently, or throws base::DeadlineError with `timeoutMessage` once `deadline` has
// passed. A rank that never joins a collective then turns into an error here instead of a hang.
#include <mpi.h>

#include <chrono>
#include <functional>
#include <string>

namespace base {

void waitWithDeadline(MPI_Request& request, std::chrono::steady_clock::time_point deadline,
                      const std::string& timeoutMessage);
// The same for a wait that is expected to be long (a rank idling until the next order): the
// sleeps between polls double from 20 us up to `maxSleep`, so the wait costs (nearly) no CPU.
void waitWithDeadline(MPI_Request& request, std::chrono::steady_clock::time_point deadline,
                      const std::string& timeoutMessage, std::chrono::microseconds maxSleep);
// The same, giving up early with a DeadlineError of the text `unless` returns once that is not
// empty (a peer that left for good; polled between tests).
void waitWithDeadline(MPI_Request& request, std::chrono::steady_clock::time_point deadline,
                      const std::string& timeoutMessage, std::chrono::microseconds maxSleep,
                      const std::function<std::string()>& unless);

}  // namespace base
