#pragma once
// IceT (Kitware's Image Composition Engine for Tiles) set up the way ParaView drives it for
// pre-rendered images: icetCompositeImage on each rank's full-frame buffers, either ordered
// "over" blending of premultiplied float RGBA (transparent data; the order is the bricks'
// visibility order) or z-buffer compositing of RGBA8 + float depth (opaque data), onto one tile
// shown by rank 0 or a grid of tiles each shown by one rank.
#include <IceT.h>
#include <mpi.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace icetbench {

struct IcetSetup {
  bool blend = true;                            // false: z-buffer (colour RGBA8 + depth)
  int width = 0, height = 0;                    // the canvas
  int tilesX = 1, tilesY = 1;                   // tile (tx, ty) is shown by rank ty * tilesX + tx
  std::array<float, 4> background{0, 0, 0, 1};  // blended under (blend) or filling empty pixels
};

// IceT's own account of the last composite, from its timing state (this rank).
struct IcetTimes {
  double compositeMs = 0, blendMs = 0, compressMs = 0, collectMs = 0;
  double bytesSent = 0;
};

class IcetCompositor {
 public:
  IcetCompositor(MPI_Comm comm, const IcetSetup& setup);
  ~IcetCompositor();
  IcetCompositor(const IcetCompositor&) = delete;
  IcetCompositor& operator=(const IcetCompositor&) = delete;

  // strategy: "reduce" (IceT's default REDUCE with its automatic single-image strategy,
  // radix-kr) or "radixk" (REDUCE with radix-k).
  void setStrategy(const std::string& strategy);
  // Collective. color: float RGBA (blend) or RGBA8 (z-buffer); depth: z-buffer only.
  // viewport: x, y, width, height of the valid pixels. order: ranks front to back (blend).
  // Returns on every rank; the finished tile is then in tileRgba()/tileRgba8() on its display.
  void composite(const void* color, const float* depth, const std::array<int, 4>& viewport,
                 const std::vector<int>& order);

  // This rank's tile (-1: it shows none), its rectangle on the canvas, and its pixels.
  int displayedTile() const { return tile_; }
  std::array<int, 4> tileRect() const;
  std::vector<float> tileRgba() const;           // blend mode
  std::vector<std::uint32_t> tileRgba8() const;  // z-buffer mode
  IcetTimes times() const;

 private:
  IcetSetup setup_;
  int tile_ = -1;
  IceTCommunicator communicator_ = nullptr;
  IceTContext context_ = nullptr;
  IceTImage image_{};  // the last composite's result; valid until the next one
};

}  // namespace icetbench
