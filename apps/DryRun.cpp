// --dry-run: what the job would do, without rendering.
#include <algorithm>
#include <cstdio>

#include "apps/Job.h"
#include "renderers/BuiltinScenes.h"
#include "renderers/FrameDriver.h"
#include "renderers/scivis/bricks/BrickPlan.h"
#include "wall/route/Routing.h"

namespace app {

void printDryRun(const Job& job) {
  const Options& o = job.options;
  const wall::Layout& layout = *job.layout;
  std::printf("layout %s: canvas %dx%d, %zu displays, %d wall processes\n", layout.file.c_str(),
              layout.canvasWidth, layout.canvasHeight, layout.displays.size(), layout.processCount);
  if (job.connected()) {
    std::printf("wall service at %s (protocol %u, session %016llx, %u frames in flight):\n",
                o.connect.c_str(), static_cast<unsigned>(wall::service::kProtocolVersion),
                static_cast<unsigned long long>(job.directory->session),
                job.directory->framesInFlight);
    const dfb::Region& w = job.directory->window;
    std::printf("  window %d,%d,%d,%d of the wall's canvas (the canvas above)\n", w.x0, w.y0,
                w.width(), w.height());
    for (size_t p = 0; p < job.directory->processes.size(); ++p)
      std::printf("  wall process %zu: pieces to %s\n", p,
                  job.directory->processes[p].endpoint.c_str());
    std::printf("ranks: 0..%d render, every one sends its pieces straight to the wall (codec %s)\n",
                job.roles.renderRanks - 1, wall::service::codecName(job.codec).c_str());
  } else {
    std::printf("ranks: 0..%d render, %d..%d wall\n", job.roles.renderRanks - 1,
                job.roles.renderRanks, job.roles.worldSize() - 1);
  }
  const std::vector<bool> active = wall::tilesShownByAnyDisplay(layout, o.tileSize);
  int shown = 0;
  for (bool a : active) shown += a;
  std::printf(
      "tiles: %zu of %d px, %d shown by some display (the rest are not rendered in route mode)\n",
      active.size(), o.tileSize, shown);
  const dfb::OwnershipFunction owner = job.gatherMode()
                                           ? dfb::OwnershipFunction(dfb::roundRobinOwner)
                                           : renderers::activeTileOwnership(active);
  for (size_t d = 0; d < layout.displays.size(); ++d) {
    const wall::Display& display = layout.displays[d];
    const auto tiles = wall::tilesOfDisplay(layout, static_cast<int>(d), o.tileSize);
    std::printf("display %-8s %4dx%-4d at (%d, %d), wall process %d (rank %d)%s%s, %zu tiles:",
                display.name.c_str(), display.rect.width(), display.rect.height(), display.rect.x0,
                display.rect.y0, display.process,
                job.connected() ? -1 : job.roles.rankOfProcess(display.process),
                display.host.empty() ? "" : ", host ", display.host.c_str(), tiles.size());
    for (const wall::DisplayTile& t : tiles)
      std::printf(" %d@r%d", t.tileIndex,
                  owner(t.tileIndex, static_cast<int>(active.size()), job.roles.renderRanks));
    std::printf("\n");
  }
  if (o.bricks > 0) {
    // The data-parallel plan: every brick, its bounds and the render ranks that load it. A
    // tile's brick is rendered by holder (tile + brick) mod K of the K holders.
    const renderers::SceneDesc desc = renderers::loadSceneDesc(o.scene);
    const auto bricks = renderers::scivis::splitScene(desc, o.bricks);
    std::printf(
        "bricks: %zu, each on %d render rank(s); tile-brick owner = holders[(tile + brick) %% K]\n",
        bricks.size(), std::min(o.replication, job.roles.renderRanks));
    const renderers::scivis::GhostMode ghost = renderers::scivis::ghostModeFromName(o.ghost);
    const renderers::scivis::GhostReach reach = renderers::scivis::ghostReach(desc, ghost);
    std::printf(
        "ghost: %s, %g world units beyond each brick plus a layer of 2 voxels, and for shadows "
        "the brick swept towards %zu light(s) to the domain's boundary\n",
        renderers::scivis::ghostModeName(ghost), reach.margin, reach.lights.size());
    for (const renderers::scivis::BrickPlan& b : bricks) {
      std::printf("brick %d [%g %g %g]..[%g %g %g] on ranks", b.id, b.bounds.lo.x, b.bounds.lo.y,
                  b.bounds.lo.z, b.bounds.hi.x, b.bounds.hi.y, b.bounds.hi.z);
      for (int r : renderers::scivis::brickHolders(b.id, job.roles.renderRanks, o.replication))
        std::printf(" %d", r);
      std::printf("\n");
    }
  }
}

}  // namespace app
