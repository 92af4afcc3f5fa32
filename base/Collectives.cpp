#include "base/Collectives.h"

#include "base/BoundedWait.h"
#include "base/Error.h"

namespace base {
namespace {

void finish(MPI_Request& request, std::chrono::milliseconds timeout, const std::string& what,
            std::chrono::microseconds maxSleep = std::chrono::microseconds(20)) {
  base::waitWithDeadline(
      request, std::chrono::steady_clock::now() + timeout,
      what + ": another rank did not join within " + std::to_string(timeout.count()) + " ms",
      maxSleep);
}

}  // namespace

void boundedBarrier(MPI_Comm comm, std::chrono::milliseconds timeout, const std::string& what) {
  MPI_Request request;
  base::checkMpi(MPI_Ibarrier(comm, &request), "MPI_Ibarrier");
  finish(request, timeout, what);
}

void boundedBcast(void* buffer, int bytes, MPI_Comm comm, std::chrono::milliseconds timeout,
                  const std::string& what, std::chrono::microseconds maxSleep) {
  MPI_Request request;
  base::checkMpi(MPI_Ibcast(buffer, bytes, MPI_BYTE, 0, comm, &request), "MPI_Ibcast");
  finish(request, timeout, what, maxSleep);
}

void boundedAllreduce(const void* in, void* out, int count, MPI_Datatype type, MPI_Op op,
                      MPI_Comm comm, std::chrono::milliseconds timeout, const std::string& what) {
  MPI_Request request;
  base::checkMpi(MPI_Iallreduce(in, out, count, type, op, comm, &request), "MPI_Iallreduce");
  finish(request, timeout, what);
}

}  // namespace base
