#include <gtest/gtest.h>
#include <mpi.h>

#include <cstdio>

#include "messaging/MpiSession.h"

namespace {

// The other ranks print no progress, but each failure with its rank, file and line: a failure on
// one rank only would otherwise show as a bare "tests failed on this rank".
class FailurePrinter : public ::testing::EmptyTestEventListener {
 public:
  explicit FailurePrinter(int rank) : rank_(rank) {}
  void OnTestPartResult(const ::testing::TestPartResult& result) override {
    if (!result.failed()) return;
    const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
    std::fprintf(stderr, "[rank %d] %s.%s failed at %s:%d\n%s\n", rank_,
                 test ? test->test_suite_name() : "?", test ? test->name() : "?",
                 result.file_name() ? result.file_name() : "?", result.line_number(),
                 result.message());
  }

 private:
  int rank_;
};

}  // namespace

int main(int argc, char** argv) {
  try {
    messaging::MpiSession mpi(&argc, &argv);
    ::testing::InitGoogleTest(&argc, argv);
    if (mpi.worldRank() != 0) {
      // Only rank 0 prints progress; every rank still prints its failures.
      auto& listeners = ::testing::UnitTest::GetInstance()->listeners();
      delete listeners.Release(listeners.default_result_printer());
      listeners.Append(new FailurePrinter(mpi.worldRank()));
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
