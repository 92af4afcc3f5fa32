#include "renderers/FrameDriver.h"

#include <atomic>

#include "base/Parallel.h"
#include "base/Timing.h"

namespace renderers {

struct FrameDriver::Impl {
  Renderer& renderer;
  FrameDriverOptions options;
  base::ThreadLimit threads;
  // Shared with the DFB's expectedInputs callback, which begin() calls on this thread.
  std::shared_ptr<WorkPlan> plan = std::make_shared<WorkPlan>();
  Impl(Renderer& r, FrameDriverOptions o) : renderer(r), options(o), threads(o.threads) {}
};

namespace {

// Plans over the active tiles as if they were the whole image, then maps back to tile indices.
WorkPlan planActiveTiles(const FrameDriverOptions& options, int tileCount, int ranks,
                         std::span<const float> errors) {
  const std::vector<bool>& active = options.activeTiles;
  std::vector<int> tiles;
  std::vector<float> activeErrors;
  for (int t = 0; t < tileCount; ++t)
    if (t < static_cast<int>(active.size()) && active[static_cast<std::size_t>(t)]) {
      tiles.push_back(t);
      if (!errors.empty()) activeErrors.push_back(errors[static_cast<std::size_t>(t)]);
    }
  WorkPlan plan = planWork(static_cast<int>(tiles.size()), ranks, options.samplesPerPixel,
                           activeErrors, options.distribution, options.dynamic);
  for (auto& assignments : plan.perRank)
    for (Assignment& a : assignments) a.tile = tiles[static_cast<std::size_t>(a.tile)];
  std::vector<int> inputs(static_cast<std::size_t>(tileCount), 0);
  for (std::size_t i = 0; i < tiles.size(); ++i)
    inputs[static_cast<std::size_t>(tiles[i])] = plan.inputsPerTile[i];
  plan.inputsPerTile = std::move(inputs);
  return plan;
}

}  // namespace

dfb::OwnershipFunction activeTileOwnership(std::vector<bool> activeTiles) {
  std::vector<int> activeIndex(activeTiles.size(), -1);
  int next = 0;
  for (std::size_t t = 0; t < activeTiles.size(); ++t)
    if (activeTiles[t]) activeIndex[t] = next++;
  return [activeIndex](int tile, int, int ranks) {
    const int i = tile < static_cast<int>(activeIndex.size())
                      ? activeIndex[static_cast<std::size_t>(tile)]
                      : -1;
    return i < 0 ? 0 : i % ranks;
  };
}

FrameDriver::FrameDriver(Renderer& renderer, FrameDriverOptions options)
    : impl_(std::make_unique<Impl>(renderer, options)) {}

FrameDriver::~FrameDriver() = default;

void FrameDriver::configure(dfb::DfbOptions& options) const {
  std::shared_ptr<const WorkPlan> plan = impl_->plan;
  options.expectedInputs = [plan](int tile) {
    return tile >= 0 && static_cast<std::size_t>(tile) < plan->inputsPerTile.size()
               ? plan->inputsPerTile[static_cast<std::size_t>(tile)]
               : 1;
  };
}

const WorkPlan& FrameDriver::lastPlan() const { return *impl_->plan; }

void FrameDriver::setSamplesPerPixel(std::uint32_t samples) {
  impl_->options.samplesPerPixel = samples;
}

FrameReport FrameDriver::renderFrame(dfb::DistributedFrameBuffer& dfb, const dfb::FrameInfo& frame,
                                     const CameraDesc& camera) {
  using base::Clock;
  const auto t0 = Clock::now();
  Impl& m = *impl_;
  const dfb::TileGrid& grid = dfb.grid();
  if (m.options.activeTiles.empty()) {
    *m.plan = planWork(grid.tileCount(), dfb.ranks(), m.options.samplesPerPixel, dfb.tileErrors(),
                       m.options.distribution, m.options.dynamic);
  } else {
    *m.plan = planActiveTiles(m.options, grid.tileCount(), dfb.ranks(), dfb.tileErrors());
  }
  m.renderer.beginFrame(frame, camera);
  dfb.begin(frame);
  const auto t1 = Clock::now();
  const std::uint32_t accumulationId = dfb.accumulationId();
  const std::vector<Assignment>& mine = m.plan->perRank[dfb.rank()];
  FrameReport report;
  // Rendering alone, in CPU time: setTile() may do the owner's per-pixel work (tone mapping,
  // routing) on this thread too, and the DFB times that itself.
  std::atomic<std::int64_t> renderCpuNs{0};
  base::parallelFor(mine.size(), [&](std::size_t i) {
    dfb::Tile tile;
    const Assignment& a = mine[i];
    const std::int64_t cpu = base::threadCpuNs();
    m.renderer.render(grid.region(a.tile), accumulationId, a.firstSample, a.samples, tile);
    renderCpuNs += base::threadCpuNs() - cpu;
    dfb.setTile(std::move(tile));
  });
  const auto t2 = Clock::now();
  dfb.end();
  report.tilesRendered = static_cast<int>(mine.size());
  for (const Assignment& a : mine)
    report.samples += std::uint64_t{a.samples} * grid.region(a.tile).pixelCount();
  report.renderMs = base::msBetween(t1, t2);
  report.renderCpuMs = static_cast<double>(renderCpuNs.load()) * 1e-6;
  report.frameMs = base::msBetween(t0, Clock::now());
  return report;
}

}  // namespace renderers
