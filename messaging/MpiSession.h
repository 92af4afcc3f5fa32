#pragma once
// Owns MPI_Init_thread / MPI_Finalize for a process. The Messenger's thread runs MPI calls
// beside collectives issued by the application thread, so it needs MPI_THREAD_MULTIPLE; a lower
// level is an error with a clear message, not a silent data race.
#include <mpi.h>

namespace messaging {

class MpiSession {
 public:
  MpiSession(int* argc, char*** argv);
  ~MpiSession();
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;

  int worldRank() const { return rank_; }
  int worldSize() const { return size_; }

 private:
  int rank_ = 0;
  int size_ = 1;
};

}  // namespace messaging
