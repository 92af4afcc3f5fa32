#pragma once
// Setup problems (a bad layout, a rank count it does not fit, a capture folder one wall process
// cannot write) may show on some ranks only: the ranks agree before anything else, so every rank
// fails together instead of some waiting for the others forever.
#include <mpi.h>

#include <chrono>
#include <optional>
#include <string>

namespace runtime {

// Collective over `comm`, each rank with its own `problem` (empty: none). The lowest rank that
// has one, or nullopt when every rank is fine.
std::optional<int> firstRankWithProblem(const std::string& problem, MPI_Comm comm,
                                        std::chrono::milliseconds timeout, const std::string& what);

}  // namespace runtime
