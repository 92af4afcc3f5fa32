#include "base/Collectives.h"

#include <limits>

#include "base/BoundedWait.h"
#include "base/Error.h"

namespace base {
namespace {

constexpr std::size_t kMaxCount = std::numeric_limits<int>::max();

void tooLarge(const Bound& bound, std::size_t values) {
  throw Error(!bound.tooLarge.empty() ? bound.tooLarge
                                      : "a collective of " + std::to_string(values) +
                                            " values: more than an MPI count reaches (2^31-1)");
}

// Values of `bytes` bytes each, as one MPI datatype; freed by the caller once the call started
// (MPI keeps it for the collective in flight).
struct ValueType {
  explicit ValueType(std::size_t bytes) {
    if (bytes == 1) return;
    checkMpi(MPI_Type_contiguous(static_cast<int>(bytes), MPI_BYTE, &type), "MPI_Type_contiguous");
    checkMpi(MPI_Type_commit(&type), "MPI_Type_commit");
  }
  ~ValueType() {
    if (type != MPI_BYTE) MPI_Type_free(&type);
  }
  ValueType(const ValueType&) = delete;
  ValueType& operator=(const ValueType&) = delete;

  MPI_Datatype type = MPI_BYTE;
};

}  // namespace

std::chrono::steady_clock::time_point Bound::deadline() const {
  if (const auto* timeout = std::get_if<std::chrono::milliseconds>(&until))
    return std::chrono::steady_clock::now() + *timeout;
  return std::get<std::chrono::steady_clock::time_point>(until);
}

Bound Bound::joinWithin(std::chrono::milliseconds timeout, const std::string& what) {
  return {.until = timeout,
          .late = what + ": another rank did not join within " + std::to_string(timeout.count()) +
                  " ms"};
}

void Pending::finish(const Bound& bound) {
  waitWithDeadline(request_, bound.deadline(), bound.late, bound.maxSleep, bound.unless);
}

void barrier(MPI_Comm comm, const Bound& bound) {
  MPI_Request request;
  checkMpi(MPI_Ibarrier(comm, &request), "MPI_Ibarrier");
  Pending(request).finish(bound);
}

void bcast(void* data, int bytes, int root, MPI_Comm comm, const Bound& bound) {
  MPI_Request request;
  checkMpi(MPI_Ibcast(data, bytes, MPI_BYTE, root, comm, &request), "MPI_Ibcast");
  Pending(request).finish(bound);
}

void allreduce(const void* in, void* out, int count, MPI_Datatype type, MPI_Op op, MPI_Comm comm,
               const Bound& bound) {
  startAllreduce(in, out, count, type, op, comm).finish(bound);
}

Pending startAllreduce(const void* in, void* out, int count, MPI_Datatype type, MPI_Op op,
                       MPI_Comm comm) {
  MPI_Request request;
  checkMpi(MPI_Iallreduce(in, out, count, type, op, comm, &request), "MPI_Iallreduce");
  return Pending(request);
}

namespace collectives {

void gatherBytes(const void* mine, void* all, int bytes, int root, MPI_Comm comm,
                 const Bound& bound) {
  MPI_Request request;
  checkMpi(MPI_Igather(mine, bytes, MPI_BYTE, all, bytes, MPI_BYTE, root, comm, &request),
           "MPI_Igather");
  Pending(request).finish(bound);
}

void allgatherBytes(const void* mine, void* all, int bytes, MPI_Comm comm, const Bound& bound) {
  MPI_Request request;
  checkMpi(MPI_Iallgather(mine, bytes, MPI_BYTE, all, bytes, MPI_BYTE, comm, &request),
           "MPI_Iallgather");
  Pending(request).finish(bound);
}

int countOf(std::size_t values, const Bound& bound) {
  if (values > kMaxCount) tooLarge(bound, values);
  return static_cast<int>(values);
}

std::size_t layOut(const std::vector<int>& counts, std::vector<int>& offsets, const Bound& bound) {
  offsets.resize(counts.size());
  std::size_t total = 0;
  for (std::size_t r = 0; r < counts.size(); ++r) {
    offsets[r] = static_cast<int>(total);
    total += static_cast<std::size_t>(counts[r]);
    if (total > kMaxCount) tooLarge(bound, total);
  }
  return total;
}

Pending startGatherv(const void* mine, int count, void* all, const std::vector<int>& counts,
                     const std::vector<int>& offsets, std::size_t valueBytes, int root,
                     MPI_Comm comm) {
  const ValueType value(valueBytes);
  MPI_Request request;
  checkMpi(MPI_Igatherv(mine, count, value.type, all, counts.data(), offsets.data(), value.type,
                        root, comm, &request),
           "MPI_Igatherv");
  return Pending(request);
}

Pending startAllgatherv(const void* mine, int count, void* all, const std::vector<int>& counts,
                        const std::vector<int>& offsets, std::size_t valueBytes, MPI_Comm comm) {
  const ValueType value(valueBytes);
  MPI_Request request;
  checkMpi(MPI_Iallgatherv(mine, count, value.type, all, counts.data(), offsets.data(), value.type,
                           comm, &request),
           "MPI_Iallgatherv");
  return Pending(request);
}

}  // namespace collectives
}  // namespace base
