#pragma once
// The one interface the frame driver renders tiles through.
//
// Contracts: render() is const and thread-safe (tiles render concurrently from TBB workers);
// a pixel's value depends only on its canvas coordinates, the accumulation id, the sample
// indices, the seed and the frame and camera given to beginFrame(), never on the tile it is
// rendered in, the thread or the rank. beginFrame() is called from one thread, between frames.
//
// The camera comes with the frame (render rank 0 decides it and broadcasts it with the frame
// order), so no rank can render a frame with another rank's camera, whatever moves it: an
// orbit, a camera path, an operator steering the wall.
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
  // When set, a renderer that can produce display pixels directly (the pattern) fills
  // Tile::rgba8, tone-mapped with these settings exactly as the DFB would, and no color: no
  // float pixels, no tone mapping. Only for the DFB's write operation, and not for linear
  // output (RGBAF32).
  std::optional<dfb::ToneMapSettings> displayPixels = std::nullopt;
  // Screens placed in a room (RoomView.h): each pixel's ray from its screen's frustum, pixels
  // no screen shows not traced. Null: one pinhole image over the canvas.
  std::shared_ptr<const RoomView> room = nullptr;
};

// Settings an operator may change while the wall runs (steering). Set between frames,
// the same on every rank (they come with the frame order); a renderer ignores what it lacks.
struct LiveSettings {
  int maxDepth = 8;           // the path tracer's path length
  int transferFunction = -1;  // scivis: preset index in transferFunctionPresetNames(); -1: own
  float opacityScale = 1.0f;  // scivis: every volume's opacity times this
};

class Renderer {
 public:
  virtual ~Renderer() = default;
  // `camera` is the frame's camera (the pattern ignores it).
  virtual void beginFrame(const dfb::FrameInfo& /*frame*/, const CameraDesc& /*camera*/) {}
  // Between frames, from one thread.
  virtual void setLiveSettings(const LiveSettings& /*settings*/) {}
  // Fills `out` for `region`: color is the MEAN RGBA over samples firstSample ..
  // firstSample + samples - 1 (alpha 1), weight = samples, sequence = firstSample,
  // accumulationId = accumulationId.
  virtual void render(const dfb::Region& region, std::uint32_t accumulationId,
                      std::uint32_t firstSample, std::uint32_t samples, dfb::Tile& out) const = 0;
};

// "pathtracer", "primary" or "pattern"; `scene` must outlive the renderer (unused by
// "pattern"). Throws base::Error naming the choices for an unknown name.
std::unique_ptr<Renderer> makeRenderer(const std::string& name, const Scene& scene,
                                       const RenderSettings& settings);

// Sizes out.color for `region` and fills the bookkeeping fields render() promises.
void prepareTile(const dfb::Region& region, std::uint32_t accumulationId, std::uint32_t firstSample,
                 std::uint32_t samples, dfb::Tile& out);
// Flush denormals to zero in the calling thread (Embree's advice; cheap to repeat).
void enableFlushToZero();

}  // namespace renderers
