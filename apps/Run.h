#pragma once

namespace app {

// Initialises MPI, parses and checks the command line and the input files on every rank, agrees
// on success (bad input: one precise message from one rank, every rank exits non-zero), then
// runs this rank's role. A failure while frames are in flight aborts the whole job, so no rank
// is left waiting.
int run(int argc, char** argv);

}  // namespace app
