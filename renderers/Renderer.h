#pragma once
// The one interface the frame driver renders tiles through.
//
// Contracts: render() is const and thread-safe (tiles render concurrently from TBB workers);
// a pixel's value depends only on its canvas coordinates, the accumulation id, the sample
// indices, the seed and the frame given to beginFrame(), never on the tile it is rendered in,
// the thread or the rank. beginFrame() is called from one thread, between frames.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "dfb/PixelOp.h"
#include "dfb/Tile.h"
#include "dfb/TileOperation.h"
#include "renderers/Camera.h"

namespace renderers {

class Scene;

struct RenderSettings {
  int width = 0, height = 0;  // the whole canvas, in pixels
  std::uint64_t seed = 0;
  int maxDepth = 8;  // path segments (camera ray included), as Embree's --max-path-length
  // Camera orbit: frame F sees the scene's camera turned about its look-at point around its up
  // axis by orbitDegreesPerFrame * (F - 1). 0: a fixed camera.
  float orbitDegreesPerFrame = 0.0f;
  // When set, a renderer that can produce display pixels directly (the pattern) fills
  // Tile::rgba8, tone-mapped with these settings exactly as the DFB would, and no color: no
  // float pixels, no tone mapping. Only for the DFB's write operation, and not for linear
  // output (RGBAF32).
  std::optional<dfb::ToneMapSettings> displayPixels = std::nullopt;
};

// The camera of frame `frameId` under the orbit in `settings`.
CameraDesc frameCamera(const CameraDesc& base, const RenderSettings& settings,
                       std::uint32_t frameId);

class Renderer {
 public:
  virtual ~Renderer() = default;
  virtual void beginFrame(const dfb::FrameInfo& /*frame*/) {}
  // Fills `out` for `region`: color is the MEAN RGBA over samples firstSample ..
  // firstSample + samples - 1 (alpha 1), weight = samples, sequence = firstSample,
  // accumulationId = accumulationId.
  virtual void render(const dfb::Region& region, std::uint32_t accumulationId,
                      std::uint32_t firstSample, std::uint32_t samples, dfb::Tile& out) const = 0;
};

// "pathtracer", "primary" or "pattern"; `scene` must outlive the renderer (unused by
// "pattern"). Throws renderers::Error naming the choices for an unknown name.
std::unique_ptr<Renderer> makeRenderer(const std::string& name, const Scene& scene,
                                       const RenderSettings& settings);

// Sizes out.color for `region` and fills the bookkeeping fields render() promises.
void prepareTile(const dfb::Region& region, std::uint32_t accumulationId, std::uint32_t firstSample,
                 std::uint32_t samples, dfb::Tile& out);
// Flush denormals to zero in the calling thread (Embree's advice; cheap to repeat).
void enableFlushToZero();

}  // namespace renderers
