#pragma once
// Small helpers for tests that run on several ranks (under tests/mpi_test_main.cpp).
#include <mpi.h>

namespace testutil {

inline int worldRank() {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  return rank;
}

inline int worldSize() {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  return size;
}

}  // namespace testutil
