#pragma once
// Particle sets that are not typed into a scene file: a clustered cloud made from a seed, and
// binary files of float32 records.
#include <cstdint>
#include <string>

#include "renderers/scivis/io/SciVisDesc.h"

namespace renderers::scivis {

// `count` particles clustered the way matter is in a cosmology run: a hierarchy of clumps
// (Soneira & Peebles 1978: each level places a few sub-clumps inside a sphere a fixed fraction of
// its parent's size) over a sparse uniform background, inside the cube of side `size` about
// `center`. The attribute is the local density proxy (the clump level, jittered) in [0, 1].
// A pure function of its arguments: every rank that asks makes the same particles.
ParticlesDesc clusteredParticles(std::size_t count, std::uint64_t seed, Vec3 center, float size,
                                 float radius);

// Records of float32 values in the order `layout` names: 'x' 'y' 'z' (required), 'r' (radius),
// 'a' (attribute), each once, e.g. "xyz", "xyzr", "xyzra". Throws base::Error naming the
// file when it cannot be read or its size is not a whole number of records.
void readParticleFile(const std::string& path, const std::string& layout, ParticlesDesc& out);

}  // namespace renderers::scivis
