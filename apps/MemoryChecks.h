#pragma once
// The memory budget (base/MemoryBudget.h) of what a job allocates for its canvas, checked at
// setup on the rank that will hold it, before any frame: the frame buffer's tiles a render rank
// owns, the image render rank 0 gathers (--image), the display frames a wall process holds and,
// with --capture, the whole-wall preview wall process 0 composes. Estimates of the real
// buffers (see the .cpp), so a --size or a layout asking for more than the rank has is one named
// error, not an allocation failure in the first frame.
#include <string>

#include "apps/Job.h"

namespace app {

// Empty when this rank's canvas buffers fit, else the error naming the option and the bytes.
// Needs job.roles, job.canvasWidth/Height and, for wall ranks, job.layout.
std::string canvasMemoryProblem(const Job& job);

// The MPI ranks of this job on this host, from the launcher's environment (Open MPI, MPICH);
// 1 when it does not say.
int ranksOnThisHost();

}  // namespace app
