#include "runtime/SetupAgreement.h"

#include "base/Collectives.h"

namespace runtime {

std::optional<int> firstRankWithProblem(const std::string& problem, MPI_Comm comm,
                                        std::chrono::milliseconds timeout,
                                        const std::string& what) {
  int rank = 0, size = 0;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  int failing = problem.empty() ? size : rank, first = size;
  base::allreduce(&failing, &first, 1, MPI_INT, MPI_MIN, comm,
                  base::Bound::joinWithin(timeout, what));
  if (first == size) return std::nullopt;
  return first;
}

}  // namespace runtime
