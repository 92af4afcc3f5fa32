#include "apps/Preview.h"

#include "base/Error.h"
#include "wall/image/Png.h"
#include "wall/route/Routing.h"

namespace app {
namespace {

wall::PreviewGrid gridOf(int width, int height) {
  return {width, height, wall::previewFactor(width, height)};
}

// The tiles that complete every frame: in route mode those some display shows (the render
// ranks render no other, runRenderRank), otherwise all.
std::vector<bool> tilesOfFrame(const Job& job, const wall::Layout* layout, int width, int height) {
  if (layout && !job.gatherMode())
    return wall::tilesShownByAnyDisplay(*layout, job.options.tileSize);
  const dfb::TileGrid tiles(width, height, job.options.tileSize);
  return std::vector<bool>(static_cast<size_t>(tiles.tileCount()), true);
}

}  // namespace

Preview::Preview(const Job& job, messaging::Messenger& messenger)
    : job_(job), messenger_(messenger) {
  const wall::PreviewGrid grid = gridOf(job.canvasWidth, job.canvasHeight);
  op_ = std::make_shared<wall::PreviewOp>(messenger, grid);
  if (job.worldRank != 0) return;
  if (job.layout) layout_ = std::make_shared<const wall::Layout>(*job.layout);
  assembler_ = std::make_unique<wall::PreviewAssembler>(
      messenger, grid, job.options.tileSize,
      tilesOfFrame(job, layout_.get(), job.canvasWidth, job.canvasHeight));
}

void Preview::replan(const wall::Layout& layout, std::uint32_t fromFrame) {
  const wall::PreviewGrid grid = gridOf(layout.canvasWidth, layout.canvasHeight);
  op_ = std::make_shared<wall::PreviewOp>(messenger_, grid);
  if (!assembler_) return;
  std::lock_guard lock(pngMutex_);
  layout_ = std::make_shared<const wall::Layout>(layout);
  assembler_->restart(grid, job_.options.tileSize,
                      tilesOfFrame(job_, layout_.get(), layout.canvasWidth, layout.canvasHeight),
                      fromFrame);
  // The displays are the new window's: the roster's next word says which are lost.
  lost_.clear();
  png_ = {};
}

Preview::Png Preview::png() const {
  std::lock_guard lock(pngMutex_);
  const auto snapshot = assembler_->latest();
  if (!png_.bytes || png_.frame != snapshot->frame || lostChanged_) {
    png_.frame = snapshot->frame;
    png_.bytes = std::make_shared<const std::string>(wall::encodePng(
        wall::decoratePreview(snapshot->image, snapshot->grid, layout_.get(), lost_)));
    lostChanged_ = false;
  }
  return png_;
}

Preview::Canvas Preview::canvas() const {
  std::lock_guard lock(pngMutex_);
  return {layout_, assembler_->grid()};
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
  std::lock_guard lock(pngMutex_);
  const auto snapshot = assembler_->latest();
  wall::writePng(job_.options.previewFile,
                 wall::decoratePreview(snapshot->image, snapshot->grid, layout_.get(), lost_));
}

}  // namespace app
