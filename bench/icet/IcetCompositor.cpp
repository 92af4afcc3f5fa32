#include "bench/icet/IcetCompositor.h"

#include <IceTMPI.h>

#include <cstring>
#include <stdexcept>

namespace icetbench {
namespace {

void check(const char* what) {
  const IceTEnum error = icetGetError();
  if (error != ICET_NO_ERROR)
    throw std::runtime_error(std::string("IceT error in ") + what + " (code 0x" +
                             std::to_string(static_cast<unsigned>(error)) + ")");
}

}  // namespace

IcetCompositor::IcetCompositor(MPI_Comm comm, const IcetSetup& setup) : setup_(setup) {
  communicator_ = icetCreateMPICommunicator(comm);
  context_ = icetCreateContext(communicator_);
  icetDiagnostics(ICET_DIAG_ERRORS | ICET_DIAG_ALL_NODES);
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  icetResetTiles();
  const int w = setup.width / setup.tilesX, h = setup.height / setup.tilesY;
  for (int ty = 0; ty < setup.tilesY; ++ty)
    for (int tx = 0; tx < setup.tilesX; ++tx) {
      const int display = ty * setup.tilesX + tx;
      // The last column and row take what the division leaves.
      const int tw = tx + 1 == setup.tilesX ? setup.width - tx * w : w;
      const int th = ty + 1 == setup.tilesY ? setup.height - ty * h : h;
      icetAddTile(tx * w, ty * h, tw, th, display);
      if (display == rank) tile_ = display;
    }
  if (setup.blend) {
    icetSetColorFormat(ICET_IMAGE_COLOR_RGBA_FLOAT);
    icetSetDepthFormat(ICET_IMAGE_DEPTH_NONE);
    icetCompositeMode(ICET_COMPOSITE_MODE_BLEND);
    icetEnable(ICET_ORDERED_COMPOSITE);
    // The bricks' images have alpha 0 where empty: blend the background under the result once.
    icetEnable(ICET_CORRECT_COLORED_BACKGROUND);
  } else {
    icetSetColorFormat(ICET_IMAGE_COLOR_RGBA_UBYTE);
    icetSetDepthFormat(ICET_IMAGE_DEPTH_FLOAT);
    icetCompositeMode(ICET_COMPOSITE_MODE_Z_BUFFER);
  }
  setStrategy("reduce");
  check("set-up");
}

IcetCompositor::~IcetCompositor() {
  icetDestroyContext(context_);
  icetDestroyMPICommunicator(communicator_);
}

void IcetCompositor::setStrategy(const std::string& strategy) {
  icetStrategy(ICET_STRATEGY_REDUCE);
  if (strategy == "reduce")
    icetSingleImageStrategy(ICET_SINGLE_IMAGE_STRATEGY_AUTOMATIC);
  else if (strategy == "radixk")
    icetSingleImageStrategy(ICET_SINGLE_IMAGE_STRATEGY_RADIXK);
  else
    throw std::runtime_error("unknown IceT strategy '" + strategy + "' (reduce or radixk)");
}

void IcetCompositor::composite(const void* color, const float* depth,
                               const std::array<int, 4>& viewport, const std::vector<int>& order) {
  if (setup_.blend) icetCompositeOrder(order.data());
  // No projection: IceT learns from the valid viewport alone which tiles this rank touches.
  image_ = icetCompositeImage(color, setup_.blend ? nullptr : depth, viewport.data(), nullptr,
                              nullptr, setup_.background.data());
  check("icetCompositeImage");
}

std::array<int, 4> IcetCompositor::tileRect() const {
  if (tile_ < 0) return {0, 0, 0, 0};
  const int w = setup_.width / setup_.tilesX, h = setup_.height / setup_.tilesY;
  const int tx = tile_ % setup_.tilesX, ty = tile_ / setup_.tilesX;
  return {tx * w, ty * h, tx + 1 == setup_.tilesX ? setup_.width - tx * w : w,
          ty + 1 == setup_.tilesY ? setup_.height - ty * h : h};
}

std::vector<float> IcetCompositor::tileRgba() const {
  if (tile_ < 0 || icetImageIsNull(image_)) return {};
  const IceTSizeType n = icetImageGetNumPixels(image_);
  const IceTFloat* c = icetImageGetColorcf(image_);
  return std::vector<float>(c, c + 4 * n);
}

std::vector<std::uint32_t> IcetCompositor::tileRgba8() const {
  if (tile_ < 0 || icetImageIsNull(image_)) return {};
  const IceTSizeType n = icetImageGetNumPixels(image_);
  std::vector<std::uint32_t> out(static_cast<std::size_t>(n));
  std::memcpy(out.data(), icetImageGetColorcub(image_), out.size() * 4);
  return out;
}

IcetTimes IcetCompositor::times() const {
  IcetTimes t;
  IceTDouble v = 0;
  icetGetDoublev(ICET_COMPOSITE_TIME, &v), t.compositeMs = 1e3 * v;
  icetGetDoublev(ICET_BLEND_TIME, &v), t.blendMs = 1e3 * v;
  icetGetDoublev(ICET_COMPRESS_TIME, &v), t.compressMs = 1e3 * v;
  icetGetDoublev(ICET_COLLECT_TIME, &v), t.collectMs = 1e3 * v;
  icetGetDoublev(ICET_BYTES_SENT, &v), t.bytesSent = v;
  return t;
}

}  // namespace icetbench
