#pragma once
// Tone mapping of a run of pixels, linear float RGBA to display RGBA8: the per-pixel work of
// every float tile on its owner. Two kernels compute the same bits: a scalar one (the
// definition, also toneMapPixel's) and an AVX2 one that maps two pixels per 256-bit vector and
// looks the sRGB steps up with gathers; toneMapPixels picks AVX2 where the CPU has it.
// tests/dfb/ToneMapKernelTest.cpp checks them equal on random and special inputs.
#include <cstddef>
#include <cstdint>

#include "dfb/PixelOp.h"

namespace dfb {

// `pixels` pixels of 4 floats at `rgba` to `out` (R in the low byte): the fastest kernel here.
void toneMapPixels(const float* rgba, std::size_t pixels, std::uint32_t* out,
                   const ToneMapSettings& settings);

// The kernels themselves, for the tests and benchmarks.
void toneMapPixelsScalar(const float* rgba, std::size_t pixels, std::uint32_t* out,
                         const ToneMapSettings& settings);
bool toneMapAvx2Available();  // the CPU runs AVX2 (and the build has the kernel)
// Only where toneMapAvx2Available().
void toneMapPixelsAvx2(const float* rgba, std::size_t pixels, std::uint32_t* out,
                       const ToneMapSettings& settings);

}  // namespace dfb
