#pragma once
// The app's collectives, each with a deadline (docs/design.md, invariant 6): the non-blocking
// MPI call completed by base::waitWithDeadline, so a rank that never joins turns into a
// base::Error naming `what` on the others instead of a hang.
#include <mpi.h>

#include <chrono>
#include <string>

namespace base {

void boundedBarrier(MPI_Comm comm, std::chrono::milliseconds timeout, const std::string& what);
// `maxSleep`: the longest sleep between polls (base::waitWithDeadline); long for a rank that
// idles until the next order.
void boundedBcast(void* buffer, int bytes, MPI_Comm comm, std::chrono::milliseconds timeout,
                  const std::string& what,
                  std::chrono::microseconds maxSleep = std::chrono::microseconds(20));
void boundedAllreduce(const void* in, void* out, int count, MPI_Datatype type, MPI_Op op,
                      MPI_Comm comm, std::chrono::milliseconds timeout, const std::string& what);

}  // namespace base
