#pragma once
// Which rank renders which tiles with which samples: a pure function, the same on every rank,
// testable without MPI.
//
//  - Static: contiguous blocks of tile indices, one block per rank.
//  - RoundRobin (default): tile i on rank i % ranks, which is the DFB's default owner, so every
//    tile is processed where it is rendered.
//  - Dynamic (paper 4.1.1): round robin, plus extra inputs for the tiles whose error was highest
//    in the previous frame. Each extra input renders `samplesPerPixel` further samples with
//    distinct sample indices on the least-loaded rank that does not have the tile yet; the DFB's
//    accumulate operation averages the inputs weighted by samples, in `sequence` order.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace renderers {

enum class Distribution { Static, RoundRobin, Dynamic };

// "static", "roundrobin" or "dynamic"; throws base::Error naming the choices otherwise.
Distribution distributionFromName(const std::string& name);

struct Assignment {
  int tile = 0;
  std::uint32_t firstSample = 0;
  std::uint32_t samples = 0;
  bool operator==(const Assignment&) const = default;
};

struct WorkPlan {
  std::vector<std::vector<Assignment>> perRank;  // in rendering order
  std::vector<int> inputsPerTile;                // what DfbOptions::expectedInputs answers
};

struct DynamicOptions {
  float fraction = 0.25f;  // at most this share of tiles gets extra inputs
  int maxInputs = 4;       // per tile, never more than the rank count
};

// `tileErrors` may be empty (first frame): Dynamic then equals RoundRobin.
WorkPlan planWork(int tileCount, int ranks, std::uint32_t samplesPerPixel,
                  std::span<const float> tileErrors, Distribution distribution,
                  const DynamicOptions& dynamic = {});

}  // namespace renderers
