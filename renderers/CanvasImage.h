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

}  // namespace renderers
