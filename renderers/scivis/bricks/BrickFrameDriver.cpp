#include "renderers/scivis/bricks/BrickFrameDriver.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>
#include <vector>

#include "base/Error.h"
#include "base/Parallel.h"
#include "base/Timing.h"
#include "dfb/TileOperation.h"
#include "renderers/scivis/bricks/BrickExchange.h"
#include "renderers/scivis/bricks/BrickOcclusion.h"
#include "renderers/scivis/bricks/BrickPlan.h"
#include "renderers/scivis/render/CameraRays.h"
#include "renderers/scivis/render/RayBlocks.h"

namespace renderers::scivis {
namespace {

constexpr float kInf = Box3::kInf;

// The pixel rectangle covering `box` seen by `camera` on a width x height canvas, or nothing
// (false) when a corner is behind or beside the camera's plane (then every tile may see it).
bool projectBox(const CameraDesc& c, int width, int height, const Box3& box, float& x0, float& y0,
                float& x1, float& y1) {
  const Vec3 forward = normalize(c.lookAt - c.position);
  const Vec3 right = normalize(cross(forward, c.up));
  const Vec3 up = cross(right, forward);
  const float halfHeight = std::tan(0.5f * c.fovY * kPi / 180.0f);
  const float halfWidth = halfHeight * static_cast<float>(width) / static_cast<float>(height);
  x0 = y0 = kInf;
  x1 = y1 = -kInf;
  for (int i = 0; i < 8; ++i) {
    const Vec3 p{(i & 1) ? box.hi.x : box.lo.x, (i & 2) ? box.hi.y : box.lo.y,
                 (i & 4) ? box.hi.z : box.lo.z};
    const Vec3 v = p - c.position;
    if (!inFrontOfCamera(v, forward)) return false;
    const float depth = dot(v, forward);
    const float sx = dot(v, right) / (depth * halfWidth), sy = dot(v, up) / (depth * halfHeight);
    const float px = (sx + 1) * 0.5f * static_cast<float>(width);
    const float py = (1 - sy) * 0.5f * static_cast<float>(height);
    x0 = std::min(x0, px), x1 = std::max(x1, px), y0 = std::min(y0, py), y1 = std::max(y1, py);
  }
  return true;
}

// The camera ray of sample `s` of pixel (x, y): exactly the ray the brick renderers trace.
void sampleRay(const Camera& camera, std::uint64_t seed, int x, int y, std::uint32_t accumulationId,
               std::uint32_t s, Vec3& origin, Vec3& dir) {
  const Sampler sampler(seed, x, y, accumulationId, s);
  camera.ray(static_cast<float>(x) + sampler.get(0), static_cast<float>(y) + sampler.get(1), 0.5f,
             0.5f, origin, dir);
}

// Whether any camera ray of `region` this frame enters or leaves `box` (the same test the brick's
// renderer clips with, so a brick counted here is one some sample renders, and one not counted
// is one no sample sees). A ray from inside the box leaves it: a camera inside a brick counts it.
bool raysMeetBox(const Camera& camera, std::uint64_t seed, const dfb::Region& region,
                 std::uint32_t accumulationId, std::uint32_t spp, const Box3& box) {
  for (int y = region.y0; y < region.y1; ++y)
    for (int x = region.x0; x < region.x1; ++x)
      for (std::uint32_t s = 0; s < spp; ++s) {
        Vec3 origin, dir;
        sampleRay(camera, seed, x, y, accumulationId, s, origin, dir);
        float a = 0, b = kInf;
        if (clipToBox(box, origin, reciprocal(dir), a, b)) return true;
      }
  return false;
}

// The distance to sort a brick's fragment of a pixel by: where the ray enters the brick, or, when
// it misses (another sample of the pixel may hit), the distance to the brick's nearest point.
float brickDepth(const Box3& b, Vec3 origin, Vec3 dir) {
  float t0 = 0, t1 = kInf;
  if (clipToBox(b, origin, reciprocal(dir), t0, t1)) return t0;
  const Vec3 nearest{std::clamp(origin.x, b.lo.x, b.hi.x), std::clamp(origin.y, b.lo.y, b.hi.y),
                     std::clamp(origin.z, b.lo.z, b.hi.z)};
  return length(nearest - origin);
}

// Whether a ray from `eye` can meet `front` before `back` (disjoint boxes): not when a plane
// between them has the eye strictly on back's side (along that axis the ray must cross back's
// side first). Only a filter: the per-ray test decides; leaving a brick out only skips less.
bool mayComeFirst(const Box3& front, const Box3& back, Vec3 eye) {
  for (int a = 0; a < 3; ++a) {
    if (front.hi[a] <= back.lo[a] && eye[a] > front.hi[a]) return false;
    if (back.hi[a] <= front.lo[a] && eye[a] < front.lo[a]) return false;
  }
  return true;
}

// A pixel of the background tile: the mean of the background along its `spp` rays (a constant
// background needs none: `rays` may be null).
void backgroundPixel(const Environment& background, const SciVisRenderer::RayPiece* rays,
                     std::uint32_t spp, float inv, float out[4]) {
  float sum[4] = {0, 0, 0, 0};
  for (std::uint32_t s = 0; s < spp; ++s) {
    const Vec3 bg = background.kind == Environment::Kind::Constant
                        ? background.color
                        : background.radiance(rays[s].dir);
    sum[0] += bg.x, sum[1] += bg.y, sum[2] += bg.z, sum[3] += 1.0f;
  }
  for (int c = 0; c < 4; ++c) out[c] = sum[c] * inv;
}

// How many of a frame's `spp` samples a brick's tile carries apart (dfb::Tile::samples), so the
// DFB composites them one by one as one renderer would: all of them up to dfb::kMaxTileSamples,
// beyond that the most that divide them into equal groups (each such sample the mean of a group).
std::uint32_t samplesApart(std::uint32_t spp) {
  std::uint32_t apart = std::min(spp, dfb::kMaxTileSamples);
  while (spp % apart != 0) --apart;
  return apart;
}

}  // namespace

struct BrickFrameDriver::Impl {
  std::shared_ptr<const SceneDesc> desc;
  RenderSettings settings;
  BrickDriverOptions options;
  int rank = 0, ranks = 1;
  base::ThreadLimit threads;
  BrickDirectory directory;  // every brick by id, and its holders
  // This rank's bricks: scene and renderer (without background) per held brick.
  std::vector<std::unique_ptr<SciVisScene>> scenes;        // by brick index; null: not held
  std::vector<std::unique_ptr<SciVisRenderer>> renderers;  // the same
  std::size_t bytes = 0;
  std::atomic<std::uint64_t> brickTiles{0};
  // Every brick's occlusion summary (exchanged when the cut is exact for the scene).
  bool occlusionExact = false;
  BrickOcclusion occlusion;
  std::atomic<std::uint64_t> raysSkipped{0};

  Impl(std::shared_ptr<const SceneDesc> d, const RenderSettings& s, BrickDriverOptions o, int r,
       int n)
      : desc(std::move(d)),
        settings(s),
        options(std::move(o)),
        rank(r),
        ranks(n),
        threads(options.threads) {}
};

std::vector<BuiltBrick> buildBricks(std::shared_ptr<const SceneDesc> desc,
                                    std::vector<HeldBrick> mine) {
  std::vector<BuiltBrick> built;
  for (HeldBrick& b : mine) {
    if (b.content.volumes.size() != sciVisDesc(*desc).volumes.size())
      throw base::Error("brick " + std::to_string(b.id) + " has " +
                        std::to_string(b.content.volumes.size()) + " volumes, the scene " +
                        std::to_string(sciVisDesc(*desc).volumes.size()));
    built.push_back({b.id, std::make_unique<SciVisScene>(desc, std::move(b.content))});
  }
  return built;
}

BrickFrameDriver::BrickFrameDriver(std::shared_ptr<const SceneDesc> desc,
                                   const RenderSettings& settings, BrickDriverOptions options,
                                   std::vector<HeldBrick> mine, MPI_Comm comm)
    : BrickFrameDriver(desc, settings, std::move(options), buildBricks(desc, std::move(mine)),
                       comm) {}

BrickFrameDriver::BrickFrameDriver(std::shared_ptr<const SceneDesc> desc,
                                   const RenderSettings& settings, BrickDriverOptions options,
                                   std::vector<BuiltBrick> mine, MPI_Comm comm)
    : impl_(std::make_unique<Impl>(std::move(desc), settings, std::move(options), 0, 1)) {
  Impl& m = *impl_;
  MPI_Comm_rank(comm, &m.rank);
  MPI_Comm_size(comm, &m.ranks);
  std::vector<BrickPlan> held;
  for (const BuiltBrick& b : mine) {
    for (const BrickPlan& p : held)
      if (p.id == b.id)
        throw base::Error("brick " + std::to_string(b.id) + " is added twice on render rank " +
                          std::to_string(m.rank));
    held.push_back({b.id, b.scene->bounds()});
  }
  m.directory = exchangeBricks(held, comm, m.options.timeout);
  // Every rank decides alike (the same description), so all join the exchange or none.
  m.occlusionExact = BrickOcclusion::exactFor(*m.desc);
  if (m.occlusionExact) {
    std::vector<std::pair<int, const BrickContent*>> contents;
    for (const BuiltBrick& b : mine) contents.emplace_back(b.id, &b.scene->content());
    m.occlusion =
        BrickOcclusion::exchange(*m.desc, m.directory.bricks, contents, comm, m.options.timeout);
  }
  m.scenes.resize(m.directory.bricks.size());
  m.renderers.resize(m.directory.bricks.size());
  for (BuiltBrick& b : mine) {
    const auto i =
        static_cast<std::size_t>(std::find_if(m.directory.bricks.begin(), m.directory.bricks.end(),
                                              [&](const BrickPlan& p) { return p.id == b.id; }) -
                                 m.directory.bricks.begin());
    m.scenes[i] = std::move(b.scene);
    m.bytes += m.scenes[i]->bytes();
    SciVisOptions brickOptions;
    brickOptions.background = false;
    brickOptions.firstHits = m.options.firstHits;
    m.renderers[i] = std::make_unique<SciVisRenderer>(*m.scenes[i], m.settings, brickOptions);
  }
}

BrickFrameDriver::~BrickFrameDriver() = default;

void BrickFrameDriver::configure(dfb::DfbOptions& options) const {
  configureBrickDfb(options, impl_->options.activeTiles);
}

void configureBrickDfb(dfb::DfbOptions& options, std::vector<bool> active) {
  options.operation = dfb::compositeAccumulateOperation();
  options.expectedInputs = [active = std::move(active)](int tile) {
    return active.empty() || (tile >= 0 && static_cast<std::size_t>(tile) < active.size() &&
                              active[static_cast<std::size_t>(tile)])
               ? 1
               : 0;
  };
}

const std::vector<BrickPlan>& BrickFrameDriver::bricks() const { return impl_->directory.bricks; }
const std::vector<int>& BrickFrameDriver::holders(int brick) const {
  return impl_->directory.holders.at(static_cast<std::size_t>(brick));
}
std::size_t BrickFrameDriver::sceneBytes() const { return impl_->bytes; }
SciVisScene::IsosurfaceStats BrickFrameDriver::isosurfaceStats() const {
  SciVisScene::IsosurfaceStats out;
  for (const auto& scene : impl_->scenes) {
    if (!scene) continue;
    const SciVisScene::IsosurfaceStats& s = scene->isosurfaceStats();
    out.cameraTriangles += s.cameraTriangles;
    out.shadingTriangles += s.shadingTriangles;
    out.seconds += s.seconds;
  }
  return out;
}
std::uint64_t BrickFrameDriver::brickTilesRendered() const { return impl_->brickTiles.load(); }
std::uint64_t BrickFrameDriver::raysSkipped() const { return impl_->raysSkipped.load(); }

std::vector<HeldBrick> BrickFrameDriver::releaseBricks() {
  Impl& m = *impl_;
  std::vector<HeldBrick> out;
  for (std::size_t b = 0; b < m.renderers.size(); ++b) {
    if (!m.renderers[b]) continue;
    out.push_back({m.directory.bricks[b].id, m.scenes[b]->release()});
  }
  m.renderers.clear();
  m.scenes.clear();
  m.bytes = 0;
  return out;
}

std::vector<int> BrickFrameDriver::heldBricks() const {
  std::vector<int> out;
  for (std::size_t b = 0; b < impl_->renderers.size(); ++b)
    if (impl_->renderers[b]) out.push_back(impl_->directory.bricks[b].id);
  return out;
}

int BrickFrameDriver::tileBrickOwner(int tile, int brick) const {
  const std::vector<int>& h = impl_->directory.holders[static_cast<std::size_t>(brick)];
  return h[static_cast<std::size_t>(tile + brick) % h.size()];
}

std::vector<int> BrickFrameDriver::candidateBricks(const CameraDesc& camera,
                                                   const dfb::Region& region) const {
  std::vector<int> out;
  const std::vector<BrickPlan>& plans = impl_->directory.bricks;
  for (std::size_t b = 0; b < plans.size(); ++b) {
    float x0, y0, x1, y1;
    // A pixel's samples jitter within it: widen the projection by a pixel. A room's screens are
    // not one pinhole image: every brick is a candidate, the tile's rays decide.
    if (impl_->settings.room ||
        !projectBox(camera, impl_->settings.width, impl_->settings.height, plans[b].bounds, x0, y0,
                    x1, y1) ||
        (x0 - 1 < static_cast<float>(region.x1) && x1 + 1 > static_cast<float>(region.x0) &&
         y0 - 1 < static_cast<float>(region.y1) && y1 + 1 > static_cast<float>(region.y0)))
      out.push_back(static_cast<int>(b));
  }
  return out;
}

void BrickFrameDriver::setSamplesPerPixel(std::uint32_t samples) {
  impl_->options.samplesPerPixel = samples;
}

void BrickFrameDriver::setLiveSettings(const LiveSettings& live) {
  for (auto& r : impl_->renderers)
    if (r) r->setLiveSettings(live);
}

std::vector<int> BrickFrameDriver::bricksOfTile(const CameraDesc& cameraDesc,
                                                const dfb::Region& region,
                                                std::uint32_t accumulationId) const {
  const Camera camera(cameraDesc, impl_->settings.width, impl_->settings.height,
                      impl_->settings.room);
  std::vector<int> out;
  for (int b : candidateBricks(cameraDesc, region))
    if (raysMeetBox(camera, impl_->settings.seed, region, accumulationId,
                    impl_->options.samplesPerPixel,
                    impl_->directory.bricks[static_cast<std::size_t>(b)].bounds))
      out.push_back(b);
  return out;
}

FrameReport BrickFrameDriver::renderFrame(dfb::DistributedFrameBuffer& dfb,
                                          const dfb::FrameInfo& frame,
                                          const CameraDesc& cameraDesc) {
  using base::Clock;
  const auto t0 = Clock::now();
  Impl& m = *impl_;
  const Camera camera(cameraDesc, m.settings.width, m.settings.height, m.settings.room);
  for (auto& r : m.renderers)
    if (r) r->beginFrame(frame, cameraDesc);

  dfb.begin(frame);
  const auto t1 = Clock::now();
  const std::uint32_t accumulationId = dfb.accumulationId();

  // The plan: what every rank would decide, worked out here only where it concerns this rank
  // (the tiles it owns, the tile-bricks it renders). Candidates come from the bricks' screen
  // projections, and each candidate is confirmed by the tile's own sample rays (raysMeetBox),
  // which every rank traces identically. A job is (tile, brick index), brick -1 the background.
  // A tile whose rays meet one brick only, which its owner renders, is one job that blends the
  // background in itself (withBackground): the root of a tree without children, no second tile
  // to fill, hand over and blend (most tiles on one rank). The same bits: it blends as the DFB's
  // blend of the two tiles would, and the blend of a lone root returns it as it is.
  struct Job {
    int tile, brick, children;
    bool withBackground = false;
  };
  const dfb::TileGrid& grid = dfb.grid();
  std::vector<std::vector<Job>> perTile(static_cast<std::size_t>(grid.tileCount()));
  base::parallelFor(perTile.size(), [&](std::size_t i) {
    const int t = static_cast<int>(i);
    if (!m.options.activeTiles.empty() && !m.options.activeTiles[i]) return;
    const bool owner = dfb.ownerOf(t) == dfb.rank();
    const dfb::Region region = grid.region(t);
    int children = 0;
    std::vector<Job>& mine = perTile[i];
    if (owner) mine.push_back({t, -1, 0});
    for (int b : candidateBricks(cameraDesc, region)) {
      const bool renders = tileBrickOwner(t, b) == dfb.rank();
      if (!owner && !renders) continue;
      if (!raysMeetBox(camera, m.settings.seed, region, accumulationId, m.options.samplesPerPixel,
                       m.directory.bricks[static_cast<std::size_t>(b)].bounds))
        continue;
      ++children;
      if (renders) mine.push_back({t, b, 0});
    }
    if (owner) mine.front().children = children;
    if (owner && children == 1 && mine.size() == 2) mine = {{t, mine.back().brick, 0, true}};
  });
  std::vector<Job> jobs;
  for (const auto& tileJobs : perTile) jobs.insert(jobs.end(), tileJobs.begin(), tileJobs.end());
  const std::uint32_t spp = m.options.samplesPerPixel;
  const float inv = 1.0f / static_cast<float>(spp);
  // Samples carried apart, each the mean of a group of `group` consecutive ones.
  const std::uint32_t apart = samplesApart(spp), group = spp / apart;
  const float invGroup = 1.0f / static_cast<float>(group);
  const Environment& background = m.desc->environment;
  // Camera rays 16 at a time in AVX-512 where the march runs it, as SciVisRenderer::render.
  const bool simdRows =
      resolveMarchKernel(MarchKernel::Auto) == MarchKernel::Avx512 && cameraRowSimdAvailable();
  base::parallelFor(jobs.size(), [&](std::size_t i) {
    enableFlushToZero();
    const Job& job = jobs[i];
    const dfb::Region region = grid.region(job.tile);
    dfb::Tile tile;
    prepareTile(region, accumulationId, 0, spp, tile);
    const std::size_t pixels = static_cast<std::size_t>(region.pixelCount());
    tile.depth.assign(pixels, kInf);
    tile.generation = job.brick < 0 || job.withBackground ? 0 : 1;
    tile.children = job.children;
    const BrickPlan* plan =
        job.brick < 0 ? nullptr : &m.directory.bricks[static_cast<std::size_t>(job.brick)];
    // Fragments of one depth composite by brick id: the same order whoever rendered them.
    tile.sequence = plan && !job.withBackground ? static_cast<std::uint32_t>(plan->id) : 0;
    const SciVisRenderer* renderer =
        job.brick < 0 ? nullptr : m.renderers[static_cast<std::size_t>(job.brick)].get();
    const Box3 bounds = plan ? plan->bounds : Box3{};
    // The bricks that may hide this one's rays (BrickOcclusion.h): with one sample a frame every
    // fragment is sorted by its own ray's entry into its brick, so a ray is hidden when it
    // enters another brick first (ties: the lower id, as the compositor sorts) and certainly
    // crosses an opaque isosurface there. That brick renders this tile too (its box meets the
    // ray), its fragment has alpha exactly 1, and this one's would be multiplied by 0.
    thread_local std::vector<int> occluders;
    occluders.clear();
    if (renderer && m.occlusionExact && m.options.occlusionCut && spp == 1)
      for (int other : candidateBricks(cameraDesc, region))
        if (other != job.brick &&
            mayComeFirst(m.directory.bricks[static_cast<std::size_t>(other)].bounds, bounds,
                         cameraDesc.position))
          occluders.push_back(other);
    std::uint64_t skipped = 0;
    // A constant background is the same in every pixel: worked out once, no rays needed.
    const bool constantBackground = background.kind == Environment::Kind::Constant;
    float constantPixel[4] = {0, 0, 0, 0};
    if (constantBackground) backgroundPixel(background, nullptr, spp, inv, constantPixel);
    if (!renderer && constantBackground) {
      for (std::size_t p = 0; p < static_cast<std::size_t>(region.pixelCount()); ++p)
        std::copy(constantPixel, constantPixel + 4, &tile.color[4 * p]);
      dfb.setTile(std::move(tile));
      return;
    }
    // The brick's pieces of the tile's rays, rows at a time, integrated together
    // (SciVisRenderer batches the rays of its SIMD march) in 4x4 pixel blocks (RayBlocks.h: the
    // Embree packets of the rays' first hits are compact squares); a ray that misses the brick
    // adds nothing.
    thread_local std::vector<SciVisRenderer::RayPiece> rays, pieces;
    thread_local std::vector<Fragment> fragments;
    thread_local std::vector<std::uint8_t> hits;
    thread_local std::vector<std::uint32_t> slots;  // slots: each sample's piece
    thread_local RayBlockOrderCache blockOrder;
    thread_local std::vector<float> depths;  // per pixel: brickDepth() of its first sample's ray
    thread_local std::vector<std::uint8_t> inside;
    thread_local std::vector<SciVisRenderer::FirstSurface> firsts, pieceFirsts;
    // The background tile's pixel whose rays start at rays[first]; with samples apart, the
    // sample whose group's rays start there.
    const auto backgroundAt = [&](std::size_t first, float out[4]) {
      if (constantBackground)
        std::copy(constantPixel, constantPixel + 4, out);
      else if (apart == 1)
        backgroundPixel(background, rays.data() + first, spp, inv, out);
      else
        backgroundPixel(background, rays.data() + first, group, invGroup, out);
    };
    // A pixel's samples apart: the tile holds `apart` blocks of its pixels (a constant
    // background's tile stands for every sample; a lone root is blended here, one block).
    if (apart > 1 && !job.withBackground && (renderer || !constantBackground)) {
      tile.samples = apart;
      tile.color.assign(4 * pixels * apart, 0.0f);
      tile.depth.assign(pixels * apart, kInf);
    }
    // Pixel p with samples apart, its rays from rays[first], its samples' depths from
    // depths[apart * rowPixel]: each sample the mean of its group's fragments, written to its
    // block, or for a lone root blended with its background and averaged as the DFB would.
    const auto pixelApart = [&](std::size_t first, std::size_t p, std::size_t rowPixel) {
      float composites[4 * dfb::kMaxTileSamples];
      float front = kInf;
      for (std::uint32_t s = 0; s < apart; ++s) {
        const std::size_t from = first + std::size_t{s} * group, block = std::size_t{s} * pixels;
        float* out = job.withBackground ? &composites[4 * s] : &tile.color[4 * (block + p)];
        if (!renderer) {
          backgroundAt(from, out);
          continue;
        }
        float sum[4] = {0, 0, 0, 0};
        for (std::size_t r = from; r < from + group; ++r) {
          if (!hits[r]) continue;
          const Fragment& f = fragments[slots[r]];
          for (int c = 0; c < 4; ++c) sum[c] += f.rgba[c];
        }
        for (int c = 0; c < 4; ++c) out[c] = sum[c] * invGroup;
        const float depth = depths[apart * rowPixel + s];
        if (!job.withBackground) {
          tile.depth[block + p] = depth;
          continue;
        }
        float bg[4];
        backgroundAt(from, bg);
        const float d = dfb::blendPixelPair(bg, kInf, out, depth, out);
        if (s == 0) front = d;
      }
      if (job.withBackground) {
        dfb::meanOfComposites(composites, apart, &tile.color[4 * p]);
        tile.depth[p] = front;
      }
    };
    const RowRays row{&camera, bounds, m.settings.seed, accumulationId, 0, spp, simdRows};
    // Where the raster accepts the brick's first hits: its bounds, but not at the faces it shares
    // with the domain's boundary. The unbricked scene clips no ray there, and a surface that
    // meets the boundary is hit within rounding of where the ray enters (or leaves) the domain:
    // a brick must take that hit as the whole scene does. Between bricks the split stays exact.
    const Box3 accept =
        renderer
            ? openAtDomainBoundary(bounds, m.scenes[static_cast<std::size_t>(job.brick)]->domain())
            : bounds;
    const int rows =
        std::max(1, static_cast<int>(SciVisRenderer::kBatch /
                                     std::max<std::size_t>(1, std::size_t{spp} * region.width())));
    for (int y0 = region.y0; y0 < region.y1; y0 += rows) {
      const int y1 = std::min(region.y1, y0 + rows);
      hits.clear(), depths.clear();
      // The camera rays of SciVisRenderer::render, sample for sample, clipped to the brick
      // (CameraRays.h: 16 pixels at a time in AVX-512 where the march runs it, the same bits).
      const std::size_t rowRays = std::size_t{spp} * static_cast<std::size_t>(region.width());
      const std::size_t n = static_cast<std::size_t>(y1 - y0) * rowRays;
      rays.resize(n), inside.resize(n);
      for (int y = y0; y < y1; ++y) {
        const std::size_t first = static_cast<std::size_t>(y - y0) * rowRays;
        cameraRowRays(row, region.x0, region.x1, y, rays.data() + first, inside.data() + first);
      }
      for (std::size_t r = 0; r < n; ++r) {
        const SciVisRenderer::RayPiece& ray = rays[r];
        bool hit = renderer && inside[r], skippedRay = false;
        if (hit && !occluders.empty()) {
          const Vec3 invDir = reciprocal(ray.dir);
          for (std::size_t k = 0; hit && k < occluders.size(); ++k) {
            const BrickPlan& front = m.directory.bricks[static_cast<std::size_t>(occluders[k])];
            if (m.occlusion.hides(occluders[k], ray.origin, ray.dir, invDir, ray.t0,
                                  front.id < plan->id))
              hit = false, skippedRay = true, ++skipped;
          }
        }
        hits.push_back(hit ? 1 : 0);
        // Sorted by the first sample's ray: with one sample a frame (the usual progressive
        // case) every sample's fragments then composite in exactly its own ray's order,
        // also in pixels that see a brick border edge-on. (Where the ray enters the brick
        // is t0, brickDepth()'s own clip; a hidden ray keeps it.)
        if (renderer && r % group == 0)  // with samples apart, each one's first ray
          depths.push_back(hit || skippedRay ? ray.t0 : brickDepth(bounds, ray.origin, ray.dir));
        // The piece goes on past the faces the brick shares with the domain's boundary, as the
        // unbricked scene's ray does (it clips none there: a sample exactly on the boundary is
        // in it, where a piece ending there stopped short of it); only seams cut rays.
        if (hit && renderer) {
          float a = 0, b = kInf;
          for (int axis = 0; axis < 3; ++axis)
            if (accept.lo[axis] > -kInf || accept.hi[axis] < kInf)
              clipToSlab(accept.lo[axis], accept.hi[axis], ray.origin[axis], 1.0f / ray.dir[axis],
                         a, b);
          rays[r].t0 = a, rays[r].t1 = b;
        }
      }
      if (renderer && renderer->firstHitsRasterised(spp)) {
        // First hits from this frame's raster of the brick's triangles (FirstHitRaster.h), then
        // the rays that meet the brick in row order; slots[r]: ray r's piece among them.
        firsts.resize(n);
        renderer->rasterFirstHits(region.x0, region.x1, y0, y1, rays.data(), hits.data(),
                                  firsts.data(), &accept);
        pieces.clear(), pieceFirsts.clear(), slots.resize(n);
        for (std::size_t r = 0; r < n; ++r)
          if (hits[r]) {
            slots[r] = static_cast<std::uint32_t>(pieces.size());
            pieces.push_back(rays[r]), pieceFirsts.push_back(firsts[r]);
          }
        fragments.resize(pieces.size());
        renderer->integrate(pieces.data(), pieces.size(), fragments.data(), pieceFirsts.data());
      } else if (renderer) {
        // The rays that meet the brick, in block order; slots[r]: ray r's piece among them.
        const std::vector<std::uint32_t>& order = blockOrder.of(region.width(), y1 - y0, spp);
        pieces.clear(), slots.resize(n);
        for (const std::uint32_t r : order)
          if (hits[r])
            slots[r] = static_cast<std::uint32_t>(pieces.size()), pieces.push_back(rays[r]);
        fragments.resize(pieces.size());
        renderer->integrate(pieces.data(), pieces.size(), fragments.data());
      }
      std::size_t sample = 0;
      for (int y = y0; y < y1; ++y)
        for (int x = region.x0; x < region.x1; ++x) {
          const std::size_t first = sample;
          sample += spp;
          const std::size_t p = static_cast<std::size_t>(y - region.y0) * region.width() +
                                static_cast<std::size_t>(x - region.x0);
          float* out = &tile.color[4 * p];
          if (apart > 1) {
            pixelApart(first, p,
                       static_cast<std::size_t>(y - y0) * region.width() +
                           static_cast<std::size_t>(x - region.x0));
            continue;
          }
          if (!renderer) {
            backgroundAt(first, out);
            continue;
          }
          float sum[4] = {0, 0, 0, 0};
          for (std::size_t r = first; r < sample; ++r) {
            if (!hits[r]) continue;
            const Fragment& f = fragments[slots[r]];
            for (int c = 0; c < 4; ++c) sum[c] += f.rgba[c];
          }
          for (int c = 0; c < 4; ++c) out[c] = sum[c] * inv;
          float& depth = tile.depth[p];
          depth = depths[static_cast<std::size_t>(y - y0) * region.width() +
                         static_cast<std::size_t>(x - region.x0)];
          if (job.withBackground) {
            // The background tile's pixel (depth infinite, first in the tree) and this one, as
            // the DFB would blend the two.
            float bg[4];
            backgroundAt(first, bg);
            depth = dfb::blendPixelPair(bg, kInf, out, depth, out);
          }
        }
    }
    if (renderer) m.brickTiles.fetch_add(1, std::memory_order_relaxed);
    if (skipped > 0) m.raysSkipped.fetch_add(skipped, std::memory_order_relaxed);
    dfb.setTile(std::move(tile));
  });
  const auto t3 = Clock::now();
  dfb.end();
  FrameReport report;
  report.tilesRendered = static_cast<int>(jobs.size());
  for (const Job& j : jobs)
    if (j.brick >= 0) report.samples += std::uint64_t{spp} * grid.region(j.tile).pixelCount();
  // Planning (the tiles' ray tests) included: it is this rank's work before its last tile.
  report.renderMs = base::msBetween(t1, t3);
  report.frameMs = base::msBetween(t0, Clock::now());
  return report;
}

}  // namespace renderers::scivis
