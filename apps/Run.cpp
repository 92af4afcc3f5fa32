#include "apps/Run.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <new>
#include <string>

#include "apps/ControlApi.h"
#include "apps/ControlServer.h"
#include "apps/Failure.h"
#include "apps/Job.h"
#include "apps/MemoryChecks.h"
#include "apps/PageRoutes.h"
#include "apps/Preview.h"
#include "apps/RunControl.h"
#include "apps/Stats.h"
#include "apps/StatusBoard.h"
#include "apps/Steering.h"
#include "apps/StopSignals.h"
#include "apps/WallKeys.h"
#include "base/AtomicFile.h"
#include "base/Collectives.h"
#include "base/Error.h"
#include "base/MemoryBudget.h"
#include "messaging/MpiSession.h"
#include "renderers/BuiltinScenes.h"
#include "renderers/picture/PictureRenderer.h"
#include "renderers/scivis/bricks/BrickLoad.h"
#include "renderers/scivis/bricks/BrickPlan.h"
#include "renderers/scivis/io/SciVisDesc.h"
#include "runtime/RoomView.h"
#include "runtime/SetupAgreement.h"
#include "runtime/WallControl.h"
#include "wall/display/Capture.h"
#include "wall/layout/Window.h"
#include "wall/service/client/ServiceClient.h"

namespace app {
namespace {

// This process's rank as the MPI launcher gave it (OpenMPI, then PMIx and MPICH's names); 0
// when started without one.
int launcherRank() {
  for (const char* name : {"OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK"})
    if (const char* value = std::getenv(name)) return std::atoi(value);
  return 0;
}

// Every rank calls this with its own verdict; the lowest failing rank prints its message, so a
// problem every rank finds (a bad layout) is printed once. True when every rank is fine.
bool agree(const std::string& problem, int rank, std::chrono::milliseconds timeout) {
  const std::optional<int> first =
      runtime::firstRankWithProblem(problem, MPI_COMM_WORLD, timeout, "setup");
  if (first == rank) std::fprintf(stderr, "dfbwall: error: %s\n", problem.c_str());
  return !first;
}

// FNV-1a of a file's bytes, continuing from `hash` (unchanged when the file cannot be read: the
// loaders report that themselves). A file over kWholeHashBytes (a raw volume that ranks read
// brick by brick) contributes its size and its first and last MiB: reading all of it on every
// rank would cost more than the check is worth.
constexpr long kWholeHashBytes = 64L << 20, kSampleBytes = 1L << 20;
std::uint64_t hashFile(const std::string& path, std::uint64_t hash = 0xcbf29ce484222325ull) {
  FILE* in = std::fopen(path.c_str(), "rb");
  if (!in) return hash;
  auto mix = [&hash](const unsigned char* bytes, size_t n) {
    for (size_t i = 0; i < n; ++i) hash = (hash ^ bytes[i]) * 0x100000001b3ull;
  };
  auto mixRange = [&](long from, long bytes) {
    std::fseek(in, from, SEEK_SET);
    unsigned char buffer[65536];
    for (size_t n;
         bytes > 0 &&
         (n = std::fread(buffer, 1, std::min(sizeof buffer, static_cast<size_t>(bytes)), in)) > 0;
         bytes -= static_cast<long>(n))
      mix(buffer, n);
  };
  std::fseek(in, 0, SEEK_END);
  const long size = std::ftell(in);
  if (size <= kWholeHashBytes) {
    mixRange(0, size);
  } else {
    mixRange(0, kSampleBytes);
    mixRange(size - kSampleBytes, kSampleBytes);
  }
  mix(reinterpret_cast<const unsigned char*>(&size), sizeof size);
  std::fclose(in);
  return hash;
}

// `dfbwall show`: a scene of nothing but its pictures, drawn by the picture renderer.
renderers::SceneDesc showScene(const ShowOptions& show) {
  renderers::picture::PictureDesc desc;
  desc.files = show.files;
  desc.filter = renderers::picture::filterFromName(show.filter);
  desc.background = show.background;
  desc.loop = show.loop;
  return renderers::picture::pictureScene(desc);
}

struct InputHashes {
  std::uint64_t layout = 0, scene = 0;
};

// Outputs are checked before any frame: a folder that cannot take files fails the setup, on
// the rank that will write there, not after the last frame.
std::string checkOutputs(const Job& job) {
  const Options& o = job.options;
  if (job.isWallRank() && !o.captureDir.empty())
    if (std::string problem = wall::checkCaptureFolders(o.captureDir, *job.layout,
                                                        job.roles.processOfRank(job.worldRank));
        !problem.empty())
      return "--capture " + problem;
  if (job.worldRank == 0 && !o.image.empty()) {
    const std::string folder = std::filesystem::path(o.image).parent_path().string();
    if (std::string problem = base::checkWritableFolder(folder.empty() ? "." : folder);
        !problem.empty())
      return "--image " + problem;
  }
  if (job.worldRank == 0 && !o.previewFile.empty()) {
    const std::string folder = std::filesystem::path(o.previewFile).parent_path().string();
    if (std::string problem = base::checkWritableFolder(folder.empty() ? "." : folder);
        !problem.empty())
      return "--preview " + problem;
  }
  return {};
}

std::string setUp(Job& job, int worldSize, std::unique_ptr<StatsStream>& stats,
                  std::unique_ptr<ControlServer>& server, InputHashes& hashes) {
  try {
    Options& o = job.options;
    if (!o.wall.empty()) {
      hashes.layout = hashFile(o.wall);
      job.layout = wall::loadLayout(o.wall);
      if (auto problem = wall::checkRankCount(*job.layout, worldSize)) return *problem;
      job.roles = wall::rankRoles(*job.layout, worldSize);
      job.canvasWidth = job.layout->canvasWidth;
      job.canvasHeight = job.layout->canvasHeight;
      job.room = runtime::roomView(*job.layout);
      if (job.isWallRank()) {
        char name[MPI_MAX_PROCESSOR_NAME];
        int length = 0;
        MPI_Get_processor_name(name, &length);
        for (const std::string& w :
             wall::hostWarnings(*job.layout, job.roles.processOfRank(job.worldRank),
                                std::string(name, static_cast<size_t>(length))))
          std::fprintf(stderr, "dfbwall: warning: %s\n", w.c_str());
      }
    } else if (!o.viewLayout.empty()) {  // --view: the wall's canvas, some displays' pictures
      hashes.layout = hashFile(o.viewLayout);
      const wall::Layout layout = wall::loadLayout(o.viewLayout);
      for (std::size_t from = 0; from <= o.view.size();) {
        const std::size_t comma = std::min(o.view.find(',', from), o.view.size());
        const std::string name = o.view.substr(from, comma - from);
        from = comma + 1;
        const int display = layout.findDisplay(name);
        if (display < 0) {
          std::string names;
          for (const wall::Display& d : layout.displays)
            names += (names.empty() ? "" : ", ") + d.name;
          return "--view " + name + ": " + o.viewLayout + " has no such display (it has " + names +
                 ")";
        }
        job.views.push_back({name, layout.displays[static_cast<std::size_t>(display)].rect});
      }
      if (job.views.size() > 1 && o.image.find(kViewedDisplay) == std::string::npos)
        return "--view with several displays writes one image each: put " +
               std::string(kViewedDisplay) + " in --image's name (got " + o.image + ")";
      job.roles = wall::RankRoles{worldSize, 0};
      job.canvasWidth = layout.canvasWidth;
      job.canvasHeight = layout.canvasHeight;
      job.room = runtime::roomView(layout);
    } else {
      job.roles = wall::RankRoles{worldSize, 0};
      job.canvasWidth = o.width;
      job.canvasHeight = o.height;
    }
    if (std::string problem = canvasMemoryProblem(job); !problem.empty()) return problem;
    if (!job.isWallRank() && !o.dryRun) {
      renderers::SceneDesc desc =
          o.show ? showScene(o.pictures) : renderers::loadSceneDesc(o.scene);
      if (o.show) {
        for (const std::string& file : desc.inputFiles())
          hashes.scene = hashFile(file, hashes.scene);
      } else if (o.scene.rfind("builtin:", 0) != 0) {
        hashes.scene = hashFile(o.scene);
        for (const std::string& file : desc.inputFiles())
          hashes.scene = hashFile(file, hashes.scene);
      }
      job.scene = renderers::buildRenderScene(o.renderer, std::move(desc), o.bricks > 0);
      // Bricks load once the frames are set up; their memory is known now (render ranks are
      // world ranks 0 .. R-1, in order).
      if (o.bricks > 0)
        renderers::scivis::checkOwnBricksMemory(*job.scene.desc, o.bricks, o.replication,
                                                job.worldRank, job.roles.renderRanks,
                                                renderers::scivis::ghostModeFromName(o.ghost));
      if (job.worldRank == 0 && !o.cameraPath.empty())
        job.cameraPath = CameraPath::load(o.cameraPath, job.scene.desc->camera,
                                          renderers::scivis::timeSteps(*job.scene.desc));
    }
    // Bound now, so a port in use is a setup error on every rank (and a job's hello can name its
    // page); served once frames start.
    if (job.worldRank == 0 && !o.control.empty() && !o.dryRun)
      server = std::make_unique<ControlServer>(o.control, controlSecret(o.controlTokenFile),
                                               o.controlHosts);
    if (!o.connect.empty()) {
      job.roles = wall::RankRoles{worldSize, 0};  // every rank renders; the wall is elsewhere
      job.codec = wall::service::parseCodec(o.codec);
      if (job.worldRank == 0) {
        wall::service::Hello hello =
            wall::service::jobHello(worldSize, o.tileSize, job.codec, o.framesInFlight, o.wait,
                                    o.dryRun ? std::string() : o.captureDir, o.captureEvery);
        hello.window = wall::parseWindowRequest(o.window);
        // For the wall's window manager: what this job renders, and where its page is.
        std::string what = o.show ? "show" : o.renderer + " " + o.scene;
        if (o.show)
          for (const std::string& picture : o.pictures.arguments) what += " " + picture;
        hello.job = what.substr(0, 256);
        if (server) hello.page = server->pageAddress(hello.host);
        // The frame buffer, renderers, routing and preview (the job's page, --preview) are
        // re-planned for a moved window (RenderRank::replan).
        hello.canReshape = true;
        job.service = std::make_shared<wall::service::ServiceClient>(
            o.connect,
            wall::service::loadCredentials({o.token, o.tokenFile, {}, o.serverKey}, false), hello,
            std::chrono::seconds(o.timeoutSeconds), [](const std::string& queued) {
              std::printf("dfbwall: %s\n", queued.c_str());
              std::fflush(stdout);
            });
      }
    }
    if (o.dryRun) return {};
    if (std::string problem = checkOutputs(job); !problem.empty()) return problem;
    if (job.worldRank == 0 && !o.statsFile.empty()) {
      stats = std::make_unique<StatsStream>(o.statsFile);
      stats->writeRun(job);
    }
    return {};
  } catch (const std::bad_alloc&) {
    // Loaders name what they load; this is the net for whatever else allocates at setup.
    return "out of memory while setting up (the layout, the scene and its buffers); this rank "
           "may hold " +
           base::memoryLimitText();
  } catch (const std::exception& e) {
    return e.what();
  }
}

// Every rank must render and show the same layout and scene: a file that differs between hosts
// (a stale copy on one node) is an error, not a wall whose displays disagree.
std::string compareInputs(const Job& job, const InputHashes& mine,
                          std::chrono::milliseconds timeout) {
  std::uint64_t local[4] = {mine.layout, ~mine.layout, mine.scene, mine.scene ? ~mine.scene : 0};
  std::uint64_t high[4] = {0, 0, 0, 0};
  base::allreduce(local, high, 4, MPI_UINT64_T, MPI_MAX, MPI_COMM_WORLD,
                  base::Bound::joinWithin(timeout, "comparing inputs"));
  // max(h) == min(h) exactly when every rank's hash is the same; min(h) = ~max(~h).
  if (high[0] != ~high[1])
    return job.options.wall +
           ": the ranks read different bytes from this file; every host "
           "must see the same layout";
  if (high[2] != (high[3] ? ~high[3] : 0))
    return job.options.show
               ? std::string(
                     "show: the ranks read different bytes from the pictures; every "
                     "host must see the same files")
               : job.options.scene +
                     ": the render ranks read different bytes from this file or the files it "
                     "refers to; every host must see the same scene";
  return {};
}

// What the control API reports and checks against, of this job.
ControlFacts controlFacts(const Job& job) {
  ControlFacts facts{
      job.options.renderer, job.options.maxSpp, {}, job.layout && !job.options.captureDir.empty()};
  if (job.layout)
    for (const auto& d : job.layout->displays) facts.displays.push_back(d.name);
  return facts;
}

// Every rank's totals to rank 0. Collective over MPI_COMM_WORLD; only with --stats.
std::vector<RankTotals> collectTotals(RankTotals mine, std::chrono::milliseconds timeout) {
  mine.peakRssKiB = peakRssKiB();
  return base::gather(mine, 0, MPI_COMM_WORLD,
                      {.until = timeout,
                       .late = "collecting statistics: another rank did not send its totals in "
                               "time"});
}

// --connect: render rank 0 read the wall's directory; every rank routes with it.
void shareDirectory(Job& job, std::chrono::milliseconds timeout) {
  job.directory = wall::service::shareDirectory(MPI_COMM_WORLD, job.service.get(), timeout);
  job.credentials = wall::service::shareCredentials(MPI_COMM_WORLD, job.service.get(), timeout);
  job.layout = job.directory->layout;
  job.canvasWidth = job.layout->canvasWidth;
  job.canvasHeight = job.layout->canvasHeight;
}

}  // namespace

int run(int argc, char** argv) {
  // Before MPI or any library starts a thread: the stop signals stay blocked in all of them.
  StopSignals signals;
  // The relay runs on a gateway, alone: no MPI.
  if (argc > 1 && std::string(argv[1]) == "relay") return runRelay(argc - 1, argv + 1, signals);
  if (argc > 1 && std::string(argv[1]) == "keygen") return runKeygen(argc - 1, argv + 1);
  // The command line is read before MPI starts, so --help and a mistyped option answer at once
  // (a process started without mpirun would first spawn MPI's runtime); every rank reads the
  // same one, and the rank the launcher numbers 0 prints.
  Job job;
  const int parsed = parseOptions(argc, argv, job.options, launcherRank() == 0);
  if (parsed >= 0) return parsed;
  std::unique_ptr<messaging::MpiSession> mpi;
  try {
    mpi = std::make_unique<messaging::MpiSession>(&argc, &argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dfbwall: error: %s\n", e.what());
    return 1;
  }
  job.worldRank = mpi->worldRank();
  if (const char* at = std::getenv("DFBWALL_FAIL_AT"))
    std::sscanf(at, "%d:%u", &job.failAtRank, &job.failAtFrame);
  FailurePath failure(job.worldRank);
  job.failure = &failure;
  base::setMemoryLimit(job.options.memoryLimit);
  base::setRanksOnHost(ranksOnThisHost());
  if (job.options.serve) return runServe(job.options, job.worldRank, signals, failure);
  const std::chrono::milliseconds timeout = std::chrono::seconds(job.options.timeoutSeconds);

  // From here on, whatever goes wrong on this rank ends the job through the failure path,
  // before any destructor runs (a destructor could wait for a rank that is gone).
  try {
    std::unique_ptr<StatsStream> stats;
    std::unique_ptr<ControlServer> server;
    InputHashes hashes;
    if (!agree(setUp(job, mpi->worldSize(), stats, server, hashes), job.worldRank, timeout))
      return 1;
    if (!agree(compareInputs(job, hashes, timeout), job.worldRank, timeout)) return 1;
    if (!job.options.connect.empty()) shareDirectory(job, timeout);
    if (job.options.dryRun) {
      if (job.worldRank == 0) printDryRun(job);
      return 0;
    }

    MPI_Comm roleComm;
    base::checkMpi(
        MPI_Comm_split(MPI_COMM_WORLD, job.isWallRank() ? 1 : 0, job.worldRank, &roleComm),
        "MPI_Comm_split");
    messaging::MessengerOptions messaging;
    messaging.compress = job.options.compress;
    messaging.compressWithinHost = job.options.compressWithinHost;
    messaging.handlerThreads = job.options.handlerThreads;
    messaging.quiesceTimeout = timeout;
    messaging::Messenger messenger(MPI_COMM_WORLD, messaging);
    // A message that cannot be handled (malformed, for nobody, a handler that threw) is a
    // failure of the job now, not a frame that times out later under another name.
    messenger.setErrorCallback([&failure](const std::string& m) { failure.fail(m); });
    // Half a second for every rank's inbox thread to answer: a frame on a loaded host is slower,
    // but an answer is a few microseconds of work.
    failure.setWhoIsSilent(
        [&messenger] { return messenger.probePeers(std::chrono::milliseconds(500)); });
    // Unwinding destroys the messenger before the catch below: the question goes first.
    struct Forget {
      FailurePath& failure;
      ~Forget() { failure.setWhoIsSilent({}); }
    } forget{failure};
    RunControl control(messenger, signals);
    runtime::MpiWallControl wallControl(messenger, job.roles.renderRanks, job.roles.worldSize());
    std::unique_ptr<Preview> preview;
    if (!job.isWallRank() && job.previewWanted()) {
      preview = std::make_unique<Preview>(job, messenger);
      job.preview = preview.get();
    }
    Steering steering(messenger);
    // A job of a service wall: keys and the mouse over its window there steer it as its page
    // does (docs/service.md, "Several jobs at once"); never after `steering` goes.
    struct InputGuard {
      wall::service::ServiceClient* client;
      ~InputGuard() {
        if (client) client->onInput({});
      }
    } inputGuard{job.service.get()};
    if (job.service)
      job.service->onInput([&steering,
                            client = job.service.get()](const wall::service::WindowInput& in) {
        // A drag across the window orbits 180°: the window it came in, moved and resized or not.
        const wall::service::ServiceClient::Size size = client->windowSize();
        if (const std::optional<SteeringRequest> r = requestForInput(in, size.width, size.height)) {
          try {
            steering.submit(*r);
          } catch (const std::exception&) {
            // Out of range after all: the event is dropped, the job goes on.
          }
        }
      });
    std::unique_ptr<StatusBoard> status;
    if (server) {
      status = std::make_unique<StatusBoard>();
      addPageRoutes(server->requests(), *preview);  // the controller page and the preview
      addApiRoutes(
          server->requests(), controlFacts(job),
          [&steering](const SteeringRequest& r) { return steering.submit(r); }, *status);
      server->start();
      // One line a script can read: the address to open.
      std::printf("dfbwall: %s\n", server->startLine().c_str());
      std::fflush(stdout);
    }
    RankTotals totals;
    const int exitCode =
        job.isWallRank()
            ? runWallRank(job, messenger, roleComm, control, wallControl, steering, totals)
            : runRenderRank(job, messenger, roleComm, control, wallControl, steering, status.get(),
                            stats.get(), totals);
    if (!job.options.statsFile.empty()) {
      const std::vector<RankTotals> ranks = collectTotals(totals, timeout);
      const bool stoppedEarly = control.stopRequested().has_value() || exitCode != 0;
      if (stats) stats->writeEnd(ranks, stoppedEarly, exitCode);
    }
    if (server) server->stop();
    messenger.stop();
    MPI_Comm_free(&roleComm);
    return exitCode;
  } catch (const std::exception& e) {
    failure.fail(e);
  }
}

}  // namespace app
