#include "apps/Failure.h"

#include <mpi.h>

#include <cstdio>
#include <cstdlib>
#include <new>

#include "base/Error.h"
#include "base/MemoryBudget.h"

namespace app {

FailurePath::FailurePath(int worldRank) : rank_(worldRank) {
  char name[MPI_MAX_PROCESSOR_NAME];
  int length = 0;
  if (MPI_Get_processor_name(name, &length) == MPI_SUCCESS)
    host_.assign(name, static_cast<size_t>(length));
}

void FailurePath::setWhoIsSilent(std::function<std::string()> whoIsSilent) {
  std::lock_guard lock(mutex_);
  whoIsSilent_ = std::move(whoIsSilent);
}

void FailurePath::fail(const std::exception& e) {
  std::string what = e.what();
  // Loaders name what they load (base/MemoryBudget.h); this is the net for the rest.
  if (dynamic_cast<const std::bad_alloc*>(&e))
    what = "out of memory (an allocation failed); this rank may hold " + base::memoryLimitText();
  if (dynamic_cast<const base::DeadlineError*>(&e)) {
    std::function<std::string()> ask;
    {
      std::lock_guard lock(mutex_);
      ask = whoIsSilent_;
    }
    if (ask)
      if (const std::string silent = ask(); !silent.empty())
        what += " [not answering: " + silent + "]";
  }
  fail(what);
}

void FailurePath::fail(const std::string& what) {
  mutex_.lock();  // never unlocked: the process ends below
  std::fprintf(stderr, "dfbwall: error on rank %d (%s): %s\n", rank_, host_.c_str(), what.c_str());
  std::fflush(stderr);
  MPI_Abort(MPI_COMM_WORLD, 1);
  std::_Exit(1);  // MPI_Abort does not return; if an MPI ever did, still no destructors
}

}  // namespace app
