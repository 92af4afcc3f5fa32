#include "apps/Preview.h"

#include "base/Error.h"
#include "wall/image/Png.h"
#include "wall/route/Routing.h"

namespace app {

Preview::Preview(const Job& job, messaging::Messenger& messenger) : job_(job) {
  const wall::PreviewGrid grid{job.canvasWidth, job.canvasHeight,
                               wall::previewFactor(job.canvasWidth, job.canvasHeight)};
  op_ = std::make_shared<wall::PreviewOp>(messenger, grid);
  if (job.worldRank != 0) return;
  // The tiles that complete every frame: in route mode those some display shows (the render
  // ranks render no other, runRenderRank), otherwise all.
  std::vector<bool> activeTiles;
  if (job.layout && !job.gatherMode()) {
    activeTiles = wall::tilesShownByAnyDisplay(*job.layout, job.options.tileSize);
  } else {
    const dfb::TileGrid tiles(job.canvasWidth, job.canvasHeight, job.options.tileSize);
    activeTiles.assign(static_cast<size_t>(tiles.tileCount()), true);
  }
  assembler_ = std::make_unique<wall::PreviewAssembler>(messenger, grid, job.options.tileSize,
                                                        std::move(activeTiles));
}

Preview::Png Preview::png() const {
  const auto snapshot = assembler_->latest();
  std::lock_guard lock(pngMutex_);
  if (!png_.bytes || png_.frame != snapshot->frame || lostChanged_) {
    const wall::Layout* layout = job_.layout ? &*job_.layout : nullptr;
    png_.frame = snapshot->frame;
    png_.bytes = std::make_shared<const std::string>(
        wall::encodePng(wall::decoratePreview(snapshot->image, assembler_->grid(), layout, lost_)));
    lostChanged_ = false;
  }
  return png_;
}

void Preview::setLostDisplays(std::vector<bool> lost) {
  std::lock_guard lock(pngMutex_);
  if (lost != lost_) lostChanged_ = true;
  lost_ = std::move(lost);
}

void Preview::finish(std::uint32_t lastFrame, std::chrono::milliseconds timeout) const {
  if (!assembler_ || lastFrame == 0) return;
  if (!assembler_->waitFor(lastFrame, std::chrono::steady_clock::now() + timeout))
    throw base::Error("the preview of frame " + std::to_string(lastFrame) +
                      " did not arrive within --timeout");
  if (job_.options.previewFile.empty()) return;
  const auto snapshot = assembler_->latest();
  const wall::Layout* layout = job_.layout ? &*job_.layout : nullptr;
  std::vector<bool> lost;
  {
    std::lock_guard lock(pngMutex_);
    lost = lost_;
  }
  wall::writePng(job_.options.previewFile,
                 wall::decoratePreview(snapshot->image, assembler_->grid(), layout, lost));
}

}  // namespace app
