#pragma once

namespace app {

// Initialises MPI, parses and checks the command line, the input files and the outputs on every
// rank, agrees on success (bad input: one precise message from one rank, every rank exits
// non-zero), then runs this rank's role. A failure after that goes through the one failure path
// (apps/Failure.h): cause printed once, the whole job aborted. A stop signal ends the run
// gracefully (apps/RunControl.h). Returns the exit code.
int run(int argc, char** argv);

struct Options;
class StopSignals;
class FailurePath;
// `dfbwall serve`: every rank is a wall process of options.wall's layout, serving render jobs
// until stopped (wall/service/server/WallService.h). Returns the exit code.
int runServe(const Options& options, int worldRank, StopSignals& signals, FailurePath& failure);

// `dfbwall relay ...` (argv from "relay" on): forwards render jobs to a serving wall
// (wall/service/relay/Relay.h); no MPI. Returns the exit code.
int runRelay(int argc, char** argv, StopSignals& signals);

// `dfbwall keygen DIR` (argv from "keygen" on): writes a CURVE key pair for serve --curve DIR;
// no MPI. Returns the exit code.
int runKeygen(int argc, char** argv);

}  // namespace app
