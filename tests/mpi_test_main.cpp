#include <gtest/gtest.h>
#include <mpi.h>

#include <cstdio>

#include "messaging/MpiSession.h"

int main(int argc, char** argv) {
  try {
    messaging::MpiSession mpi(&argc, &argv);
    ::testing::InitGoogleTest(&argc, argv);
    if (mpi.worldRank() != 0) {
      // Only rank 0 prints progress; every rank still prints its failures.
      auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
      delete listeners.Release(listeners.default_result_printer());
    }
    int failed = RUN_ALL_TESTS() != 0;
    int anyFailed = 0;
    MPI_Allreduce(&failed, &anyFailed, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    if (failed) std::fprintf(stderr, "[rank %d] tests failed on this rank\n", mpi.worldRank());
    return anyFailed;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
