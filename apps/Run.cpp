#include "apps/Run.h"

#include <cstdio>
#include <cstdlib>
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
      job.scene = renderers::buildRenderScene(o.renderer, renderers::loadSceneDesc(o.scene));
    return {};
  } catch (const std::exception& e) {
    return e.what();
  }
}

// Every rank's totals to rank 0, and the displays' completion times into rank 0's records.
// Collective over MPI_COMM_WORLD; called by every rank when --stats is given.
std::vector<RankTotals> collectTotals(const Job& job, RankTotals mine,
                                      std::vector<FrameRecord>& frames,
                                      const std::vector<std::int64_t>& completeNs) {
  int size = 0;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  mine.peakRssKiB = peakRssKiB();
  std::vector<RankTotals> all(job.worldRank == 0 ? static_cast<size_t>(size) : 0);
  static_assert(sizeof(RankTotals) == (RankTotals::kStages + 2) * sizeof(double));
  MPI_Gather(&mine, RankTotals::kStages + 2, MPI_DOUBLE, all.data(), RankTotals::kStages + 2,
             MPI_DOUBLE, 0, MPI_COMM_WORLD);
  std::vector<std::int64_t> local(static_cast<size_t>(job.options.frames), 0),
      latest(local.size(), 0);
  for (size_t i = 0; i < completeNs.size() && i < local.size(); ++i) local[i] = completeNs[i];
  MPI_Reduce(local.data(), latest.data(), static_cast<int>(local.size()), MPI_INT64_T, MPI_MAX, 0,
             MPI_COMM_WORLD);
  for (size_t i = 0; i < frames.size() && i < latest.size(); ++i)
    frames[i].displaysCompleteNs = latest[i];
  return all;
}

// Other ranks may be inside a collective this rank will never join: end them all.
[[noreturn]] void abortJob(int rank, const char* what) {
  std::fprintf(stderr, "dfbwall: error on rank %d: %s\n", rank, what);
  std::fflush(stderr);
  MPI_Abort(MPI_COMM_WORLD, 1);
  std::abort();  // MPI_Abort does not return
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
    messaging.compressWithinHost = job.options.compressWithinHost;
    messaging.quiesceTimeout = std::chrono::seconds(job.options.timeoutSeconds);
    dfb::Messenger messenger(MPI_COMM_WORLD, messaging);
    try {
      RankTotals totals;
      std::vector<FrameRecord> frames;
      std::vector<std::int64_t> completeNs;
      if (job.isWallRank())
        completeNs = runWallRank(job, messenger, roleComm, totals);
      else
        frames = runRenderRank(job, messenger, roleComm, totals);
      if (!job.options.statsFile.empty()) {
        const std::vector<RankTotals> ranks = collectTotals(job, totals, frames, completeNs);
        if (job.worldRank == 0) writeStats(job, frames, ranks);
      }
      messenger.stop();
    } catch (const std::exception& e) {
      // Here, not after unwinding: the messenger's destructor would first wait up to --timeout
      // for the other ranks to quiesce, so the message would come a whole timeout late.
      abortJob(job.worldRank, e.what());
    }
  } catch (const std::exception& e) {
    abortJob(job.worldRank, e.what());
  }
  MPI_Comm_free(&roleComm);
  return 0;
}

}  // namespace app
