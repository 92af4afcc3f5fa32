#pragma once
// A whole canvas rendered tile by tile, as the frame driver does, but on this process alone and
// without the DFB: for benchmarks and offline images of one renderer.
#include <cstdint>
#include <vector>

#include "renderers/Renderer.h"

namespace renderers {

// RGBA floats, row-major from the top row, width x height; tiles of tileSize rendered in parallel
// on `threads` threads (0: all), `spp` samples per pixel from `firstSample` of accumulation
// `accumulationId`.
std::vector<float> renderCanvas(const Renderer& renderer, int width, int height, int tileSize,
                                int threads, std::uint32_t spp, std::uint32_t accumulationId = 0,
                                std::uint32_t firstSample = 0);
// The same into `image` (resized to fit), for frame loops: a buffer kept from frame to frame is
// not faulted in (and zeroed by the kernel) again each frame on one thread while the others
// wait, which cost the scivis bench 5-10% of its frame time at 1024^2.
void renderCanvas(const Renderer& renderer, int width, int height, int tileSize, int threads,
                  std::uint32_t spp, std::vector<float>& image, std::uint32_t accumulationId = 0,
                  std::uint32_t firstSample = 0);

}  // namespace renderers
