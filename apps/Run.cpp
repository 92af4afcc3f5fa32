#include "apps/Run.h"

#include <cstdio>
#include <exception>
#include <string>

#include "apps/Job.h"
#include "dfb/MpiSession.h"
#include "renderers/BuiltinScenes.h"
#include "wall/Error.h"

namespace app {
namespace {

// Every rank calls this with its own verdict; the lowest failing rank prints its message, so a
// problem every rank finds (a bad layout) is printed once. True when every rank is fine.
bool agree(const std::string& problem, int rank) {
  int failing = problem.empty() ? 1 << 30 : rank, first = 0;
  MPI_Allreduce(&failing, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  if (first == rank) std::fprintf(stderr, "dfbwall: error: %s\n", problem.c_str());
  return first == 1 << 30;
}

std::string setUp(Job& job, int worldSize) {
  try {
    Options& o = job.options;
    if (!o.wall.empty()) {
      job.layout = wall::loadLayout(o.wall);
      if (auto problem = wall::checkRankCount(*job.layout, worldSize)) return *problem;
      job.roles = wall::rankRoles(*job.layout, worldSize);
      job.canvasWidth = job.layout->canvasWidth;
      job.canvasHeight = job.layout->canvasHeight;
      if (job.isWallRank()) {
        char name[MPI_MAX_PROCESSOR_NAME];
        int length = 0;
        MPI_Get_processor_name(name, &length);
        for (const std::string& w :
             wall::hostWarnings(*job.layout, job.roles.processOfRank(job.worldRank),
                                std::string(name, static_cast<size_t>(length))))
          std::fprintf(stderr, "dfbwall: warning: %s\n", w.c_str());
      }
    } else {
      job.roles = wall::RankRoles{worldSize, 0};
      job.canvasWidth = o.width;
      job.canvasHeight = o.height;
    }
    if (!job.isWallRank() && !o.dryRun)
      job.scene = std::make_shared<renderers::Scene>(renderers::loadSceneDesc(o.scene));
    return {};
  } catch (const std::exception& e) {
    return e.what();
  }
}

}  // namespace

int run(int argc, char** argv) {
  std::unique_ptr<dfb::MpiSession> mpi;
  try {
    mpi = std::make_unique<dfb::MpiSession>(&argc, &argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dfbwall: error: %s\n", e.what());
    return 1;
  }
  Job job;
  job.worldRank = mpi->worldRank();
  const int parsed = parseOptions(argc, argv, job.options, job.worldRank == 0);
  if (parsed >= 0) return parsed;
  if (!agree(setUp(job, mpi->worldSize()), job.worldRank)) return 1;
  if (job.options.dryRun) {
    if (job.worldRank == 0) printDryRun(job);
    return 0;
  }

  MPI_Comm roleComm;
  MPI_Comm_split(MPI_COMM_WORLD, job.isWallRank() ? 1 : 0, job.worldRank, &roleComm);
  try {
    dfb::MessengerOptions messaging;
    messaging.compress = job.options.compress;
    messaging.quiesceTimeout = std::chrono::seconds(job.options.timeoutSeconds);
    dfb::Messenger messenger(MPI_COMM_WORLD, messaging);
    if (job.isWallRank()) {
      runWallRank(job, messenger, roleComm);
    } else {
      const std::vector<FrameRecord> frames = runRenderRank(job, messenger, roleComm);
      if (job.worldRank == 0 && !job.options.statsFile.empty()) writeStats(job, frames);
    }
    messenger.stop();
  } catch (const std::exception& e) {
    // Other ranks may be inside a collective this rank will never join: end them all.
    std::fprintf(stderr, "dfbwall: error on rank %d: %s\n", job.worldRank, e.what());
    std::fflush(stderr);
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  MPI_Comm_free(&roleComm);
  return 0;
}

}  // namespace app
