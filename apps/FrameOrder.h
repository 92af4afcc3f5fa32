#pragma once
// What render rank 0 broadcasts to the render ranks before each frame: the frame, its camera and
// settings, and whether the run stops or idles. Everything a rank needs to render the frame is
// in here, so every rank renders it the same (docs/design.md, "Steering").
#include <cstdint>
#include <type_traits>

#include "dfb/TileOperation.h"
#include "renderers/Camera.h"

namespace app {

// The camera and the settings a frame is rendered with. A change of any of them starts a new
// accumulation epoch.
struct FrameView {
  renderers::CameraDesc camera;
  float exposure = 1;
  std::int32_t spp = 1;                // samples per pixel per frame
  std::int32_t maxDepth = 8;           // path tracer
  std::int32_t transferFunction = -1;  // scivis: preset index; -1: the scene's own
  float opacityScale = 1;              // scivis
  // scivis: the time step of the scene's series shown (0 without one); a new step starts a new
  // epoch like any change of view.
  std::uint32_t timeStep = 0;

  bool sameAs(const FrameView& o) const;
};

struct FrameOrder {
  dfb::FrameInfo frame;
  FrameView view;
  std::int32_t stop = 0;      // 1: no more frames (a graceful stop)
  std::int32_t exitCode = 0;  // of the stop
  // 1: no frame now; the camera is still and the sample budget reached (--max-spp). The ranks
  // wait for the next order without rendering (rank 0 sends one at least every heartbeat).
  std::int32_t idle = 0;
  // --connect: the version of the wall's roster this frame routes with
  // (wall/service/protocol/Protocol.h, Roster); a rank whose version differs takes the roster from
  // rank 0 before the frame.
  std::uint32_t rosterVersion = 0;
  // --connect: the version of the move of the job's window this frame renders with
  // (Protocol.h, Reshape); a rank whose version differs re-plans for the new window first.
  std::uint32_t reshapeVersion = 0;
  std::uint64_t captureSequence = 0;  // > 0: the walls capture this frame
  // The last steering request this frame applies (0: none), when the first of them arrived
  // (steady_clock ns on rank 0), and the last frame every display had presented then.
  std::uint64_t requestId = 0;
  std::int64_t requestNs = 0;
  std::int64_t presentedAtRequest = 0;
};
static_assert(std::is_trivially_copyable_v<FrameOrder>);

}  // namespace app
